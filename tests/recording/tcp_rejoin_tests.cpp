// teejet-record over the project's TCP profiles (the gateway on 127.0.0.1), inside a private
// network namespace. Fast DDS 2.9.1's TCP transport leaves about one participant in twenty that
// starts beside a starting gateway without meeting anyone, for good; the recorder then joins
// again with a new participant, as valvectl does (docs/remote-benches.md). Which start stalls
// cannot be chosen, so the gateway is held back until the recorder has joined again, and the
// recording must then hold the gateway's data, received through the new participant.

#include <gtest/gtest.h>

#include <csignal>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "support/eventually.hpp"
#include "support/scratch_dir.hpp"
#include "support/subprocess.hpp"
#include "support/tcp_profiles.hpp"
#include "support/test_domain.hpp"
#include "support/text.hpp"

namespace teejet::testing {
namespace {

using namespace std::chrono_literals;

TEST(RecorderOverTcp, ARecorderThatMetNoGatewayJoinsAgainAndRecordsTheGatewayThatCameLater) {
  ScratchDir scratch;
  const std::string bench = (scratch / "bench.xml").string();
  write_local_tcp_bench_profile(CONFIG_DIR, bench);
  const std::string domain = std::to_string(test_domain());
  const std::string output = (scratch / "tcp.mcap").string();
  Subprocess recorder(
      {TEEJET_RECORD_PATH, "-o", output, "--domain", domain, "--profile", bench, "--progress"});
  ASSERT_TRUE(recorder.wait_for_stderr(
      "teejet-record: met no gateway over TCP; joined DDS domain " + domain + " again (1 time(s))",
      30s))
      << recorder.err();
  Subprocess gateway({TEEJET_GATEWAY_PATH, "--can", "sim:4", "--domain", domain, "--profile",
                      tcp_gateway_profile(CONFIG_DIR), "--log-level", "warn"});
  // What the recorder has written so far (--info reads a file being written up to its last
  // flushed chunk, once a second): every valve's presence (durable, so a late joiner gets them)
  // and positions, all received through the participant made when it joined again.
  const auto counts = [&] {
    std::map<std::string, std::uint64_t> messages;
    const Finished info = run({TEEJET_RECORD_PATH, "--info", output, "--json"}, 60s);
    if (info.exit_code != 0) return messages;
    const auto described = nlohmann::json::parse(info.out);  // outlives the loop over it
    for (const auto& channel : described["channels"]) {
      messages[channel["topic"]] = channel["messages"];
    }
    return messages;
  };
  EXPECT_TRUE(eventually(
      [&] {
        auto messages = counts();
        return messages["teejet/valve/presence"] >= 4 && messages["teejet/valve/position"] >= 1;
      },
      60s))
      << describe(run({TEEJET_RECORD_PATH, "--info", output}, 60s));
  recorder.signal(SIGINT);
  const Finished finished = recorder.wait(60s);
  EXPECT_EQ(finished.exit_code, 0) << describe(finished);
}

}  // namespace
}  // namespace teejet::testing
