#pragma once

// The record layouts of https://mcap.dev/spec (major version 0), each written down once: the
// fields of a record's content in the spec's order, shared by the writer (put_*: the whole record,
// opcode and length included) and the reader (parse_*: a record's content; never reads outside
// it). A content whose fields are not all there is an Error naming the record ("a Schema record
// does not parse"); the reader adds where it is. What the fields must mean (offsets inside the
// file, known compressions) is the reader's to check.

#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "bytes.hpp"
#include "teejet/core/result.hpp"
#include "teejet/mcap/records.hpp"

namespace teejet::mcap {

inline constexpr std::size_t kMagicSize = sizeof kMagic;
// Every record begins with its opcode (1 byte) and the length of its content (8 bytes).
inline constexpr std::size_t kRecordPrefixSize = 1 + 8;

// Footer (op 0x02): the last record, right before the closing magic, with a fixed size.
struct Footer {
  static constexpr std::uint64_t kContentSize = 8 + 8 + 4;
  static constexpr std::size_t kRecordSize = kRecordPrefixSize + kContentSize;
  // The summary CRC covers the summary section, the Summary Offsets and the footer's own bytes
  // up to the CRC.
  static constexpr std::size_t kBytesBeforeCrc = kRecordSize - 4;

  std::uint64_t summary_start = 0;         // 0: the file has no summary
  std::uint64_t summary_offset_start = 0;  // 0: no Summary Offset records
  std::uint32_t summary_crc = 0;           // 0: not computed
};
// Appends the Footer to `summary`, the bytes written from summary_start on: its CRC is theirs.
void put_footer(Bytes& summary, std::uint64_t summary_start, std::uint64_t summary_offset_start);
// `record`: the whole record, refused unless it is a Footer of the spec's length.
Result<Footer> parse_footer(std::span<const std::uint8_t> record);

// Header (op 0x01).
void put_header(ByteBuilder& out, const Header& header);
Result<Header> parse_header(std::span<const std::uint8_t> content);

// Schema (op 0x03) and Channel (op 0x04).
void put_schema(ByteBuilder& out, const Schema& schema);
Result<Schema> parse_schema(std::span<const std::uint8_t> content);
void put_channel(ByteBuilder& out, const Channel& channel);
Result<Channel> parse_channel(std::span<const std::uint8_t> content);

// Message (op 0x05): its data is the rest of the content.
void put_message(ByteBuilder& out, std::uint16_t channel_id, std::uint32_t sequence,
                 std::uint64_t log_time, std::uint64_t publish_time,
                 std::span<const std::uint8_t> data);
Result<Message> parse_message(std::span<const std::uint8_t> content);

// Chunk (op 0x06): the records of the data section, compressed.
struct ChunkRecord {
  std::uint64_t message_start_time = 0;
  std::uint64_t message_end_time = 0;
  std::uint64_t uncompressed_size = 0;
  std::uint32_t uncompressed_crc = 0;  // 0: not computed
  std::string compression;             // "", "zstd", "lz4"
  std::span<const std::uint8_t> records;
};
void put_chunk(ByteBuilder& out, const ChunkRecord& chunk);
// `records` then lies inside `content`; records longer than the chunk are refused.
Result<ChunkRecord> parse_chunk(std::span<const std::uint8_t> content);

// Message Index (op 0x07): (log time, offset in the uncompressed chunk) of a channel's messages.
void put_message_index(ByteBuilder& out, std::uint16_t channel_id,
                       const std::vector<std::pair<std::uint64_t, std::uint64_t>>& entries);

// Chunk Index (op 0x08) and Statistics (op 0x0B), in the summary.
void put_chunk_index(ByteBuilder& out, const ChunkIndex& index);
Result<ChunkIndex> parse_chunk_index(std::span<const std::uint8_t> content);
void put_statistics(ByteBuilder& out, const Statistics& statistics);
Result<Statistics> parse_statistics(std::span<const std::uint8_t> content);

// Summary Offset (op 0x0E): where the summary's group of `group` records starts and its length.
void put_summary_offset(ByteBuilder& out, Opcode group, std::uint64_t start, std::uint64_t length);

// Data End (op 0x0F): the CRC of the data section.
void put_data_end(ByteBuilder& out, std::uint32_t data_crc);

}  // namespace teejet::mcap
