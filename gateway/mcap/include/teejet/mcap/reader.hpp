#pragma once

// Reads MCAP files: front to back (every message in file order, as a replay needs it), and the
// summary at the end (what --info shows, without reading the messages). Reads from a Source: a
// file, one record at a time (memory bounded by the largest record, a chunk of about 1 MiB, never
// by the file), or bytes in memory; never outside them. A damaged file (wrong magic, a CRC that
// does not match, a record that does not parse, a message before its channel) is an Error naming
// the byte offset; a file that merely ends early (a recorder that was killed) reads up to its
// last complete record and says so.

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>

#include "teejet/core/result.hpp"
#include "teejet/mcap/records.hpp"

namespace teejet::mcap {

struct Contents {
  Header header;
  std::map<std::uint16_t, Schema> schemas;
  std::map<std::uint16_t, Channel> channels;
  std::uint64_t messages = 0;
  std::uint64_t chunks = 0;
  // Empty when the file is complete (Data End, summary, footer, magic); otherwise why it is not,
  // e.g. "the file ends inside a Chunk record at byte 81234 (not closed: the recorder stopped
  // early?)". Everything before that point was read.
  std::string incomplete;
};

using MessageVisitor = std::function<void(const Channel&, const Message&)>;

// Where the reader gets its bytes.
class Source {
 public:
  virtual ~Source() = default;
  virtual std::uint64_t size() const = 0;
  // `length` bytes from `offset`, both within size(); an Error when they cannot be read or held.
  virtual Result<Bytes> read(std::uint64_t offset, std::uint64_t length) = 0;
};

// Bytes already in memory (standard input, a test, the fuzzer).
class MemorySource final : public Source {
 public:
  explicit MemorySource(std::span<const std::uint8_t> bytes) : bytes_(bytes) {}
  std::uint64_t size() const override { return bytes_.size(); }
  Result<Bytes> read(std::uint64_t offset, std::uint64_t length) override;

 private:
  std::span<const std::uint8_t> bytes_;
};

// A regular file, read piece by piece. Anything else (a FIFO, a device such as /dev/zero, a
// directory) is refused at open without blocking: a FIFO without a writer would hang open().
class FileSource final : public Source {
 public:
  // Errors say what went wrong, not which file: the caller names it.
  static Result<std::unique_ptr<FileSource>> open(const std::string& path);
  ~FileSource() override;
  FileSource(const FileSource&) = delete;
  FileSource& operator=(const FileSource&) = delete;
  std::uint64_t size() const override { return size_; }
  Result<Bytes> read(std::uint64_t offset, std::uint64_t length) override;

 private:
  FileSource(int fd, std::uint64_t size) : fd_(fd), size_(size) {}
  int fd_;
  std::uint64_t size_;
};

// Reads every message in file order; `visit` may be empty (a check of the whole file).
Result<Contents> read_messages(Source& file, const MessageVisitor& visit);
Result<Contents> read_messages(std::span<const std::uint8_t> file, const MessageVisitor& visit);

struct Summary {
  Statistics statistics;
  std::map<std::uint16_t, Schema> schemas;
  std::map<std::uint16_t, Channel> channels;
  std::vector<ChunkIndex> chunk_indexes;
};

// The summary section through the footer. nullopt when the file has no summary (it was not
// closed, or its writer wrote none): read_messages() still reads such a file.
Result<std::optional<Summary>> read_summary(Source& file);
Result<std::optional<Summary>> read_summary(std::span<const std::uint8_t> file);

}  // namespace teejet::mcap
