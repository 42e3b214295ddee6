// teejet-record's --info and teejet-replay on files a user might hand them: good ones, cut ones,
// damaged ones and foreign ones. Each gets a clear answer naming the problem, never a crash.
// Replay creates a DDS participant: this suite runs in a private network namespace.
#include <fastdds/rtps/common/SerializedPayload.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <atomic>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fstream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <thread>

#include "info.hpp"
#include "recorder.hpp"
#include "replayer.hpp"
#include "support/dds_peer.hpp"
#include "support/eventually.hpp"
#include "support/scratch_dir.hpp"
#include "support/test_domain.hpp"
#include "support/valve_commands.hpp"
#include "teejet/mcap/reader.hpp"
#include "teejet/mcap/writer.hpp"
#include "teejet/recording/catalog.hpp"
#include "teejet/valvePubSubTypes.h"

namespace teejet {
namespace {

using mcap::Bytes;
using ::testing::HasSubstr;

constexpr std::uint64_t kStart = 1'790'000'000'000'000'000ull;
constexpr auto kDeadline = std::chrono::seconds(10);

Bytes position_payload(std::uint32_t serial, float degrees) {
  ValvePosition sample;
  sample.serial(serial);
  sample.degrees(degrees);
  sample.received_ns(kStart);
  ValvePositionPubSubType type;
  eprosima::fastrtps::rtps::SerializedPayload_t payload(type.getSerializedSizeProvider(&sample)());
  EXPECT_TRUE(type.serialize(&sample, &payload));
  return Bytes(payload.data, payload.data + payload.length);
}

struct FileSpec {
  std::string schema = "teejet::ValvePosition";
  std::string topic = "teejet/valve/position";
  std::string compression;  // none: a flipped byte meets the CRC, not the decompressor
  std::size_t chunk_size = 64;
  int messages = 12;
  Bytes payload_override;  // instead of a real sample
  // The recorder's wall clock stepped by this before message `step_before` (counting from 0):
  // its log times move, the publish times (the gateway's clock) do not.
  int step_before = -1;
  std::int64_t step_ns = 0;
};

Bytes make_file(const FileSpec& spec) {
  auto sink = std::make_unique<mcap::MemorySink>();
  auto* memory = sink.get();
  auto writer = mcap::Writer::create(
      std::move(sink), {.compression = spec.compression, .chunk_size = spec.chunk_size});
  EXPECT_TRUE(writer.ok());
  const auto idl = recording::valve_idl();
  const auto schema = (*writer)->add_schema(
      spec.schema, "omgidl", {reinterpret_cast<const std::uint8_t*>(idl.data()), idl.size()});
  const auto channel =
      (*writer)->add_channel(*schema, spec.topic, "cdr", {{"dds_topic", spec.topic}});
  for (int i = 0; i < spec.messages; ++i) {
    const Bytes payload = spec.payload_override.empty() ? position_payload(1, static_cast<float>(i))
                                                        : spec.payload_override;
    const std::uint64_t at = kStart + static_cast<std::uint64_t>(i) * 1'000'000;  // 1 ms apart
    const std::uint64_t logged = spec.step_before >= 0 && i >= spec.step_before
                                     ? at + static_cast<std::uint64_t>(spec.step_ns)
                                     : at;
    EXPECT_TRUE(
        (*writer)->write(*channel, static_cast<std::uint32_t>(i + 1), logged, at, payload).ok());
  }
  EXPECT_TRUE((*writer)->finish().ok());
  return memory->bytes();
}

// Little-endian fields of a file, for making crafted ones out of a good one.
std::uint64_t get_u64(const Bytes& file, std::size_t at) {
  std::uint64_t value = 0;
  for (int i = 7; i >= 0; --i) value = (value << 8) | file[at + static_cast<std::size_t>(i)];
  return value;
}
void put_u64(Bytes& file, std::size_t at, std::uint64_t value) {
  for (std::size_t i = 0; i < 8; ++i) file[at + i] = static_cast<std::uint8_t>(value >> (8 * i));
}
// A complete file's Footer: opcode, length, summary start, summary offset start, summary CRC.
std::size_t footer_at(const Bytes& file) { return file.size() - 8 - 29; }
// The first record of `opcode` in a complete file's summary section.
std::size_t summary_record(const Bytes& file, std::uint8_t opcode) {
  const std::size_t end = footer_at(file);
  for (auto at = static_cast<std::size_t>(get_u64(file, end + 9)); at < end;
       at += 9 + static_cast<std::size_t>(get_u64(file, at + 1))) {
    if (file[at] == opcode) return at;
  }
  ADD_FAILURE() << "no record " << int{opcode} << " in the summary";
  return 0;
}
// Summary CRC 0: not checked, so a crafted summary is read as it stands.
void drop_summary_crc(Bytes& file) {
  for (std::size_t i = 0; i < 4; ++i) file[footer_at(file) + 25 + i] = 0;
}

class RecordingFiles : public ::testing::Test {
 protected:
  std::string save(const std::string& name, const Bytes& bytes) {
    const std::string path = (dir_.path() / name).string();
    std::ofstream(path, std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()),
               static_cast<std::streamsize>(bytes.size()));
    return path;
  }

