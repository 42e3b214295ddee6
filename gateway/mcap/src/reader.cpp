#include "teejet/mcap/reader.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <new>

#include "bytes.hpp"
#include "compression.hpp"
#include "layouts.hpp"

namespace teejet::mcap {

std::string opcode_name(std::uint8_t opcode) {
  static constexpr const char* kNames[] = {nullptr,      "Header",           "Footer",
                                           "Schema",     "Channel",          "Message",
                                           "Chunk",      "Message Index",    "Chunk Index",
                                           "Attachment", "Attachment Index", "Statistics",
                                           "Metadata",   "Metadata Index",   "Summary Offset",
                                           "Data End"};
  if (opcode >= 1 && opcode <= 0x0F) return kNames[opcode];
  char text[24];
  std::snprintf(text, sizeof text, "opcode 0x%02x", opcode);
  return text;
}

namespace {

Error damaged(std::uint64_t offset, const std::string& what) {
  return Error{ErrorCode::kInvalidValue,
               "damaged MCAP file at byte " + std::to_string(offset) + ": " + what};
}

bool has_magic(std::span<const std::uint8_t> bytes) {
  return bytes.size() >= kMagicSize &&
         std::equal(bytes.begin(), bytes.begin() + kMagicSize, kMagic);
}

// One pass over a sequence of records (the file's data section, or a chunk's records).
class RecordWalker {
 public:
  RecordWalker(Contents& contents, const MessageVisitor& visit)
      : contents_(contents), visit_(visit) {}

  // A chunk's records, which must all be complete; `base` is the chunk's offset in the file.
  Status walk_chunk(std::span<const std::uint8_t> bytes, std::uint64_t base) {
    ByteReader in(bytes);
    while (in.remaining() > 0) {
      const std::uint64_t at = base + in.position();
      const auto opcode = in.u8();
      const auto length = in.u64();
      if (!length) return damaged(at, "a chunk's records end inside a record header");
      const auto content = in.take(*length);
      if (!content) {
        return damaged(at, "a chunk's records end inside a " + opcode_name(*opcode) + " record");
      }
      auto handled = handle(*opcode, *content, at, true);
      if (!handled) return handled.error();
    }
    return {};
  }

  // The file's data section from `start`, record by record: only the records read_messages
  // handles are read (indexes and attachments are stepped over), so memory is bounded by the
  // largest of those, not by the file. `end` is where the records read end.
  Result<bool> walk(Source& file, std::uint64_t start, std::uint64_t& end) {
    const std::uint64_t size = file.size();
    end = start;
    for (std::uint64_t at = start; at < size;) {
      if (size - at < kRecordPrefixSize) return cut_short_file(at, "a record header");
      auto prefix = file.read(at, kRecordPrefixSize);
      if (!prefix) return prefix.error();
      ByteReader in(*prefix);
      const std::uint8_t opcode = *in.u8();
      const std::uint64_t length = *in.u64();
      if (length > size - at - kRecordPrefixSize) {
        return cut_short_file(at, "a " + opcode_name(opcode) + " record");
      }
      Result<bool> handled = true;
      if (read_by_walker(opcode)) {
        auto content = file.read(at + kRecordPrefixSize, length);
        if (!content) return content.error();
        handled = handle(opcode, *content, at, false);
      } else {
        handled = handle(opcode, {}, at, false);
      }
      if (!handled) return handled.error();
      at += kRecordPrefixSize + length;
      end = at;
      if (!*handled) return false;  // Data End: the data section is over
    }
    return true;
  }

 private:
  static bool read_by_walker(std::uint8_t opcode) {
    switch (static_cast<Opcode>(opcode)) {
      case Opcode::kSchema:
      case Opcode::kChannel:
      case Opcode::kMessage:
      case Opcode::kChunk:
        return true;
      default:
        return false;
    }
  }

  Result<bool> cut_short_file(std::uint64_t at, const std::string& what) {
    contents_.incomplete = "the file ends inside " + what + " at byte " + std::to_string(at) +
                           " (not closed: the recorder stopped early?)";
    return false;
  }

