#include "teejet/mcap/reader.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>

#include "bytes.hpp"
#include "compression.hpp"

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

constexpr std::size_t kMagicSize = sizeof kMagic;
constexpr std::size_t kFooterRecordSize = 1 + 8 + 8 + 8 + 4;

Error damaged(std::uint64_t offset, const std::string& what) {
  return Error{ErrorCode::kInvalidValue,
               "damaged MCAP file at byte " + std::to_string(offset) + ": " + what};
}

bool has_magic(std::span<const std::uint8_t> bytes) {
  return bytes.size() >= kMagicSize &&
         std::equal(bytes.begin(), bytes.begin() + kMagicSize, kMagic);
}

std::optional<Schema> parse_schema(std::span<const std::uint8_t> content) {
  ByteReader in(content);
  Schema schema;
  const auto id = in.u16();
  auto name = in.string();
  auto encoding = in.string();
  auto data = in.bytes32();
  if (!id || !name || !encoding || !data) return std::nullopt;
  return Schema{*id, std::move(*name), std::move(*encoding), std::move(*data)};
}

std::optional<Channel> parse_channel(std::span<const std::uint8_t> content) {
  ByteReader in(content);
  const auto id = in.u16();
  const auto schema_id = in.u16();
  auto topic = in.string();
  auto encoding = in.string();
  auto metadata = in.string_map();
  if (!id || !schema_id || !topic || !encoding || !metadata) return std::nullopt;
  return Channel{*id, *schema_id, std::move(*topic), std::move(*encoding), std::move(*metadata)};
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
        if (!schema) return damaged(at, "a Schema record does not parse");
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
        if (!channel) return damaged(at, "a Channel record does not parse");
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
        ByteReader in(content);
        Message message;
        const auto channel_id = in.u16();
        const auto sequence = in.u32();
        const auto log_time = in.u64();
        const auto publish_time = in.u64();
        if (!channel_id || !sequence || !log_time || !publish_time) {
          return damaged(at, "a Message record is shorter than its fields");
        }
        const auto channel = contents_.channels.find(*channel_id);
        if (channel == contents_.channels.end()) {
          return damaged(at, "a message on channel " + std::to_string(*channel_id) +
                                 " comes before that channel's record");
        }
        message.channel_id = *channel_id;
        message.sequence = *sequence;
        message.log_time = *log_time;
        message.publish_time = *publish_time;
        const auto data = in.take(in.remaining());
        message.data.assign(data->begin(), data->end());
        ++contents_.messages;
        if (visit_) visit_(channel->second, message);
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
    ByteReader in(content);
    const auto start_time = in.u64();
    const auto end_time = in.u64();
    const auto uncompressed_size = in.u64();
    const auto uncompressed_crc = in.u32();
    const auto compression = in.string();
    const auto records_size = in.u64();
    if (!start_time || !end_time || !uncompressed_size || !uncompressed_crc || !compression ||
        !records_size) {
      return damaged(at, "a Chunk record does not parse");
    }
    const auto records = in.take(*records_size);
    if (!records) return damaged(at, "a chunk's records are longer than the chunk");
    auto data = decompress(*compression, *records, *uncompressed_size);
    if (!data) return damaged(at, data.error().reason);
    if (*uncompressed_crc != 0 && crc32(*data) != *uncompressed_crc) {
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
  ByteReader header_in(*header);
  auto profile = header_in.string();
  auto library = header_in.string();
  if (!profile || !library) return damaged(kMagicSize, "the Header does not parse");
  contents.header = {std::move(*profile), std::move(*library)};

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
  if (file.size() < data_end + kFooterRecordSize + kMagicSize ||
      !has_magic(file.last(kMagicSize))) {
    contents.incomplete = "the file ends after Data End without its footer";
  }
  return contents;
}

Result<std::optional<Summary>> read_summary(std::span<const std::uint8_t> file) {
  if (!has_magic(file)) return not_mcap(file);
  if (file.size() < 2 * kMagicSize + kFooterRecordSize || !has_magic(file.last(kMagicSize))) {
    return std::optional<Summary>{};
  }
  const std::size_t footer_at = file.size() - kMagicSize - kFooterRecordSize;
  ByteReader footer(file.subspan(footer_at, kFooterRecordSize));
  const auto opcode = footer.u8();
  const auto length = footer.u64();
  const auto summary_start = footer.u64();
  const auto summary_offset_start = footer.u64();
  const auto summary_crc = footer.u32();
  if (*opcode != static_cast<std::uint8_t>(Opcode::kFooter) || *length != 20) {
    return damaged(footer_at, "the record before the closing magic is not a Footer");
  }
  if (*summary_start == 0) return std::optional<Summary>{};
  if (*summary_start > footer_at ||
      (*summary_offset_start != 0 &&
       (*summary_offset_start < *summary_start || *summary_offset_start > footer_at))) {
    return damaged(footer_at, "the footer points outside the file");
  }
  const auto summary_bytes =
      file.subspan(*summary_start, footer_at + 1 + 8 + 8 + 8 - *summary_start);
  if (*summary_crc != 0 && crc32(summary_bytes) != *summary_crc) {
    return damaged(*summary_start, "the summary's CRC does not match");
  }
  const std::size_t summary_end = *summary_offset_start ? *summary_offset_start : footer_at;
  ByteReader in(file.subspan(*summary_start, summary_end - *summary_start));
  Summary summary;
  while (in.remaining() > 0) {
    const std::uint64_t at = *summary_start + in.position();
    const auto record_opcode = in.u8();
    const auto record_length = in.u64();
    const auto content = record_length ? in.take(*record_length) : std::nullopt;
    if (!content) return damaged(at, "a summary record is cut short");
    ByteReader fields(*content);
    switch (static_cast<Opcode>(*record_opcode)) {
      case Opcode::kSchema: {
        auto schema = parse_schema(*content);
        if (!schema) return damaged(at, "a Schema record does not parse");
        summary.schemas.emplace(schema->id, std::move(*schema));
        break;
      }
      case Opcode::kChannel: {
        auto channel = parse_channel(*content);
        if (!channel) return damaged(at, "a Channel record does not parse");
        summary.channels.emplace(channel->id, std::move(*channel));
        break;
      }
      case Opcode::kStatistics: {
        Statistics& s = summary.statistics;
        const auto messages = fields.u64();
        const auto schemas = fields.u16();
        const auto channels = fields.u32();
        const auto attachments = fields.u32();
        const auto metadata = fields.u32();
        const auto chunks = fields.u32();
        const auto start = fields.u64();
        const auto end = fields.u64();
        auto counts = fields.u16_u64_map();
        if (!messages || !schemas || !channels || !attachments || !metadata || !chunks || !start ||
            !end || !counts) {
          return damaged(at, "the Statistics record does not parse");
        }
        s = {*messages, *schemas, *channels, *attachments,      *metadata,
             *chunks,   *start,   *end,      std::move(*counts)};
        break;
      }
      case Opcode::kChunkIndex: {
        ChunkIndex index;
        const auto start = fields.u64();
        const auto end = fields.u64();
        const auto offset = fields.u64();
        const auto chunk_length = fields.u64();
        auto offsets = fields.u16_u64_map();
        const auto index_length = fields.u64();
        auto compression = fields.string();
        const auto compressed = fields.u64();
        const auto uncompressed = fields.u64();
        if (!start || !end || !offset || !chunk_length || !offsets || !index_length ||
            !compression || !compressed || !uncompressed) {
          return damaged(at, "a Chunk Index record does not parse");
        }
        if (*offset > file.size() || *chunk_length > file.size() - *offset) {
          return damaged(at, "a Chunk Index points outside the file");
        }
        summary.chunk_indexes.push_back({*start, *end, *offset, *chunk_length, std::move(*offsets),
                                         *index_length, std::move(*compression), *compressed,
                                         *uncompressed});
        break;
      }
      default:
        break;  // attachment and metadata indexes, later record kinds
    }
  }
  return std::optional<Summary>{std::move(summary)};
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
