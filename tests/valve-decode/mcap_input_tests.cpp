// valve-decode on MCAP recordings: the teejet/can/frame channel prints exactly what the same
// frames print from candump -L. The recordings are built here with tools/mcap's Writer and
// BusFrame payloads as fastddsgen serializes them: no DDS participant.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "codec/sheet_cases.hpp"
#include "mcap_input.hpp"
#include "support/scratch_dir.hpp"
#include "support/subprocess.hpp"
#include "teejet/bus_frame/bus_frame.hpp"
#include "teejet/mcap/writer.hpp"
#include "valve_decode_run.hpp"

namespace {

namespace fs = std::filesystem;
namespace mcap = teejet::mcap;
using namespace std::chrono_literals;
using teejet::testing::Finished;
using teejet::testing::ScratchDir;
using teejet::testing::Subprocess;
using teejet::testing::valve_decode::expect_same_lines;
using teejet::testing::valve_decode::lines_of;
using teejet::testing::valve_decode::read_file;
using teejet::testing::valve_decode::run_valve_decode;
using Bytes = std::vector<std::uint8_t>;

constexpr const char* kValveIdl = VALVE_IDL_PATH;
constexpr const char* kNoFrameChannel =
    ": no teejet/can/frame channel (record with teejet-gateway --record-frames)\n";

void write_bytes(const fs::path& path, const Bytes& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
}

// The sheet's bytes of the first case called `name` (tests/codec/sheet_cases.hpp).
Bytes sheet_bytes(const std::string& name) {
  for (const auto& sheet_case : teejet::codec::testing::sheet_cases()) {
    if (sheet_case.name == name) return sheet_case.bytes;
  }
  ADD_FAILURE() << "no sheet case " << name;
  return {};
}

teejet::BusFrame frame(std::uint32_t id, const Bytes& data, teejet::FrameDirection direction,
                       std::uint64_t stamp_ns, const std::string& gateway = "gw-left",
                       bool extended = true) {
  teejet::codec::CanFrame can;
  can.id = id;
  can.extended = extended;
  can.dlc = static_cast<std::uint8_t>(data.size());
  std::copy(data.begin(), data.end(), can.data.begin());
  return teejet::bus_frame::from_can_frame(can, gateway, "can0", direction, stamp_ns);
}

constexpr std::uint64_t kT0 = 1'700'000'000'000'000'000ULL;

// The sheet's I Am Here, Target Degrees and Position between valve 0xD8 and the controller 0xD5,
// and a frame of no valve (an 11-bit identifier), which prints an error line. The command was
// sent after the reply's kernel stamp: the output keeps the file's order, not the stamps'.
std::vector<teejet::BusFrame> sheet_frames(const std::string& gateway = "gw-left") {
  return {
      frame(0x18EFD5D8, sheet_bytes("i_am_here"), teejet::FRAME_RECEIVED, kT0 + 123'456, gateway),
      frame(0x18EFD8D5, sheet_bytes("target_degrees"), teejet::FRAME_SENT, kT0 + 500'000'999,
            gateway),
      frame(0x18EFD5D8, sheet_bytes("position"), teejet::FRAME_RECEIVED, kT0 + 499'000'000,
            gateway),
      frame(0x123, {0xAB, 0x01}, teejet::FRAME_RECEIVED, kT0 + 1'000'000'001, gateway, false),
  };
}

// A recording as teejet-record writes it: schemas with the IDL text, a teejet/can/frame channel
// and a teejet/valve/position channel whose messages valve-decode must skip.
class Recording {
 public:
  // `idl`: the schemas' data, valve.idl as teejet-record writes it unless a test needs a small
  // file.
  explicit Recording(const std::string& compression, std::size_t chunk_size = 1 << 20,
                     bool with_frame_channel = true,
                     const std::string& idl = read_file(kValveIdl)) {
    auto sink = std::make_unique<mcap::MemorySink>();
    memory_ = sink.get();
    auto writer = mcap::Writer::create(std::move(sink),
                                       {.compression = compression, .chunk_size = chunk_size});
    EXPECT_TRUE(writer.ok()) << writer.error().reason;
    writer_ = std::move(*writer);
    const Bytes idl_bytes(idl.begin(), idl.end());
    const auto position_schema = writer_->add_schema("teejet::ValvePosition", "omgidl", idl_bytes);
    position_channel_ = *writer_->add_channel(*position_schema, "teejet/valve/position", "cdr",
                                              {{"dds_topic", "teejet/valve/position"}});
    if (with_frame_channel) {
      const auto frame_schema = writer_->add_schema("teejet::BusFrame", "omgidl", idl_bytes);
      frame_channel_ = *writer_->add_channel(*frame_schema, "teejet/can/frame", "cdr",
                                             {{"dds_topic", "teejet/can/frame"}});
    }
  }

  void frame(const teejet::BusFrame& sample) { message(teejet::bus_frame::serialize(sample)); }
  // Any bytes on the frame channel.
  void message(const Bytes& data) {
    const auto log_time = kT0 + 2'000'000'000 + ++frames_;
    EXPECT_TRUE(writer_->write(frame_channel_, frames_, log_time, log_time, data).ok());
    // A position sample between frames: its bytes would decode as a frame of sorts.
    const auto position = teejet::bus_frame::serialize(sheet_frames()[0]);
    EXPECT_TRUE(writer_->write(position_channel_, frames_, log_time, log_time, position).ok());
  }
  void flush() { EXPECT_TRUE(writer_->flush().ok()); }
  std::uint64_t size() const { return writer_->bytes_written(); }
  Bytes finish() {
    EXPECT_TRUE(writer_->finish().ok());
    return memory_->bytes();
  }
  Bytes so_far() const { return memory_->bytes(); }

 private:
  mcap::MemorySink* memory_ = nullptr;
  std::unique_ptr<mcap::Writer> writer_;
  std::uint16_t position_channel_ = 0;
  std::uint16_t frame_channel_ = 0;
  std::uint32_t frames_ = 0;
};

Bytes record(const std::vector<teejet::BusFrame>& frames, const std::string& compression = "zstd",
             std::size_t chunk_size = 1 << 20, const std::string& idl = read_file(kValveIdl)) {
  Recording recording(compression, chunk_size, true, idl);
  for (const auto& sample : frames) recording.frame(sample);
  return recording.finish();
}

// What valve-decode prints for the same frames logged by candump -L.
std::string decoded_as_candump(const std::vector<teejet::BusFrame>& frames) {
  std::string log;
  for (const auto& sample : frames) {
    const auto line = teejet::bus_frame::to_candump_line(sample);
    EXPECT_TRUE(line.ok()) << line.error().reason;
    log += *line + "\n";
  }
  const auto run = run_valve_decode({}, log);
  EXPECT_EQ(run.exit_code, 0);
  return run.out;
}

const std::vector<std::string> kSheetLines{
    R"({"t":1700000000.000123,"iface":"can0","dir":"from_valve","addr":216,"msg":"i_am_here",)"
    R"("fields":{"part_number":74565,"serial":"TJV123456","boot_mode":false}})",
    R"({"t":1700000000.500000,"iface":"can0","dir":"to_valve","addr":216,"msg":"target_degrees",)"
    R"("fields":{"speed_percent":75,"direction":"open","degrees":123.4}})",
    R"({"t":1700000000.499000,"iface":"can0","dir":"from_valve","addr":216,"msg":"position",)"
    R"("fields":{"degrees":123.4}})",
    R"({"error":"11-bit identifier 0x123 is not a valve frame",)"
    R"("line":"(1700000001.000000) can0 123#AB01"})",
};

TEST(ValveDecodeMcap, SheetFramesPrintTheHandWrittenLines) {
  ScratchDir dir;
  write_bytes(dir.path() / "run.mcap", record(sheet_frames()));
  const auto run = run_valve_decode({(dir.path() / "run.mcap").string()});
  EXPECT_EQ(run.exit_code, 0);
  EXPECT_EQ(run.err, "");
  std::string expected;
  for (const auto& line : kSheetLines) expected += line + "\n";
  expect_same_lines(run.out, expected);
}

TEST(ValveDecodeMcap, EveryCompressionPrintsWhatTheCandumpLogOfTheSameFramesPrints) {
  const auto frames = sheet_frames();
  const auto expected = decoded_as_candump(frames);
  ASSERT_EQ(lines_of(expected).size(), frames.size());
  ScratchDir dir;
  for (const std::string compression : {"zstd", "lz4", ""}) {
    // 64-byte chunks: every frame in a chunk of its own, so chunk boundaries are crossed too.
    for (const std::size_t chunk_size : {std::size_t{1} << 20, std::size_t{64}}) {
      SCOPED_TRACE("compression \"" + compression + "\", chunks of " + std::to_string(chunk_size));
      const auto path = dir.path() / ("run-" + compression + ".mcap");
      write_bytes(path, record(frames, compression, chunk_size));
      const auto run = run_valve_decode({path.string()});
      EXPECT_EQ(run.exit_code, 0);
      EXPECT_EQ(run.err, "");
      EXPECT_EQ(run.out, expected);
    }
  }
}

TEST(ValveDecodeMcap, ManyFramesInManyChunksKeepTheFileOrder) {
  std::vector<teejet::BusFrame> frames;
  for (int i = 0; i < 500; ++i) {
    auto copy = sheet_frames()[static_cast<std::size_t>(i % 3)];
    // Stamps going back and forth: only the file's order may decide the output's.
    copy.stamp_ns(kT0 + static_cast<std::uint64_t>((i % 2 ? 1000 - i : i)) * 1'000'000);
    frames.push_back(copy);
  }
  ScratchDir dir;
  write_bytes(dir.path() / "many.mcap", record(frames, "lz4", 4096));
  const auto run = run_valve_decode({(dir.path() / "many.mcap").string()});
  EXPECT_EQ(run.exit_code, 0);
  EXPECT_EQ(run.err, "");
  EXPECT_EQ(lines_of(run.out).size(), 500u);
  EXPECT_EQ(run.out, decoded_as_candump(frames));
}

TEST(ValveDecodeMcap, SeveralGatewaysNameTheGatewayOnEveryLine) {
  auto frames = sheet_frames("gw-left");
  const auto right = sheet_frames("gw-right");
  frames.insert(frames.begin() + 1, right[0]);
  ScratchDir dir;
  write_bytes(dir.path() / "two.mcap", record(frames));
  const auto run = run_valve_decode({(dir.path() / "two.mcap").string()});
  EXPECT_EQ(run.exit_code, 0);
  EXPECT_EQ(run.err, "");
  const auto with_gateway = [](const std::string& line, const std::string& gateway) {
    // After "t" (or "error"): the first member ends at the first comma of these lines.
    const auto comma = line.find(',');
    return line.substr(0, comma + 1) + "\"gw\":\"" + gateway + "\"," + line.substr(comma + 1);
  };
  std::string expected;
  expected += with_gateway(kSheetLines[0], "gw-left") + "\n";
  expected += with_gateway(kSheetLines[0], "gw-right") + "\n";
  for (std::size_t i = 1; i < kSheetLines.size(); ++i) {
    expected += with_gateway(kSheetLines[i], "gw-left") + "\n";
  }
  expect_same_lines(run.out, expected);
  EXPECT_EQ(lines_of(run.out)[0],
            R"({"t":1700000000.000123,"gw":"gw-left","iface":"can0","dir":"from_valve",)"
            R"("addr":216,"msg":"i_am_here",)"
            R"("fields":{"part_number":74565,"serial":"TJV123456","boot_mode":false}})");
  EXPECT_EQ(lines_of(run.out)[4],
            R"({"error":"11-bit identifier 0x123 is not a valve frame","gw":"gw-left",)"
            R"("line":"(1700000001.000000) can0 123#AB01"})");
}

TEST(ValveDecodeMcap, SamplesThatAreNoFrameGiveErrorLinesAndDecodingGoesOn) {
  Recording recording("zstd");
  recording.message({0x00, 0x01, 0x00});
  auto long_dlc = sheet_frames()[0];
  long_dlc.dlc(9);
  long_dlc.data(Bytes(9, 0));
  recording.frame(long_dlc);
  auto short_data = sheet_frames()[0];
  short_data.data(Bytes(2, 0));
  recording.frame(short_data);
  auto bad_boolean = teejet::bus_frame::serialize(sheet_frames()[0]);
  bad_boolean[32] = 0x07;  // `extended`: CDR booleans are 0 or 1
  recording.message(bad_boolean);
  recording.frame(sheet_frames()[0]);
  ScratchDir dir;
  write_bytes(dir.path() / "bad.mcap", recording.finish());
  const auto run = run_valve_decode({(dir.path() / "bad.mcap").string()});
  EXPECT_EQ(run.exit_code, 0);
  EXPECT_EQ(run.err, "");
  const auto lines = lines_of(run.out);
  ASSERT_EQ(lines.size(), 5u) << run.out;
  EXPECT_EQ(lines[0],
            R"j({"error":"the BusFrame sample does not deserialize: it ends early (3 bytes)",)j"
            R"("topic":"teejet/can/frame","sequence":1,"log_time":1700000002000000001})");
  EXPECT_EQ(lines[1], R"({"error":"dlc 9 is above 8","topic":"teejet/can/frame","sequence":2,)"
                      R"("log_time":1700000002000000002})");
  EXPECT_EQ(lines[2],
            R"({"error":"dlc 8 but 2 data bytes","topic":"teejet/can/frame","sequence":3,)"
            R"("log_time":1700000002000000003})");
  const auto bad = nlohmann::ordered_json::parse(lines[3]);
  EXPECT_TRUE(
      bad["error"].get<std::string>().starts_with("the BusFrame sample does not deserialize: "))
      << lines[3];
  EXPECT_EQ(bad["sequence"], 4);
  EXPECT_EQ(lines[4], kSheetLines[0]);
}

TEST(ValveDecodeMcap, NoFrameChannelIsAnErrorAndTheOtherFilesAreDecoded) {
  Recording recording("zstd", 1 << 20, /*with_frame_channel=*/false);
  ScratchDir dir;
  const auto path = (dir.path() / "positions.mcap").string();
  write_bytes(path, recording.finish());
  const auto good = (dir.path() / "good.mcap").string();
  write_bytes(good, record(sheet_frames()));
  const auto run = run_valve_decode({path, good});
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_EQ(run.err, "valve-decode: " + path + kNoFrameChannel);
  EXPECT_EQ(lines_of(run.out).size(), kSheetLines.size());
}

TEST(ValveDecodeMcap, TruncatedMidChunkDecodesTheCompleteChunksAndWarns) {
  Recording recording("zstd");
  const auto frames = sheet_frames();
  recording.frame(frames[0]);
  recording.frame(frames[1]);
  recording.flush();
  const auto first_chunk_end = recording.size();
  recording.frame(frames[2]);
  recording.frame(frames[3]);
  recording.flush();
  const auto second_chunk_end = recording.size();
  auto file = recording.finish();
  file.resize((first_chunk_end + second_chunk_end) / 2);
  ScratchDir dir;
  const auto path = (dir.path() / "killed.mcap").string();
  write_bytes(path, file);
  const auto run = run_valve_decode({path});
  EXPECT_EQ(run.exit_code, 0);
  expect_same_lines(run.out, kSheetLines[0] + "\n" + kSheetLines[1] + "\n");
  EXPECT_EQ(run.err, "valve-decode: " + path +
                         ": warning: incomplete recording, decoded up to where it ends: the file "
                         "ends inside a Chunk record at byte " +
                         std::to_string(first_chunk_end) +
                         " (not closed: the recorder stopped early?)\n")
      << "the second chunk starts where the first one's message indexes end";
}

TEST(ValveDecodeMcap, AWrongMagicIsCandumpTextWithAnErrorPerLine) {
  auto file = record(sheet_frames());
  file[0] = 'X';
  ScratchDir dir;
  const auto path = (dir.path() / "not-magic.mcap").string();
  write_bytes(path, file);
  const auto run = run_valve_decode({path});
  EXPECT_EQ(run.exit_code, 0);
  EXPECT_EQ(run.err, "");
  const auto lines = lines_of(run.out);
  ASSERT_FALSE(lines.empty());
  EXPECT_EQ(lines[0], R"j({"error":"timestamp must be in parentheses, e.g. (1700000000.000123)",)j"
                      R"("line":"XMCAP0"})");
  for (const auto& line : lines) {
    const auto json = nlohmann::ordered_json::parse(line, nullptr, false);
    ASSERT_FALSE(json.is_discarded()) << line;
    EXPECT_TRUE(json.contains("error") && json.contains("line")) << line;
  }
}

TEST(ValveDecodeMcap, ACrcFlipIsAnErrorNamingTheFileAndNothingOfItIsPrinted) {
  // Uncompressed, so that the flipped byte lands in the chunk's records as they are.
  auto file = record(sheet_frames(), "");
  const std::string gateway = "gw-left";
  const auto at = std::search(file.begin(), file.end(), gateway.begin(), gateway.end());
  ASSERT_NE(at, file.end());
  *at = 'G';
  ScratchDir dir;
  const auto path = (dir.path() / "flipped.mcap").string();
  write_bytes(path, file);
  const auto good = (dir.path() / "good.mcap").string();
  write_bytes(good, record(sheet_frames()));
  const auto run = run_valve_decode({path, good});
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_TRUE(run.err.starts_with("valve-decode: " + path + ": damaged MCAP file at byte "))
      << run.err;
  EXPECT_TRUE(run.err.ends_with(": a chunk's CRC does not match its records\n")) << run.err;
  EXPECT_EQ(lines_of(run.err).size(), 1u) << run.err;
  EXPECT_EQ(lines_of(run.out).size(), kSheetLines.size()) << "only the good file's lines";
}

TEST(ValveDecodeMcap, AFrameChannelThatIsNotCdrGivesAnErrorPerMessage) {
  auto sink = std::make_unique<mcap::MemorySink>();
  const auto* memory = sink.get();
  auto writer = mcap::Writer::create(std::move(sink), {.compression = ""});
  ASSERT_TRUE(writer.ok());
  const Bytes idl{'x'};
  const auto schema = (*writer)->add_schema("teejet::BusFrame", "omgidl", idl);
  const auto json = *(*writer)->add_channel(*schema, "teejet/can/frame", "json");
  const auto cdr = *(*writer)->add_channel(*schema, "teejet/can/frame", "cdr");
  ASSERT_TRUE((*writer)->write(json, 1, 5, 5, Bytes{'{', '}'}).ok());
  ASSERT_TRUE((*writer)->write(cdr, 1, 6, 6, teejet::bus_frame::serialize(sheet_frames()[0])).ok());
  ASSERT_TRUE((*writer)->finish().ok());
  ScratchDir dir;
  const auto path = (dir.path() / "json.mcap").string();
  write_bytes(path, memory->bytes());
  const auto run = run_valve_decode({path});
  EXPECT_EQ(run.exit_code, 0);
  EXPECT_EQ(run.err, "");
  expect_same_lines(run.out, R"({"error":"message encoding \"json\" is not cdr",)"
                             R"("topic":"teejet/can/frame","sequence":1,"log_time":5})"
                             "\n" +
                                 kSheetLines[0] + "\n");
}

TEST(ValveDecodeMcap, AFileOfOnlyTheMagicHasNoFrameChannel) {
  ScratchDir dir;
  const auto path = (dir.path() / "magic.mcap").string();
  write_bytes(path, Bytes(std::begin(mcap::kMagic), std::end(mcap::kMagic)));
  const auto run = run_valve_decode({path});
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_EQ(run.out, "");
  EXPECT_EQ(run.err, "valve-decode: " + path + kNoFrameChannel + "valve-decode: " + path +
                         ": warning: incomplete recording, decoded up to where it ends: the file "
                         "ends after its magic bytes\n");
}

TEST(ValveDecodeMcap, APipeNamedAsAFileIsReadOnce) {
  // /dev/stdin names the pipe: detection by the first line works without seeking back.
  const auto file = record(sheet_frames());
  const auto run = run_valve_decode({"/dev/stdin"}, std::string(file.begin(), file.end()));
  EXPECT_EQ(run.exit_code, 0);
  EXPECT_EQ(run.err, "");
  EXPECT_EQ(lines_of(run.out), kSheetLines);
}

TEST(ValveDecodeMcap, StandardInputIsCandumpTextOnly) {
  const auto file = record(sheet_frames());
  const auto run = run_valve_decode({}, std::string(file.begin(), file.end()));
  EXPECT_EQ(run.exit_code, 0);
  const auto lines = lines_of(run.out);
  ASSERT_FALSE(lines.empty());
  EXPECT_TRUE(lines[0].starts_with(R"({"error":)")) << lines[0];
}

TEST(ValveDecodeMcap, HelpExplainsTheMcapInput) {
  const auto run = run_valve_decode({"--help"});
  EXPECT_EQ(run.exit_code, 0);
  for (const char* text : {"MCAP", "teejet::BusFrame", "teejet/can/frame", R"("gw":)",
                           "standard input is always", "--record-frames"}) {
    EXPECT_NE(run.out.find(text), std::string::npos) << text;
  }
}

// Damage at every byte: a schema text of a few bytes keeps the files (and the run) small.
constexpr const char* kSmallIdl = "module teejet { struct BusFrame { uint32 id; }; };";

// In process, so that every damaged variant of a recording is cheap: decode_mcap itself.
struct Decoded {
  bool ok = false;
  std::string out;
  std::string err;
};
Decoded decode_in_process(const Bytes& file) {
  std::ostringstream out;
  std::ostringstream err;
  const bool ok = teejet::valve_decode::decode_mcap(file, "rec.mcap", out, err);
  return {ok, out.str(), err.str()};
}

void expect_json_lines(const std::string& out) {
  for (const auto& line : lines_of(out)) {
    EXPECT_TRUE(nlohmann::ordered_json::accept(line)) << line;
  }
}

TEST(ValveDecodeMcapDamage, EveryCutPrintsALeadingPartOfTheWholeOutput) {
  for (const std::string compression : {"zstd", ""}) {
    SCOPED_TRACE("compression \"" + compression + "\"");
    const auto file = record(sheet_frames(), compression, 64, kSmallIdl);
    const auto whole = decode_in_process(file);
    ASSERT_TRUE(whole.ok) << whole.err;
    ASSERT_EQ(lines_of(whole.out), kSheetLines);
    std::size_t complete_cuts = 0;
    for (std::size_t size = 0; size < file.size(); ++size) {
      const auto cut =
          decode_in_process(Bytes(file.begin(), file.begin() + static_cast<long>(size)));
      ASSERT_TRUE(whole.out.starts_with(cut.out)) << size << " bytes: " << cut.out;
      EXPECT_TRUE(cut.out.empty() || cut.out.ends_with('\n')) << size << " bytes";
      EXPECT_FALSE(cut.err.empty()) << size << " bytes: a cut file is never silently whole";
      if (cut.ok && cut.out == whole.out) ++complete_cuts;
    }
    // The summary and footer follow the last chunk: cut there, every frame is still printed.
    EXPECT_GT(complete_cuts, 0u);
  }
}

TEST(ValveDecodeMcapDamage, EveryByteFlipIsAnErrorOrJsonLinesNeverACrash) {
  for (const std::string compression : {"zstd", "lz4", ""}) {
    SCOPED_TRACE("compression \"" + compression + "\"");
    const auto file = record(sheet_frames(), compression, 64, kSmallIdl);
    std::size_t refused = 0;
    for (std::size_t at = 0; at < file.size(); ++at) {
      auto flipped = file;
      flipped[at] ^= 0xFF;
      const auto decoded = decode_in_process(flipped);
      expect_json_lines(decoded.out);
      if (!decoded.ok) {
        ++refused;
        EXPECT_TRUE(decoded.err.starts_with("valve-decode: rec.mcap: ")) << decoded.err;
      }
    }
    EXPECT_GT(refused, 0u);
  }
}

}  // namespace
