#pragma once

// The records of an MCAP file (https://mcap.dev/spec, major version 0) that teejet-record writes
// and its readers understand: the values, with no I/O. Multi-byte integers are little-endian on
// disk; times are nanoseconds since the Unix epoch.

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace teejet::mcap {

using Bytes = std::vector<std::uint8_t>;

inline constexpr std::uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};

enum class Opcode : std::uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kAttachment = 0x09,
  kAttachmentIndex = 0x0A,
  kStatistics = 0x0B,
  kMetadata = 0x0C,
  kMetadataIndex = 0x0D,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

// "Schema", "Chunk", ... ; "opcode 0x42" for one this file does not know.
std::string opcode_name(std::uint8_t opcode);

struct Header {
  std::string profile;
  std::string library;
};

struct Schema {
  std::uint16_t id = 0;  // never 0
  std::string name;      // e.g. "teejet::ValvePosition"
  std::string encoding;  // e.g. "omgidl"
  Bytes data;            // e.g. the IDL text
  friend bool operator==(const Schema&, const Schema&) = default;
};

struct Channel {
  std::uint16_t id = 0;
  std::uint16_t schema_id = 0;  // 0: no schema
  std::string topic;
  std::string message_encoding;  // e.g. "cdr"
  std::map<std::string, std::string> metadata;
  friend bool operator==(const Channel&, const Channel&) = default;
};

struct Message {
  std::uint16_t channel_id = 0;
  std::uint32_t sequence = 0;
  std::uint64_t log_time = 0;      // when it was recorded
  std::uint64_t publish_time = 0;  // when it was published (log_time when unknown)
  Bytes data;
  friend bool operator==(const Message&, const Message&) = default;
};

struct ChunkIndex {
  std::uint64_t message_start_time = 0;
  std::uint64_t message_end_time = 0;
  std::uint64_t chunk_start_offset = 0;
  std::uint64_t chunk_length = 0;  // the whole record: opcode, length, content
  std::map<std::uint16_t, std::uint64_t> message_index_offsets;
  std::uint64_t message_index_length = 0;
  std::string compression;
  std::uint64_t compressed_size = 0;
  std::uint64_t uncompressed_size = 0;
};

struct Statistics {
  std::uint64_t message_count = 0;
  std::uint16_t schema_count = 0;
  std::uint32_t channel_count = 0;
  std::uint32_t attachment_count = 0;
  std::uint32_t metadata_count = 0;
  std::uint32_t chunk_count = 0;
  std::uint64_t message_start_time = 0;
  std::uint64_t message_end_time = 0;
  std::map<std::uint16_t, std::uint64_t> channel_message_counts;
};

}  // namespace teejet::mcap
