#pragma once

// Writes an MCAP file (https://mcap.dev/spec) as teejet-record needs it: messages in chunks
// (zstd, lz4 or none), a Message Index per channel after each chunk, and at the end a summary
// (schemas, channels, statistics, chunk indexes), summary offsets and the footer, so that readers
// can seek. Schema and Channel records go into the data section when they are added, before any
// message of theirs. Every chunk is handed to the operating system when it is closed: a process
// that dies loses at most the open chunk, and what was written stays readable from the start.
//
// Not thread-safe: one writer thread (the recorder's) owns it.

#include <cstdint>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "teejet/core/result.hpp"
#include "teejet/mcap/records.hpp"

namespace teejet::mcap {

// Where the bytes go: a file, or memory in tests.
class Sink {
 public:
  virtual ~Sink() = default;
  virtual Status write(std::span<const std::uint8_t> bytes) = 0;
};

// Creates (or truncates) a file; errors name the path and the system's reason.
Result<std::unique_ptr<Sink>> open_file_sink(const std::string& path);

class MemorySink final : public Sink {
 public:
  Status write(std::span<const std::uint8_t> bytes) override {
    bytes_.insert(bytes_.end(), bytes.begin(), bytes.end());
    return {};
  }
  const Bytes& bytes() const { return bytes_; }

 private:
  Bytes bytes_;
};

struct WriterOptions {
  std::string compression = "zstd";  // "zstd", "lz4" or "" (none)
  // A chunk is closed once its records reach this many (uncompressed) bytes.
  std::size_t chunk_size = 1 << 20;
  std::string profile;  // the Header's profile: "" (none of the well-known ones)
  std::string library = "teejet-record";
};

class Writer {
 public:
  // Writes the magic and the Header. Refuses an unknown compression.
  static Result<std::unique_ptr<Writer>> create(std::unique_ptr<Sink> sink,
                                                WriterOptions options = {});
  ~Writer();
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;

  Result<std::uint16_t> add_schema(const std::string& name, const std::string& encoding,
                                   std::span<const std::uint8_t> data);
  // schema_id 0: a channel without a schema.
  Result<std::uint16_t> add_channel(std::uint16_t schema_id, const std::string& topic,
                                    const std::string& message_encoding,
                                    const std::map<std::string, std::string>& metadata = {});
  // A message on a channel added before; closes the chunk when it is full.
  Status write(std::uint16_t channel_id, std::uint32_t sequence, std::uint64_t log_time,
               std::uint64_t publish_time, std::span<const std::uint8_t> data);
  // Closes the open chunk now (e.g. once a second, so that a crash loses little).
  Status flush();
  // Closes the open chunk and writes Data End, the summary and the footer. Afterwards the
  // writer refuses everything. Idempotent.
  Status finish();

  std::uint64_t bytes_written() const { return position_; }
  std::uint64_t messages() const { return statistics_.message_count; }
  const std::map<std::uint16_t, std::uint64_t>& messages_per_channel() const {
    return statistics_.channel_message_counts;
  }

 private:
  Writer(std::unique_ptr<Sink> sink, WriterOptions options);
  Status emit(const Bytes& bytes, bool data_section);
  Status close_chunk();

  std::unique_ptr<Sink> sink_;
  WriterOptions options_;
  std::uint64_t position_ = 0;
  std::uint32_t data_crc_ = 0;  // of every byte from the magic up to Data End
  bool finished_ = false;
  Status failed_;  // the first write error: every later call returns it

  std::vector<Schema> schemas_;
  std::vector<Channel> channels_;
  std::vector<ChunkIndex> chunk_indexes_;
  Statistics statistics_;

  // The open chunk: its records, their times, and per channel (log_time, offset) of each.
  Bytes chunk_;
  std::uint64_t chunk_start_time_ = 0, chunk_end_time_ = 0;
  std::map<std::uint16_t, std::vector<std::pair<std::uint64_t, std::uint64_t>>> chunk_index_;
};

}  // namespace teejet::mcap
