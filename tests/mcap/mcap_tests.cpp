// The MCAP writer and reader against each other and against damage. The independent check (a
// reader nobody here wrote) is the npm @mcap/core test in tests/record.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "teejet/mcap/reader.hpp"
#include "teejet/mcap/writer.hpp"

namespace teejet::mcap {
namespace {

Bytes bytes_of(const std::string& text) { return Bytes(text.begin(), text.end()); }

struct Recorded {
  Bytes file;
  std::vector<Message> messages;
};

// Two channels of one schema, `count` messages alternating between them.
Recorded record(const std::string& compression, std::size_t chunk_size, int count,
                bool finish = true) {
  auto sink = std::make_unique<MemorySink>();
  MemorySink* memory = sink.get();
  auto writer =
      Writer::create(std::move(sink), {.compression = compression, .chunk_size = chunk_size});
  EXPECT_TRUE(writer.ok());
  const Bytes idl = bytes_of("module teejet { struct ValvePosition { uint32 serial; }; };");
  const auto schema = (*writer)->add_schema("teejet::ValvePosition", "omgidl", idl);
  const auto position = (*writer)->add_channel(*schema, "teejet/valve/position", "cdr",
                                               {{"reliability", "reliable"}});
  const auto presence = (*writer)->add_channel(*schema, "teejet/valve/presence", "cdr");
  Recorded out;
  for (int i = 0; i < count; ++i) {
    const std::uint64_t at = 1'700'000'000'000'000'000ull + static_cast<std::uint64_t>(i) * 1000;
    Message message{static_cast<std::uint16_t>(i % 2 ? *presence : *position),
                    static_cast<std::uint32_t>(i), at, at - 50,
                    Bytes(static_cast<std::size_t>(8 + i % 5), static_cast<std::uint8_t>(i))};
    EXPECT_TRUE((*writer)
                    ->write(message.channel_id, message.sequence, message.log_time,
                            message.publish_time, message.data)
                    .ok());
    out.messages.push_back(message);
  }
  if (finish) {
    EXPECT_TRUE((*writer)->finish().ok());
  } else {
    EXPECT_TRUE((*writer)->flush().ok());
  }
  out.file = memory->bytes();
  return out;
}

std::vector<Message> read_all(const Bytes& file, Contents* contents_out = nullptr) {
  std::vector<Message> read;
  auto contents = read_messages(file, [&](const Channel&, const Message& m) { read.push_back(m); });
  EXPECT_TRUE(contents.ok()) << contents.error().reason;
  if (contents && contents_out) *contents_out = *contents;
  return read;
}

class EveryCompression : public ::testing::TestWithParam<std::string> {};

TEST_P(EveryCompression, WhatIsWrittenIsReadBackInOrder) {
  const Recorded recorded = record(GetParam(), 256, 200);
  Contents contents;
  EXPECT_EQ(read_all(recorded.file, &contents), recorded.messages);
  EXPECT_EQ(contents.incomplete, "");
  EXPECT_EQ(contents.messages, 200u);
  EXPECT_GT(contents.chunks, 10u);
  EXPECT_EQ(contents.header.library, "teejet-record");
  ASSERT_EQ(contents.channels.size(), 2u);
  EXPECT_EQ(contents.channels.at(0).topic, "teejet/valve/position");
  EXPECT_EQ(contents.channels.at(0).metadata.at("reliability"), "reliable");
  EXPECT_EQ(contents.schemas.at(1).encoding, "omgidl");
}

TEST_P(EveryCompression, TheSummaryCountsEveryMessageAndIndexesEveryChunk) {
  const Recorded recorded = record(GetParam(), 256, 200);
  auto summary = read_summary(recorded.file);
  ASSERT_TRUE(summary.ok()) << summary.error().reason;
  ASSERT_TRUE(summary->has_value());
  const Summary& s = **summary;
  EXPECT_EQ(s.statistics.message_count, 200u);
  EXPECT_EQ(s.statistics.channel_message_counts.at(0), 100u);
  EXPECT_EQ(s.statistics.channel_message_counts.at(1), 100u);
  EXPECT_EQ(s.statistics.message_start_time, recorded.messages.front().log_time);
  EXPECT_EQ(s.statistics.message_end_time, recorded.messages.back().log_time);
  EXPECT_EQ(s.statistics.chunk_count, s.chunk_indexes.size());
  EXPECT_EQ(s.channels.size(), 2u);
  for (const ChunkIndex& index : s.chunk_indexes) {
    EXPECT_EQ(recorded.file[index.chunk_start_offset], static_cast<std::uint8_t>(Opcode::kChunk));
    for (const auto& [channel, offset] : index.message_index_offsets) {
      EXPECT_EQ(recorded.file[offset], static_cast<std::uint8_t>(Opcode::kMessageIndex));
    }
    EXPECT_EQ(index.compression, GetParam());
  }
}

INSTANTIATE_TEST_SUITE_P(Mcap, EveryCompression, ::testing::Values("", "zstd", "lz4"),
                         [](const ::testing::TestParamInfo<std::string>& param) {
                           return param.param.empty() ? std::string("none") : param.param;
                         });

TEST(McapReader, AFileCutAnywhereReadsUpToItsLastCompleteChunkAndNeverCrashes) {
  const Recorded recorded = record("zstd", 300, 60, /*finish=*/false);
  for (std::size_t size = 0; size < recorded.file.size(); ++size) {
    const Bytes cut(recorded.file.begin(), recorded.file.begin() + static_cast<long>(size));
    std::vector<Message> read;
    auto contents =
        read_messages(cut, [&](const Channel&, const Message& m) { read.push_back(m); });
    if (size < 8) {
      EXPECT_FALSE(contents.ok()) << size;
      continue;
    }
    ASSERT_TRUE(contents.ok()) << size << ": " << contents.error().reason;
    EXPECT_NE(contents->incomplete, "") << size;
    ASSERT_LE(read.size(), recorded.messages.size());
    EXPECT_TRUE(std::equal(read.begin(), read.end(), recorded.messages.begin())) << size;
  }
  // Flushed but never finished: every message is there, and the reader says it was not closed.
  Contents contents;
  EXPECT_EQ(read_all(recorded.file, &contents), recorded.messages);
  EXPECT_NE(contents.incomplete.find("not closed"), std::string::npos) << contents.incomplete;
  auto summary = read_summary(recorded.file);
  ASSERT_TRUE(summary.ok());
  EXPECT_FALSE(summary->has_value());
}

TEST(McapReader, ADamagedChunkIsAnErrorNamingItsOffset) {
  Recorded recorded = record("", 100000, 20);
  auto summary = read_summary(recorded.file);
  ASSERT_TRUE(summary.ok() && summary->has_value());
  const ChunkIndex& chunk = (*summary)->chunk_indexes.at(0);
  recorded.file[chunk.chunk_start_offset + chunk.chunk_length - 3] ^= 0x01;  // a message byte
  auto contents = read_messages(recorded.file, {});
  ASSERT_FALSE(contents.ok());
  EXPECT_EQ(contents.error().reason, "damaged MCAP file at byte " +
                                         std::to_string(chunk.chunk_start_offset) +
                                         ": a chunk's CRC does not match its records");
}

TEST(McapReader, ADamagedSummaryIsAnError) {
  Recorded recorded = record("zstd", 100000, 20);
  recorded.file[recorded.file.size() - 8 - 29 - 5] ^= 0x40;  // inside the summary offsets
  auto summary = read_summary(recorded.file);
  ASSERT_FALSE(summary.ok());
  EXPECT_NE(summary.error().reason.find("the summary's CRC does not match"), std::string::npos);
}

// Little-endian fields of a file, for the tests that damage one on purpose.
std::uint64_t field_at(const Bytes& file, std::size_t at, std::size_t size) {
  std::uint64_t value = 0;
  for (std::size_t i = 0; i < size; ++i) value |= std::uint64_t{file.at(at + i)} << (8 * i);
  return value;
}
void set_field(Bytes& file, std::size_t at, std::size_t size, std::uint64_t value) {
  for (std::size_t i = 0; i < size; ++i) {
    file.at(at + i) = static_cast<std::uint8_t>(value >> (8 * i));
  }
}

// The Footer (https://mcap.dev/spec#footer-op0x02) right before the closing magic: opcode,
// length, summary_start, summary_offset_start, summary_crc.
struct FooterAt {
  std::size_t record, summary_start, summary_offset_start, summary_crc;
};
FooterAt footer_of(const Bytes& file) {
  const std::size_t record = file.size() - 8 - (1 + 8 + 8 + 8 + 4);
  return {record, record + 9, record + 17, record + 25};
}

// Where the first summary record of `opcode` starts.
std::size_t summary_record(const Bytes& file, Opcode opcode) {
  const auto footer = footer_of(file);
  std::size_t at = field_at(file, footer.summary_start, 8);
  while (file.at(at) != static_cast<std::uint8_t>(opcode)) at += 9 + field_at(file, at + 1, 8);
  return at;
}

std::string damaged_at(std::size_t at, const std::string& what) {
  return "damaged MCAP file at byte " + std::to_string(at) + ": " + what;
}

TEST(McapReader, TheFooterIsCheckedBeforeTheSummaryIsRead) {
  const Recorded recorded = record("zstd", 100000, 20);
  const auto footer = footer_of(recorded.file);
  {
    Bytes file = recorded.file;
    file[footer.record] = static_cast<std::uint8_t>(Opcode::kDataEnd);
    EXPECT_EQ(read_summary(file).error().reason,
              damaged_at(footer.record, "the record before the closing magic is not a Footer"));
  }
  {
    Bytes file = recorded.file;
    set_field(file, footer.summary_start, 8, footer.record + 1);
    EXPECT_EQ(read_summary(file).error().reason,
              damaged_at(footer.record, "the footer points outside the file"));
  }
  {
    Bytes file = recorded.file;
    set_field(file, footer.summary_offset_start, 8, field_at(file, footer.summary_start, 8) - 1);
    EXPECT_EQ(read_summary(file).error().reason,
              damaged_at(footer.record, "the footer points outside the file"));
  }
  {
    Bytes file = recorded.file;
    set_field(file, footer.summary_start, 8, 0);  // a writer that wrote no summary
    const auto summary = read_summary(file);
    ASSERT_TRUE(summary.ok()) << summary.error().reason;
    EXPECT_FALSE(summary->has_value());
  }
  {
    Bytes file = recorded.file;
    file.back() ^= 0x01;  // no closing magic: not closed
    const auto summary = read_summary(file);
    ASSERT_TRUE(summary.ok()) << summary.error().reason;
    EXPECT_FALSE(summary->has_value());
  }
}

TEST(McapReader, ASummaryRecordThatDoesNotParseNamesItsOffset) {
  Recorded recorded = record("zstd", 100, 20);
  const auto footer = footer_of(recorded.file);
  set_field(recorded.file, footer.summary_crc, 4, 0);  // no CRC: the records themselves are read
  {
    Bytes file = recorded.file;
    const std::size_t statistics = summary_record(file, Opcode::kStatistics);
    set_field(file, statistics + 1, 8, 8);  // a message count and nothing more
    EXPECT_EQ(read_summary(file).error().reason,
              damaged_at(statistics, "the Statistics record does not parse"));
  }
  {
    Bytes file = recorded.file;
    const std::size_t index = summary_record(file, Opcode::kChunkIndex);
    set_field(file, index + 9 + 16, 8, file.size());  // chunk_start_offset
    EXPECT_EQ(read_summary(file).error().reason,
              damaged_at(index, "a Chunk Index points outside the file"));
  }
  {
    Bytes file = recorded.file;
    const std::size_t schema = summary_record(file, Opcode::kSchema);
    set_field(file, schema + 1, 8, file.size());
    EXPECT_EQ(read_summary(file).error().reason,
              damaged_at(schema, "a summary record is cut short"));
  }
  {
    Bytes file = recorded.file;
    const std::size_t channel = summary_record(file, Opcode::kChannel);
    set_field(file, channel + 9 + 4, 4, 1000);  // the topic's length
    EXPECT_EQ(read_summary(file).error().reason,
              damaged_at(channel, "a Channel record does not parse"));
  }
  const auto summary = read_summary(recorded.file);
  ASSERT_TRUE(summary.ok()) << summary.error().reason;
  ASSERT_TRUE(summary->has_value());
  EXPECT_EQ((*summary)->statistics.message_count, 20u);
  EXPECT_EQ((*summary)->channels.size(), 2u);
  EXPECT_EQ((*summary)->schemas.size(), 1u);
  EXPECT_GT((*summary)->chunk_indexes.size(), 1u);
}

TEST(McapReader, ForeignFilesAreRefusedClearly) {
  EXPECT_EQ(read_messages(bytes_of("(1700000000.000000) vcan0 18EFD5D8#0203\n"), {}).error().reason,
            "not an MCAP file: wrong magic bytes");
  EXPECT_EQ(read_messages(bytes_of("MCAP"), {}).error().reason,
            "not an MCAP file: shorter than its magic bytes");
}

TEST(McapReader, AnUnknownCompressionIsAnError) {
  Recorded recorded = record("lz4", 100000, 5);
  // "lz4" → "lz5": the chunk's compression string.
  const std::string needle = "lz4";
  auto at = std::search(recorded.file.begin(), recorded.file.end(), needle.begin(), needle.end());
  ASSERT_NE(at, recorded.file.end());
  at[2] = '5';
  auto contents = read_messages(recorded.file, {});
  ASSERT_FALSE(contents.ok());
  EXPECT_NE(contents.error().reason.find("unknown chunk compression 'lz5'"), std::string::npos)
      << contents.error().reason;
}

// Found by the fuzz target mcap_read: a damaged size field made the reader allocate 4 GB.
TEST(McapReader, AChunkClaimingGigabytesIsRefusedBeforeAnythingIsAllocated) {
  for (const std::string compression : {"zstd", "lz4"}) {
    Recorded recorded = record(compression, 100000, 5);
    auto summary = read_summary(recorded.file);
    ASSERT_TRUE(summary.ok() && summary->has_value());
    // The chunk's uncompressed_size: after opcode, length and the two times.
    const std::size_t field = (*summary)->chunk_indexes.at(0).chunk_start_offset + 1 + 8 + 16;
    recorded.file[field + 4] = 0xFB;  // 4,211,081,216 + the real size
    auto contents = read_messages(recorded.file, {});
    ASSERT_FALSE(contents.ok()) << compression;
    EXPECT_NE(contents.error().reason.find("more than the 256 MiB a chunk may hold"),
              std::string::npos)
        << contents.error().reason;
  }
}

TEST(McapWriter, RefusesWhatWouldMakeABadFile) {
  EXPECT_FALSE(Writer::create(std::make_unique<MemorySink>(), {.compression = "gzip"}).ok());
  auto writer = Writer::create(std::make_unique<MemorySink>());
  ASSERT_TRUE(writer.ok());
  EXPECT_EQ((*writer)->add_channel(3, "t", "cdr").error().reason, "channel t: no schema 3");
  EXPECT_EQ((*writer)->write(0, 0, 0, 0, {}).error().reason, "no channel 0");
  ASSERT_TRUE((*writer)->finish().ok());
  EXPECT_EQ((*writer)->add_channel(0, "t", "cdr").error().reason, "the recording is finished");
}

}  // namespace
}  // namespace teejet::mcap