  // false: Data End reached.
  Result<bool> handle(std::uint8_t opcode, std::span<const std::uint8_t> content, std::uint64_t at,
                      bool in_chunk) {
    switch (static_cast<Opcode>(opcode)) {
      case Opcode::kSchema: {
        auto schema = parse_schema(content);
        if (!schema) return damaged(at, schema.error().reason);
        if (schema->id == 0) return true;  // the spec: readers ignore it
        const auto [it, added] = contents_.schemas.emplace(schema->id, *schema);
        if (!added && !(it->second == *schema)) {
          return damaged(at,
                         "schema " + std::to_string(schema->id) + " is defined twice, differently");
        }
        return true;
      }
      case Opcode::kChannel: {
        auto channel = parse_channel(content);
        if (!channel) return damaged(at, channel.error().reason);
        if (channel->schema_id != 0 && !contents_.schemas.count(channel->schema_id)) {
          return damaged(at, "channel " + channel->topic + " refers to schema " +
                                 std::to_string(channel->schema_id) + ", which is not defined");
        }
        const auto [it, added] = contents_.channels.emplace(channel->id, *channel);
        if (!added && !(it->second == *channel)) {
          return damaged(
              at, "channel " + std::to_string(channel->id) + " is defined twice, differently");
        }
        return true;
      }
      case Opcode::kMessage: {
        const auto message = parse_message(content);
        if (!message) return damaged(at, message.error().reason);
        const auto channel = contents_.channels.find(message->channel_id);
        if (channel == contents_.channels.end()) {
          return damaged(at, "a message on channel " + std::to_string(message->channel_id) +
                                 " comes before that channel's record");
        }
        ++contents_.messages;
        if (visit_) visit_(channel->second, *message);
        return true;
      }
      case Opcode::kChunk:
        if (in_chunk) return damaged(at, "a chunk inside a chunk");
        return chunk(content, at);
      case Opcode::kDataEnd:
        if (in_chunk) return damaged(at, "Data End inside a chunk");
        return false;
      case Opcode::kHeader:
      case Opcode::kFooter:
        return damaged(at, "a " + opcode_name(opcode) + " record in the data section");
      default:
        // Indexes, attachments, metadata and records of later versions or extensions.
        return true;
    }
  }

  Result<bool> chunk(std::span<const std::uint8_t> content, std::uint64_t at) {
    const auto chunk = parse_chunk(content);
    if (!chunk) return damaged(at, chunk.error().reason);
    auto data = decompress(chunk->compression, chunk->records, chunk->uncompressed_size);
    if (!data) return damaged(at, data.error().reason);
    if (chunk->uncompressed_crc != 0 && crc32(*data) != chunk->uncompressed_crc) {
      return damaged(at, "a chunk's CRC does not match its records");
    }
    ++contents_.chunks;
    if (auto walked = walk_chunk(*data, at); !walked) return walked.error();
    return true;
  }

