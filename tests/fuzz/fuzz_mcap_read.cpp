// The MCAP reader (tools/mcap) on arbitrary bytes: what teejet-replay, valve-decode and
// teejet-record --info open, from disks that fill up, recorders that are killed and files
// people send each other.
//
// Input: the bytes of a file. Seeds: small recordings of our writer, one per compression, and
// one cut short.
//
// Properties: no crash, leak or sanitizer report whatever the bytes; an error always has a
// reason; every message handed out is on a channel the file defined, and the count the reader
// reports is the number it handed out; the summary reader likewise never crashes. The same bytes
// then go through what teejet-record --info and teejet-replay do with a file before anything is
// published (the summary held against the messages, clock steps, the recorded gateways' status
// samples decoded, the --start window): --info exits 0 or 1, with output or a reason, and says
// as many messages as the reader counted; replay's check agrees with the reader on the file.

#include <cstddef>
#include <cstdint>
#include <span>
#include <sstream>
#include <string>

#include "fuzz_input.hpp"
#include "info.hpp"
#include "replayer.hpp"
#include "teejet/mcap/reader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace teejet::mcap;
  const std::span<const std::uint8_t> file(data, size);
  std::uint64_t visited = 0;
  auto contents = read_messages(file, [&](const Channel& channel, const Message& message) {
    FUZZ_CHECK(channel.id == message.channel_id, "a message handed out with another channel");
    ++visited;
  });
  if (contents) {
    FUZZ_CHECK(contents->messages == visited, "the count differs from the messages handed out");
    for (const auto& [id, channel] : contents->channels) {
      FUZZ_CHECK(channel.schema_id == 0 || contents->schemas.count(channel.schema_id),
                 "a channel whose schema was never defined");
    }
  } else {
    FUZZ_CHECK(!contents.error().reason.empty(), "an error without a reason");
  }
  auto summary = read_summary(file);
  if (!summary) FUZZ_CHECK(!summary.error().reason.empty(), "an error without a reason");

  MemorySource source(file);
  std::ostringstream out, err;
  const int status = teejet::record::print_info(source, "fuzz.mcap", /*json=*/false, out, err);
  FUZZ_CHECK(status == 0 || status == 1, "--info exited neither 0 nor 1");
  FUZZ_CHECK(status == (contents ? 0 : 1), "--info and the reader disagree on the file");
  if (status == 0) {
    FUZZ_CHECK(
        out.str().find("messages:    " + std::to_string(visited) + "\n") != std::string::npos,
        "--info shows another message count than the reader's");
  } else {
    FUZZ_CHECK(!err.str().empty(), "--info failed without a reason");
  }

  teejet::replay::ReplayOptions options;
  options.with_commands = true;
  options.start = std::chrono::milliseconds(1);
  auto checked = teejet::replay::check_recording(source, options);
  if (checked) {
    FUZZ_CHECK(contents.ok() && checked->contents.messages == contents->messages,
               "replay's check read another file than the reader");
  } else {
    FUZZ_CHECK(!checked.error().reason.empty(), "replay's check failed without a reason");
  }
  return 0;
}
