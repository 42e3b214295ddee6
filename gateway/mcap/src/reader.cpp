#include "teejet/mcap/reader.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>

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

  // `base`: the offset of `bytes` in the file, for messages. In a chunk, records must be
  // complete; in the file, a record cut short is where a killed recorder stopped.
  Result<bool> walk(std::span<const std::uint8_t> bytes, std::uint64_t base, bool in_chunk,
                    std::size_t& consumed) {
    ByteReader in(bytes);
    while (in.remaining() > 0) {
      const std::uint64_t at = base + in.position();
      const std::size_t record_start = in.position();
      const auto opcode = in.u8();
      const auto length = in.u64();
      if (!length) return cut_short(in_chunk, at, "a record header", consumed, record_start);
      const auto content = in.take(*length);
      if (!content) {
        return cut_short(in_chunk, at, "a " + opcode_name(*opcode) + " record", consumed,
                         record_start);
      }
      auto handled = handle(*opcode, *content, at, in_chunk);
      if (!handled) return handled.error();
      consumed = in.position();
      if (!*handled) return false;  // Data End: the data section is over
    }
    return true;
  }

 private:
  Result<bool> cut_short(bool in_chunk, std::uint64_t at, const std::string& what,
                         std::size_t& consumed, std::size_t record_start) {
    if (in_chunk) return damaged(at, "a chunk's records end inside " + what);
    consumed = record_start;
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
    std::size_t consumed = 0;
    auto walked = walk(*data, 0, true, consumed);
    if (!walked) return walked.error();
    return true;
  }

  Contents& contents_;
  const MessageVisitor& visit_;
};

Error not_mcap(std::span<const std::uint8_t> file) {
  return Error{ErrorCode::kInvalidValue, file.size() < kMagicSize
                                             ? "not an MCAP file: shorter than its magic bytes"
                                             : "not an MCAP file: wrong magic bytes"};
}

// Where the Footer starts in a file that ends with one: right before the closing magic.
std::size_t footer_offset(std::span<const std::uint8_t> file) {
  return file.size() - kMagicSize - Footer::kRecordSize;
}

// The Footer of a closed file; nullopt when the file is too short for one or lacks the closing
// magic (a recorder that stopped early).
Result<std::optional<Footer>> read_footer(std::span<const std::uint8_t> file) {
  if (file.size() < 2 * kMagicSize + Footer::kRecordSize || !has_magic(file.last(kMagicSize))) {
    return std::optional<Footer>{};
  }
  const std::size_t at = footer_offset(file);
  auto footer = parse_footer(file.subspan(at, Footer::kRecordSize));
  if (!footer) return damaged(at, footer.error().reason);
  return std::optional<Footer>{*footer};
}

// The summary's records (not its Summary Offsets), once the footer points inside the file and
// the summary's CRC matches.
Result<std::span<const std::uint8_t>> summary_section(std::span<const std::uint8_t> file,
                                                      const Footer& footer) {
  const std::size_t footer_at = footer_offset(file);
  const std::uint64_t start = footer.summary_start;
  const std::uint64_t offsets = footer.summary_offset_start;
  if (start > footer_at || (offsets != 0 && (offsets < start || offsets > footer_at))) {
    return damaged(footer_at, "the footer points outside the file");
  }
  const auto covered = file.subspan(start, footer_at + Footer::kBytesBeforeCrc - start);
  if (footer.summary_crc != 0 && crc32(covered) != footer.summary_crc) {
    return damaged(start, "the summary's CRC does not match");
  }
  const std::size_t end = offsets != 0 ? offsets : footer_at;
  return file.subspan(start, end - start);
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

// The records of `section`, which starts at byte `section_at` of `file`.
Result<Summary> parse_summary(std::span<const std::uint8_t> file, std::uint64_t section_at,
                              std::span<const std::uint8_t> section) {
  ByteReader in(section);
  Summary summary;
  while (in.remaining() > 0) {
    const std::uint64_t at = section_at + in.position();
    const auto opcode = in.u8();
    const auto length = in.u64();
    const auto content = length ? in.take(*length) : std::nullopt;
    if (!content) return damaged(at, "a summary record is cut short");
    if (auto added = add_summary_record(summary, *opcode, *content, at, file.size()); !added) {
      return added.error();
    }
  }
  return summary;
}

}  // namespace

Result<Contents> read_messages(std::span<const std::uint8_t> file, const MessageVisitor& visit) {
  if (!has_magic(file)) return not_mcap(file);
  Contents contents;
  ByteReader in(file.subspan(kMagicSize));
  const auto opcode = in.u8();
  const auto length = in.u64();
  const auto header = length ? in.take(*length) : std::nullopt;
  if (!opcode || *opcode != static_cast<std::uint8_t>(Opcode::kHeader)) {
    if (!opcode) {
      contents.incomplete = "the file ends after its magic bytes";
      return contents;
    }
    return damaged(kMagicSize, "the first record is not a Header");
  }
  if (!header) {
    contents.incomplete = "the file ends inside its Header";
    return contents;
  }
  auto parsed_header = parse_header(*header);
  if (!parsed_header) return damaged(kMagicSize, parsed_header.error().reason);
  contents.header = std::move(*parsed_header);

  const std::size_t data_start = kMagicSize + in.position();
  RecordWalker walker(contents, visit);
  std::size_t consumed = 0;
  auto walked = walker.walk(file.subspan(data_start), data_start, false, consumed);
  if (!walked) return walked.error();
  if (*walked && contents.incomplete.empty()) {
    contents.incomplete =
        "the file ends without a Data End record (not closed: the recorder "
        "stopped early?)";
  }
  if (!contents.incomplete.empty()) return contents;

  // Data End found: the file must end with a footer and the magic.
  const std::size_t data_end = data_start + consumed;
  if (file.size() < data_end + Footer::kRecordSize + kMagicSize ||
      !has_magic(file.last(kMagicSize))) {
    contents.incomplete = "the file ends after Data End without its footer";
  }
  return contents;
}

Result<std::optional<Summary>> read_summary(std::span<const std::uint8_t> file) {
  if (!has_magic(file)) return not_mcap(file);
  auto footer = read_footer(file);
  if (!footer) return footer.error();
  if (!*footer || (*footer)->summary_start == 0) return std::optional<Summary>{};
  auto section = summary_section(file, **footer);
  if (!section) return section.error();
  auto summary = parse_summary(file, (*footer)->summary_start, *section);
  if (!summary) return summary.error();
  return std::optional<Summary>{std::move(*summary)};
}

Result<Bytes> load_file(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) {
    const int error = errno;
    return Error{ErrorCode::kSystem, path + ": cannot open: " + std::strerror(error), error};
  }
  Bytes bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  if (file.bad()) return Error{ErrorCode::kSystem, path + ": read failed", EIO};
  return bytes;
}

}  // namespace teejet::mcap