  struct Info {
    int status;
    std::string out, err;
  };
  Info info(const std::string& path, bool json = false) {
    std::ostringstream out, err;
    const int status = record::print_info(path, json, out, err);
    return {status, out.str(), err.str()};
  }

  // A hundred times as fast as recorded: these files span 11 ms.
  static replay::ReplayOptions fast() {
    replay::ReplayOptions options;
    options.rate = 100;
    return options;
  }

  Result<replay::ReplayReport> replay_file(const std::string& path,
                                           replay::ReplayOptions options = fast()) {
    options.file = path;
    options.wait_for_readers = std::chrono::milliseconds(0);
    options.domain = testing::test_domain();
    std::atomic<bool> stop{false};
    return replay::replay(options, stop);
  }

  testing::ScratchDir dir_;
};

TEST_F(RecordingFiles, ASummaryIsHeldAgainstTheMessagesAndNeverShownInTheirPlace) {
  // Before, --info printed a crafted summary as it stood: 18446744073709551615 messages, an end
  // before its start, a channel left out that holds messages replay would still publish.
  Bytes lying = make_file({});
  const std::size_t statistics = summary_record(lying, 0x0B) + 9;
  put_u64(lying, statistics, UINT64_MAX);                   // message_count
  put_u64(lying, statistics + 26, kStart + 5'000'000'000);  // message_start_time
  put_u64(lying, statistics + 46 + 2, 0);                   // channel 0's count
  drop_summary_crc(lying);
  const auto path = save("lying.mcap", lying);
  const auto described = info(path);
  EXPECT_EQ(described.status, 0) << described.err;
  EXPECT_THAT(described.out, HasSubstr("messages:    12\n"));
  EXPECT_THAT(described.out, HasSubstr("duration:    0.011 s"));
  EXPECT_THAT(described.out,
              HasSubstr("summary:     disagrees with the file, not used: it counts "
                        "18446744073709551615 messages, the file holds 12; it says the messages "
                        "span 2026-09-21T14:13:25.000000000Z to 2026-09-21T14:13:20.011000000Z, "
                        "they span 2026-09-21T14:13:20.000000000Z to "
                        "2026-09-21T14:13:20.011000000Z; it counts 0 messages on channel 0 "
                        "(teejet/valve/position), the file holds 12\n"));
  const auto json = nlohmann::json::parse(info(path, true).out);
  EXPECT_EQ(json["summary"], "disagrees");
  EXPECT_EQ(json["messages"], 12);
  EXPECT_EQ(json["summary_differences"].size(), 3u);

  Bytes without_channel = make_file({});
  without_channel[summary_record(without_channel, 0x04)] = 0x80;  // a record kind readers skip
  drop_summary_crc(without_channel);
  const auto missing = info(save("channel.mcap", without_channel));
  EXPECT_THAT(missing.out, HasSubstr("summary:     disagrees with the file, not used: channel 0 "
                                     "(teejet/valve/position) (12 messages) is missing from it\n"));
  EXPECT_THAT(missing.out, HasSubstr("teejet/valve/position"));

  EXPECT_THAT(info(save("good-summary.mcap", make_file({}))).out,
              HasSubstr("complete:    yes\nsummary:     agrees with the messages read\n"));
}

TEST_F(RecordingFiles, AClosedFileWithoutASummaryIsCompleteAndSaysSo) {
  // Before: "complete: yes (summary and chunk indexes: readers can seek)" for a file with none.
  Bytes bare = make_file({});
  put_u64(bare, footer_at(bare) + 9, 0);   // summary_start
  put_u64(bare, footer_at(bare) + 17, 0);  // summary_offset_start
  drop_summary_crc(bare);
  const auto described = info(save("bare.mcap", bare));
  EXPECT_EQ(described.status, 0) << described.err;
  EXPECT_THAT(described.out, HasSubstr("complete:    yes\nsummary:     none (a reader must read "
                                       "the whole file)\n"));
  EXPECT_THAT(described.out, HasSubstr("messages:    12\n"));
}

TEST_F(RecordingFiles, AGoodFileIsDescribedAndReplayed) {
  const auto path = save("good.mcap", make_file({}));
  const auto described = info(path);
  EXPECT_EQ(described.status, 0) << described.err;
  EXPECT_THAT(described.out, HasSubstr("complete:    yes"));
  EXPECT_THAT(described.out, HasSubstr("messages:    12"));
  EXPECT_THAT(described.out, HasSubstr("duration:    0.011 s"));
  EXPECT_THAT(described.out, HasSubstr("teejet/valve/position"));
  EXPECT_EQ(described.err, "");
  const auto json = nlohmann::json::parse(info(path, true).out);
  EXPECT_EQ(json["messages"], 12);
  EXPECT_EQ(json["channels"][0]["schema"], "teejet::ValvePosition");
  EXPECT_EQ(json["start_ns"], kStart);

  const auto replayed = replay_file(path);
  ASSERT_TRUE(replayed.ok()) << replayed.error().reason;
  EXPECT_EQ(replayed->published, 12u);
  EXPECT_EQ(replayed->failed, 0u);
}

TEST_F(RecordingFiles, ACutFileSaysWhereItEndsAndReplaysWhatIsThere) {
  Bytes file = make_file({});
  // Inside the ninth message: its chunk and everything after it are lost.
  const Bytes ninth = position_payload(1, 8.0f);
  const auto at = std::search(file.begin(), file.end(), ninth.begin(), ninth.end());
  ASSERT_NE(at, file.end());
  file.resize(static_cast<std::size_t>(at - file.begin()) + 4);
  const auto path = save("cut.mcap", file);
  const auto described = info(path);
  EXPECT_EQ(described.status, 0);
  EXPECT_THAT(described.out, HasSubstr("complete:    no: "));
  EXPECT_THAT(described.err, HasSubstr("incomplete"));
  const auto replayed = replay_file(path);
  ASSERT_TRUE(replayed.ok()) << replayed.error().reason;
  EXPECT_GE(replayed->published, 6u);
  EXPECT_LE(replayed->published, 8u);
}

TEST_F(RecordingFiles, WrongMagicIsRefusedByName) {
  Bytes file = make_file({});
  file[1] = 'X';
  const auto path = save("magic.mcap", file);
  const auto described = info(path);
  EXPECT_EQ(described.status, 1);
  EXPECT_EQ(described.err, "teejet-record: " + path + ": not an MCAP file: wrong magic bytes\n");
  const auto replayed = replay_file(path);
  ASSERT_FALSE(replayed.ok());
  EXPECT_EQ(replayed.error().reason, path + ": not an MCAP file: wrong magic bytes");
}

TEST_F(RecordingFiles, AFlippedByteFailsTheChunkCrc) {
  Bytes file = make_file({});
  // The first message's degrees, inside the first chunk's records.
  const Bytes sample = position_payload(1, 0.0f);
  const auto at = std::search(file.begin(), file.end(), sample.begin(), sample.end());
  ASSERT_NE(at, file.end());
  at[8] ^= 0x40;
  const auto path = save("crc.mcap", file);
  const auto described = info(path);
  EXPECT_EQ(described.status, 1);
  EXPECT_THAT(described.err, HasSubstr("a chunk's CRC does not match its records"));
  const auto replayed = replay_file(path);
  ASSERT_FALSE(replayed.ok());
  EXPECT_THAT(replayed.error().reason, HasSubstr("a chunk's CRC does not match its records"));
}

TEST_F(RecordingFiles, AForeignTopicIsListedButNotReplayed) {
  const auto path =
      save("foreign.mcap", make_file({.schema = "acme::Thing", .topic = "acme/thing"}));
  const auto described = info(path);
  EXPECT_EQ(described.status, 0);
  EXPECT_THAT(described.out, HasSubstr("acme::Thing"));
  const auto replayed = replay_file(path);
  ASSERT_FALSE(replayed.ok());
  EXPECT_EQ(replayed.error().reason,
            path + ": channel 0 'acme/thing': 'acme/thing' is not a teejet topic");
}

TEST_F(RecordingFiles, ATeejetTopicWithAnotherSchemaIsRefused) {
  const auto path = save("schema.mcap", make_file({.schema = "teejet::ValveVoltage"}));
  const auto replayed = replay_file(path);
  ASSERT_FALSE(replayed.ok());
  EXPECT_EQ(replayed.error().reason,
            path +
                ": channel 0 'teejet/valve/position': schema 'teejet::ValveVoltage' (omgidl) "
                "is not the one this replayer knows for teejet/valve/position: "
                "'teejet::ValvePosition' (omgidl)");
}

TEST_F(RecordingFiles, APayloadThatIsNotItsTypeIsCountedNotPublished) {
  const auto path =
      save("payload.mcap", make_file({.messages = 3, .payload_override = {0, 1, 0, 0, 7}}));
  const auto replayed = replay_file(path);
  ASSERT_TRUE(replayed.ok()) << replayed.error().reason;
  EXPECT_EQ(replayed->published, 0u);
  EXPECT_EQ(replayed->failed, 3u);
  EXPECT_EQ(replayed->last_failure,
            "teejet/valve/position #3: a 5-byte payload is not a CDR teejet::ValvePosition");
}

TEST_F(RecordingFiles, APayloadCdrRefusesIsCountedNotACrash) {
  // An encapsulation CDR does not know, then a whole ValvePosition's bytes.
  Bytes payload = position_payload(1, 0.0f);
  payload[1] = 0x7F;
  const auto path =
      save("encapsulation.mcap", make_file({.messages = 2, .payload_override = payload}));
  const auto replayed = replay_file(path);
  ASSERT_TRUE(replayed.ok()) << replayed.error().reason;
  EXPECT_EQ(replayed->published, 0u);
  EXPECT_EQ(replayed->failed, 2u);
  EXPECT_EQ(replayed->last_failure,
            "teejet/valve/position #2: a 20-byte payload is not a CDR teejet::ValvePosition");
}

TEST_F(RecordingFiles, StartAndEndPickAWindowOfTheRecording) {
  // 12 messages 1 ms apart: 5 ms to 8 ms in are the 6th to the 9th.
  const auto path = save("window.mcap", make_file({}));
  auto options = fast();
  options.start = std::chrono::milliseconds(5);
  options.end = std::chrono::milliseconds(8);
  const auto replayed = replay_file(path, options);
  ASSERT_TRUE(replayed.ok()) << replayed.error().reason;
  EXPECT_EQ(replayed->published, 4u);
}

TEST_F(RecordingFiles, AWindowOutsideTheRecordingIsRefusedWithTheSpan) {
  // 12 messages 1 ms apart: 0 to 11 ms in. Before, --start past the end published nothing and
  // exited 0 without a word.
  const auto path = save("past.mcap", make_file({}));
  auto options = fast();
  options.start = std::chrono::milliseconds(100);
  const auto past = replay_file(path, options);
  ASSERT_FALSE(past.ok());
  EXPECT_EQ(past.error().reason,
            path +
                ": nothing to replay from --start 0.100 s: the messages are from 0.000 s to "
                "0.011 s into the recording");
  options.start = std::chrono::milliseconds(20);
  options.end = std::chrono::milliseconds(30);
  const auto window = replay_file(path, options);
  ASSERT_FALSE(window.ok());
  EXPECT_EQ(window.error().reason,
            path +
                ": nothing to replay from --start 0.020 s to --end 0.030 s: the messages are "
                "from 0.000 s to 0.011 s into the recording");
  options.start = std::chrono::milliseconds(11);
  options.end.reset();
  const auto last = replay_file(path, options);
  ASSERT_TRUE(last.ok()) << last.error().reason;
  EXPECT_EQ(last->published, 1u);
}

TEST_F(RecordingFiles, StepsOfTheRecordersClockAreReportedAndNeverWaitedOut) {
  // Files recorded before log times were step-free: the clock set back an hour after 6 messages,
  // or 10 years ahead. --info called the first 3,599.97 s long and replay waited the hour.
  constexpr std::int64_t kHour = 3'600'000'000'000;
  constexpr std::int64_t kTenYears = 10 * 365 * 86'400'000'000'000;
  for (const std::int64_t step : {-kHour, kTenYears}) {
    SCOPED_TRACE(step);
    const auto path = save("step.mcap", make_file({.step_before = 6, .step_ns = step}));
    const auto described = info(path);
    EXPECT_EQ(described.status, 0) << described.err;
    EXPECT_THAT(described.out, HasSubstr("duration:    0.010 s\n"));
    EXPECT_THAT(described.out,
                HasSubstr(step < 0 ? "clock steps: 1 in the recorder's log times (the largest by "
                                     "-3599.999 s, before message 7)"
                                   : "clock steps: 1 in the recorder's log times (the largest by "
                                     "+315360000.001 s, before message 7)"));
    EXPECT_EQ(nlohmann::json::parse(info(path, true).out)["clock_steps"], 1);
    replay::ReplayOptions paced;  // as recorded: 10 ms of messages without the step
    const auto replayed = replay_file(path, paced);
    ASSERT_TRUE(replayed.ok()) << replayed.error().reason;
    EXPECT_EQ(replayed->published, 12u);
    EXPECT_EQ(replayed->clock_steps, 1u);
  }
}

TEST_F(RecordingFiles, TheRateScalesTheRecordedGaps) {
  // 11 ms of recording at rate 0.1 takes 110 ms, at rate 100 about 0.1 ms.
  const auto path = save("rate.mcap", make_file({}));
  replay::ReplayOptions slow;
  slow.rate = 0.1;
  const auto before = std::chrono::steady_clock::now();
  const auto replayed = replay_file(path, slow);
  const auto took = std::chrono::steady_clock::now() - before;
  ASSERT_TRUE(replayed.ok()) << replayed.error().reason;
  EXPECT_EQ(replayed->published, 12u);
  EXPECT_GE(took, std::chrono::milliseconds(110));
}

// The degrees of every position a subscriber hears, taken on Fast DDS's thread as they arrive.
class PositionsHeard final : public eprosima::fastdds::dds::DataReaderListener {
 public:
  void on_data_available(eprosima::fastdds::dds::DataReader* reader) override {
    ValvePosition sample;
    eprosima::fastdds::dds::SampleInfo info;
    std::lock_guard lock(mutex_);
    while (reader->take_next_sample(&sample, &info) ==
           eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK) {
      if (info.valid_data) degrees_.push_back(sample.degrees());
    }
  }
  std::vector<float> degrees() const {
    std::lock_guard lock(mutex_);
    return degrees_;
  }

 private:
  mutable std::mutex mutex_;
  std::vector<float> degrees_;
};

TEST_F(RecordingFiles, LoopStartsAgainUntilStopped) {
  // 12 positions, 0 to 11 degrees: a subscriber hears them again and again until the stop.
  const auto path = save("loop.mcap", make_file({}));
  PositionsHeard heard;
  testing::DdsPeer subscriber(testing::test_domain(), "loop-subscriber");
  ASSERT_NE(subscriber.reader<ValvePosition>(dds::topics::state_reader_qos(), &heard), nullptr);
  replay::ReplayOptions options;
  options.file = path;
  options.loop = true;
  options.rate = 10;  // 1.1 ms a pass
  options.wait_for_readers = kDeadline;
  options.domain = testing::test_domain();
  std::atomic<bool> stop{false};
  bool three_passes_heard = false;
  std::thread stopper([&] {
    // Each pass ends at 11 degrees: heard three times, three whole passes reached the subscriber.
    three_passes_heard = testing::eventually(
        [&] { return std::ranges::count(heard.degrees(), 11.0f) >= 3; }, kDeadline);
    stop = true;
  });
  const auto replayed = replay::replay(options, stop);
  stopper.join();
  EXPECT_TRUE(three_passes_heard) << heard.degrees().size() << " positions heard";
  ASSERT_TRUE(replayed.ok()) << replayed.error().reason;
  EXPECT_GE(replayed->loops, 3);
  EXPECT_GE(replayed->published, 36u);
  EXPECT_EQ(replayed->failed, 0u);
  const auto degrees = heard.degrees();
  EXPECT_EQ(std::set<float>(degrees.begin(), degrees.end()),
            (std::set<float>{0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11}));
}

TEST_F(RecordingFiles, TopicGlobsChooseWhatIsReplayed) {
  const auto path = save("topics.mcap", make_file({}));
  auto options = fast();
  options.topics = {"teejet/valve/voltage"};
  const auto none = replay_file(path, options);
  ASSERT_FALSE(none.ok());
  EXPECT_EQ(none.error().reason, path + ": no channel to replay matches --topic");
  options.topics = {"teejet/valve/pos*"};
  const auto some = replay_file(path, options);
  ASSERT_TRUE(some.ok()) << some.error().reason;
  EXPECT_EQ(some->published, 12u);
}

TEST_F(RecordingFiles, CommandsAreReplayedOnlyWhenAsked) {
  auto command = testing::stop(1);
  ValveCommandPubSubType type;
  eprosima::fastrtps::rtps::SerializedPayload_t payload(type.getSerializedSizeProvider(&command)());
  ASSERT_TRUE(type.serialize(&command, &payload));
  const auto path =
      save("commands.mcap",
           make_file({.schema = "teejet::ValveCommand",
                      .topic = "teejet/valve/command",
                      .messages = 2,
                      .payload_override = Bytes(payload.data, payload.data + payload.length)}));
  const auto refused = replay_file(path);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().reason, path + ": no channel to replay");
  auto options = fast();
  options.with_commands = true;
  const auto replayed = replay_file(path, options);
  ASSERT_TRUE(replayed.ok()) << replayed.error().reason;
  EXPECT_EQ(replayed->published, 2u);
}

TEST_F(RecordingFiles, EmptyAndMissingFilesAreNamed) {
  const auto empty = save("empty.mcap", {});
  EXPECT_EQ(info(empty).err,
            "teejet-record: " + empty + ": not an MCAP file: shorter than its magic bytes\n");
  const auto missing = (dir_.path() / "missing.mcap").string();
  EXPECT_EQ(info(missing).status, 1);
  EXPECT_EQ(info(missing).err,
            "teejet-record: " + missing + ": cannot open: No such file or directory\n");
  const auto not_replayed = replay_file(missing);
  ASSERT_FALSE(not_replayed.ok());
  EXPECT_EQ(not_replayed.error().reason, missing + ": cannot open: No such file or directory");
}

TEST_F(RecordingFiles, WhatIsNotARegularFileIsRefusedAtOnce) {
  // Before: a FIFO without a writer hung replay in open(), deaf to Ctrl-C, and /dev/zero grew
  // until the OOM killer came.
  const auto fifo = (dir_.path() / "fifo.mcap").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const std::string refused =
      ": it is a FIFO, not a recording file (a recording is read from a "
      "regular file: copy it to one first)";
  EXPECT_EQ(info(fifo).err, "teejet-record: " + fifo + refused + "\n");
  const auto replayed = replay_file(fifo);
  ASSERT_FALSE(replayed.ok());
  EXPECT_EQ(replayed.error().reason, fifo + refused);
  EXPECT_EQ(info("/dev/zero").err,
            "teejet-record: /dev/zero: it is a character device, not a recording file (a "
            "recording is read from a regular file: copy it to one first)\n");
  EXPECT_EQ(info(dir_.path().string()).status, 1);
  EXPECT_NE(info(dir_.path().string()).err.find("it is a directory"), std::string::npos);
}

TEST(RecordingTopics, GlobsSelectCatalogTopicsAndRefuseStrays) {
  EXPECT_EQ(record::select_topics({})->size(), 19u);
  const auto valves = record::select_topics({"teejet/valve/*"});
  ASSERT_TRUE(valves.ok());
  EXPECT_EQ(valves->size(), 15u);
  EXPECT_EQ(valves->front(), "teejet/valve/presence");
  EXPECT_EQ(record::select_topics({"teejet/layout/*"})->size(), 2u);
  EXPECT_EQ(*record::select_topics({"*frame", "teejet/gateway/status"}),
            (std::vector<std::string>{"teejet/gateway/status", "teejet/can/frame"}));
  const auto stray = record::select_topics({"teejet/valve/postion"});
  ASSERT_FALSE(stray.ok());
  EXPECT_THAT(stray.error().reason,
              HasSubstr("--topic 'teejet/valve/postion' matches none of the teejet topics:\n"
                        "  teejet/valve/presence\n  teejet/valve/location\n"
                        "  teejet/valve/position\n"));
}

TEST(RecordingTopics, SplitFilesAreNumberedBeforeTheExtension) {
  EXPECT_EQ(record::split_file_name("run.mcap", 0), "run_000.mcap");
  EXPECT_EQ(record::split_file_name("logs.d/run", 12), "logs.d/run_012");
  EXPECT_EQ(record::split_file_name("/tmp/a.b/run.x.mcap", 3), "/tmp/a.b/run.x_003.mcap");
}

TEST(RecordingTopics, EverySchemaIsATypeOfTheBuiltInIdl) {
  const std::string idl(recording::valve_idl());
  for (const auto& type : recording::topic_types()) {
    const std::string name = type.type_name.substr(std::string("teejet::").size());
    EXPECT_NE(idl.find("struct " + name + " {"), std::string::npos) << type.type_name;
    EXPECT_EQ(recording::find_topic(type.topic), &type);
  }
  EXPECT_EQ(recording::find_topic("teejet/valve/nothing"), nullptr);
}

}  // namespace
}  // namespace teejet