  Contents& contents_;
  const MessageVisitor& visit_;
};

// The file's first bytes are MCAP's magic, or the Error that says it is not an MCAP file.
Status check_magic(Source& file) {
  if (file.size() < kMagicSize) {
    return Error{ErrorCode::kInvalidValue, "not an MCAP file: shorter than its magic bytes"};
  }
  auto magic = file.read(0, kMagicSize);
  if (!magic) return magic.error();
  if (!has_magic(*magic)) {
    return Error{ErrorCode::kInvalidValue, "not an MCAP file: wrong magic bytes"};
  }
  return {};
}

bool ends_with_magic(Source& file) {
  if (file.size() < kMagicSize) return false;
  auto magic = file.read(file.size() - kMagicSize, kMagicSize);
  return magic && has_magic(*magic);
}

// Where the Footer starts in a file that ends with one: right before the closing magic.
std::uint64_t footer_offset(const Source& file) {
  return file.size() - kMagicSize - Footer::kRecordSize;
}

// The Footer of a closed file; nullopt when the file is too short for one or lacks the closing
// magic (a recorder that stopped early).
Result<std::optional<Footer>> read_footer(Source& file) {
  if (file.size() < 2 * kMagicSize + Footer::kRecordSize || !ends_with_magic(file)) {
    return std::optional<Footer>{};
  }
  const std::uint64_t at = footer_offset(file);
  auto bytes = file.read(at, Footer::kRecordSize);
  if (!bytes) return bytes.error();
  auto footer = parse_footer(*bytes);
  if (!footer) return damaged(at, footer.error().reason);
  return std::optional<Footer>{*footer};
}

// The summary's records (not its Summary Offsets), once the footer points inside the file and
// the summary's CRC matches.
Result<Bytes> summary_section(Source& file, const Footer& footer) {
  const std::uint64_t footer_at = footer_offset(file);
  const std::uint64_t start = footer.summary_start;
  const std::uint64_t offsets = footer.summary_offset_start;
  if (start > footer_at || (offsets != 0 && (offsets < start || offsets > footer_at))) {
    return damaged(footer_at, "the footer points outside the file");
  }
  auto covered = file.read(start, footer_at + Footer::kBytesBeforeCrc - start);
  if (!covered) return covered.error();
  if (footer.summary_crc != 0 && crc32(*covered) != footer.summary_crc) {
    return damaged(start, "the summary's CRC does not match");
  }
  const std::uint64_t end = offsets != 0 ? offsets : footer_at;
  covered->resize(static_cast<std::size_t>(end - start));
  return covered;
}
// Adds one record of the summary section, found at byte `at`: schemas, channels, the statistics
// and chunk indexes; attachment and metadata indexes and later record kinds are skipped.
Status add_summary_record(Summary& summary, std::uint8_t opcode,
                          std::span<const std::uint8_t> content, std::uint64_t at,
                          std::uint64_t file_size) {
  switch (static_cast<Opcode>(opcode)) {
    case Opcode::kSchema: {
      auto schema = parse_schema(content);
      if (!schema) return damaged(at, schema.error().reason);
      summary.schemas.emplace(schema->id, std::move(*schema));
      return {};
    }
    case Opcode::kChannel: {
      auto channel = parse_channel(content);
      if (!channel) return damaged(at, channel.error().reason);
      summary.channels.emplace(channel->id, std::move(*channel));
      return {};
    }
    case Opcode::kStatistics: {
      auto statistics = parse_statistics(content);
      if (!statistics) return damaged(at, statistics.error().reason);
      summary.statistics = std::move(*statistics);
      return {};
    }
    case Opcode::kChunkIndex: {
      auto index = parse_chunk_index(content);
      if (!index) return damaged(at, index.error().reason);
      if (index->chunk_start_offset > file_size ||
          index->chunk_length > file_size - index->chunk_start_offset) {
        return damaged(at, "a Chunk Index points outside the file");
      }
      summary.chunk_indexes.push_back(std::move(*index));
      return {};
    }
    default:
      return {};
  }
}

// The records of `section`, which starts at byte `section_at` of a file of `file_size` bytes.
Result<Summary> parse_summary(std::uint64_t file_size, std::uint64_t section_at,
                              std::span<const std::uint8_t> section) {
  ByteReader in(section);
  Summary summary;
  while (in.remaining() > 0) {
    const std::uint64_t at = section_at + in.position();
    const auto opcode = in.u8();
    const auto length = in.u64();
    const auto content = length ? in.take(*length) : std::nullopt;
    if (!content) return damaged(at, "a summary record is cut short");
    if (auto added = add_summary_record(summary, *opcode, *content, at, file_size); !added) {
      return added.error();
    }
  }
  return summary;
}

}  // namespace

Result<Bytes> MemorySource::read(std::uint64_t offset, std::uint64_t length) {
  if (offset > bytes_.size() || length > bytes_.size() - offset) {
    return Error{ErrorCode::kInvalidValue, "a read beyond the end of the bytes"};
  }
  const auto part =
      bytes_.subspan(static_cast<std::size_t>(offset), static_cast<std::size_t>(length));
  return Bytes(part.begin(), part.end());
}

Result<std::unique_ptr<FileSource>> FileSource::open(const std::string& path) {
  // O_NONBLOCK: opening a FIFO without a writer returns at once instead of hanging.
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    const int error = errno;
    return Error{ErrorCode::kSystem, std::string("cannot open: ") + std::strerror(error), error};
  }
  struct stat status {};
  if (::fstat(fd, &status) != 0) {
    const int error = errno;
    ::close(fd);
    return Error{ErrorCode::kSystem, std::string("cannot stat: ") + std::strerror(error), error};
  }
  if (!S_ISREG(status.st_mode)) {
    ::close(fd);
    const char* kind = S_ISFIFO(status.st_mode)   ? "a FIFO"
                       : S_ISCHR(status.st_mode)  ? "a character device"
                       : S_ISBLK(status.st_mode)  ? "a block device"
                       : S_ISDIR(status.st_mode)  ? "a directory"
                       : S_ISSOCK(status.st_mode) ? "a socket"
                                                  : "a special file";
    return Error{ErrorCode::kInvalidValue, std::string("it is ") + kind +
                                               ", not a recording file (a recording is read from a "
                                               "regular file: copy it to one first)"};
  }
  return std::unique_ptr<FileSource>(
      new FileSource(fd, static_cast<std::uint64_t>(status.st_size)));
}

