// teejet-record --info, teejet-replay and valve-decode read a recording record by record: their
// memory is bounded by a chunk (about 1 MiB), not by the file. Before, each read the whole file
// into memory (a 400 MB file cost about 538 MB, and under `ulimit -v 700000` they aborted with
// an uncaught std::bad_alloc). Here a 160 MiB recording is read by the real programs and the
// largest resident size of any of them (getrusage of the reaped children: this executable
// starts no other process) must stay under 80 MiB. Inside a private network namespace: replay
// joins DDS.

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <string>
#include <vector>

#include "support/scratch_dir.hpp"
#include "support/subprocess.hpp"
#include "teejet/mcap/writer.hpp"

namespace teejet::testing {
namespace {

using namespace std::chrono_literals;

constexpr std::size_t kPayloadBytes = 1024;
constexpr int kMessages = 160 * 1024;  // 160 MiB of payloads
constexpr long kLargestResidentKiB = 80 * 1024;

// Payloads that do not compress and are not CDR samples: --info counts them, replay counts
// each as refused, valve-decode finds no frame channel; all three read every byte.
void write_recording(const std::string& path) {
  auto sink = mcap::open_file_sink(path);
  ASSERT_TRUE(sink.ok()) << sink.error().reason;
  auto writer = mcap::Writer::create(std::move(*sink), {.compression = ""});
  ASSERT_TRUE(writer.ok()) << writer.error().reason;
  const std::string idl = "module teejet { struct ValvePosition { uint32 serial; }; };";
  const auto schema =
      (*writer)->add_schema("teejet::ValvePosition", "omgidl",
                            {reinterpret_cast<const std::uint8_t*>(idl.data()), idl.size()});
  ASSERT_TRUE(schema.ok());
  const auto channel = (*writer)->add_channel(*schema, "teejet/valve/position", "cdr",
                                              {{"dds_topic", "teejet/valve/position"}});
  ASSERT_TRUE(channel.ok());
  mcap::Bytes payload(kPayloadBytes);
  std::uint32_t state = 12345;
  for (int i = 0; i < kMessages; ++i) {
    for (auto& byte : payload) {
      state = state * 1103515245u + 12345u;
      byte = static_cast<std::uint8_t>(state >> 24);
    }
    payload[0] = payload[1] = 0xFF;  // an encapsulation CDR does not know: never a sample
    const std::uint64_t at = 1'790'000'000'000'000'000ull + static_cast<std::uint64_t>(i) * 1000;
    ASSERT_TRUE(
        (*writer)->write(*channel, static_cast<std::uint32_t>(i + 1), at, at, payload).ok());
  }
  ASSERT_TRUE((*writer)->finish().ok());
}

long largest_child_resident_kib() {
  rusage usage{};
  getrusage(RUSAGE_CHILDREN, &usage);
  return usage.ru_maxrss;
}

TEST(RecordingMemory, ALargeRecordingIsReadInBoundedMemory) {
  ScratchDir scratch;
  const std::string path = (scratch / "large.mcap").string();
  write_recording(path);
  if (HasFatalFailure()) return;

  const Finished info = run({TEEJET_RECORD_PATH, "--info", path}, 120s);
  EXPECT_EQ(info.exit_code, 0) << describe(info);
  EXPECT_NE(info.out.find("messages:    163840"), std::string::npos) << info.out;
  const long after_info = largest_child_resident_kib();

  const Finished replayed =
      run({TEEJET_REPLAY_PATH, path, "--rate", "1000", "--wait-for-readers", "0"}, 300s);
  EXPECT_EQ(replayed.exit_code, 0) << describe(replayed);
  EXPECT_NE(replayed.err.find("0 messages published (163840 refused)"), std::string::npos)
      << replayed.err;
  const long after_replay = largest_child_resident_kib();

  const Finished decoded = run({VALVE_DECODE_PATH, path}, 120s);
  EXPECT_EQ(decoded.exit_code, 1) << describe(decoded);
  EXPECT_NE(decoded.err.find("no teejet/can/frame channel"), std::string::npos) << decoded.err;
  const long after_decode = largest_child_resident_kib();

  EXPECT_LT(after_info, kLargestResidentKiB) << "teejet-record --info";
  EXPECT_LT(after_replay, kLargestResidentKiB) << "teejet-replay";
  EXPECT_LT(after_decode, kLargestResidentKiB) << "valve-decode";
  RecordProperty("largest_resident_kib", std::to_string(after_decode));
  std::printf("largest resident size: --info %ld KiB, replay %ld KiB, valve-decode %ld KiB\n",
              after_info, after_replay, after_decode);
}

}  // namespace
}  // namespace teejet::testing