FileSource::~FileSource() { ::close(fd_); }

Result<Bytes> FileSource::read(std::uint64_t offset, std::uint64_t length) {
  if (offset > size_ || length > size_ - offset) {
    return Error{ErrorCode::kInvalidValue, "a read beyond the end of the file"};
  }
  Bytes bytes;
  try {
    bytes.resize(static_cast<std::size_t>(length));
  } catch (const std::bad_alloc&) {
    return Error{ErrorCode::kSystem,
                 "cannot hold a record of " + std::to_string(length) + " bytes at byte " +
                     std::to_string(offset) + " in memory",
                 ENOMEM};
  }
  for (std::size_t done = 0; done < bytes.size();) {
    const ssize_t got =
        ::pread(fd_, bytes.data() + done, bytes.size() - done, static_cast<off_t>(offset + done));
    if (got < 0 && errno == EINTR) continue;
    if (got < 0) {
      const int error = errno;
      return Error{ErrorCode::kSystem, std::string("read failed: ") + std::strerror(error), error};
    }
    if (got == 0) {
      return Error{
          ErrorCode::kSystem,
          "the file became shorter while it was read (" + std::to_string(offset + done) + " bytes)",
          EIO};
    }
    done += static_cast<std::size_t>(got);
  }
  return bytes;
}

Result<Contents> read_messages(Source& file, const MessageVisitor& visit) {
  if (auto magic = check_magic(file); !magic) return magic.error();
  Contents contents;
  const std::uint64_t size = file.size();
  if (size == kMagicSize) {
    contents.incomplete = "the file ends after its magic bytes";
    return contents;
  }
  auto opcode = file.read(kMagicSize, 1);
  if (!opcode) return opcode.error();
  if ((*opcode)[0] != static_cast<std::uint8_t>(Opcode::kHeader)) {
    return damaged(kMagicSize, "the first record is not a Header");
  }
  if (size - kMagicSize < kRecordPrefixSize) {
    contents.incomplete = "the file ends inside its Header";
    return contents;
  }
  auto prefix = file.read(kMagicSize, kRecordPrefixSize);
  if (!prefix) return prefix.error();
  ByteReader in(*prefix);
  in.u8();
  const std::uint64_t length = *in.u64();
  const std::uint64_t header_at = kMagicSize + kRecordPrefixSize;
  if (length > size - header_at) {
    contents.incomplete = "the file ends inside its Header";
    return contents;
  }
  auto header = file.read(header_at, length);
  if (!header) return header.error();
  auto parsed_header = parse_header(*header);
  if (!parsed_header) return damaged(kMagicSize, parsed_header.error().reason);
  contents.header = std::move(*parsed_header);

  RecordWalker walker(contents, visit);
  std::uint64_t data_end = 0;
  auto walked = walker.walk(file, header_at + length, data_end);
  if (!walked) return walked.error();
  if (*walked && contents.incomplete.empty()) {
    contents.incomplete =
        "the file ends without a Data End record (not closed: the recorder "
        "stopped early?)";
  }
  if (!contents.incomplete.empty()) return contents;

  // Data End found: the file must end with a footer and the magic.
  if (size < data_end + Footer::kRecordSize + kMagicSize || !ends_with_magic(file)) {
    contents.incomplete = "the file ends after Data End without its footer";
  }
  return contents;
}

Result<Contents> read_messages(std::span<const std::uint8_t> file, const MessageVisitor& visit) {
  MemorySource source(file);
  return read_messages(source, visit);
}

Result<std::optional<Summary>> read_summary(Source& file) {
  if (auto magic = check_magic(file); !magic) return magic.error();
  auto footer = read_footer(file);
  if (!footer) return footer.error();
  if (!*footer || (*footer)->summary_start == 0) return std::optional<Summary>{};
  auto section = summary_section(file, **footer);
  if (!section) return section.error();
  auto summary = parse_summary(file.size(), (*footer)->summary_start, *section);
  if (!summary) return summary.error();
  return std::optional<Summary>{std::move(*summary)};
}

Result<std::optional<Summary>> read_summary(std::span<const std::uint8_t> file) {
  MemorySource source(file);
  return read_summary(source);
}

}  // namespace teejet::mcap
