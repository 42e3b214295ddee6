#include "layouts.hpp"

namespace teejet::mcap {
namespace {

Error does_not_parse(const std::string& record) {
  return Error{ErrorCode::kInvalidValue, record + " does not parse"};
}

}  // namespace

void put_footer(Bytes& summary, std::uint64_t summary_start, std::uint64_t summary_offset_start) {
  ByteBuilder out(summary);
  out.u8(static_cast<std::uint8_t>(Opcode::kFooter));
  out.u64(Footer::kContentSize);
  out.u64(summary_start);
  out.u64(summary_offset_start);
  out.u32(crc32(summary));
}

Result<Footer> parse_footer(std::span<const std::uint8_t> record) {
  ByteReader in(record);
  const auto opcode = in.u8();
  const auto length = in.u64();
  const auto summary_start = in.u64();
  const auto summary_offset_start = in.u64();
  const auto summary_crc = in.u32();
  if (!opcode || *opcode != static_cast<std::uint8_t>(Opcode::kFooter) || !length ||
      *length != Footer::kContentSize || !summary_start || !summary_offset_start || !summary_crc) {
    return Error{ErrorCode::kInvalidValue, "the record before the closing magic is not a Footer"};
  }
  return Footer{*summary_start, *summary_offset_start, *summary_crc};
}

void put_header(ByteBuilder& out, const Header& header) {
  const auto started = out.begin_record(Opcode::kHeader);
  out.string(header.profile);
  out.string(header.library);
  out.end_record(started);
}

Result<Header> parse_header(std::span<const std::uint8_t> content) {
  ByteReader in(content);
  auto profile = in.string();
  auto library = in.string();
  if (!profile || !library) return does_not_parse("the Header");
  return Header{std::move(*profile), std::move(*library)};
}

void put_schema(ByteBuilder& out, const Schema& schema) {
  const auto started = out.begin_record(Opcode::kSchema);
  out.u16(schema.id);
  out.string(schema.name);
  out.string(schema.encoding);
  out.bytes32(schema.data);
  out.end_record(started);
}

Result<Schema> parse_schema(std::span<const std::uint8_t> content) {
  ByteReader in(content);
  const auto id = in.u16();
  auto name = in.string();
  auto encoding = in.string();
  auto data = in.bytes32();
  if (!id || !name || !encoding || !data) return does_not_parse("a Schema record");
  return Schema{*id, std::move(*name), std::move(*encoding), std::move(*data)};
}

void put_channel(ByteBuilder& out, const Channel& channel) {
  const auto started = out.begin_record(Opcode::kChannel);
  out.u16(channel.id);
  out.u16(channel.schema_id);
  out.string(channel.topic);
  out.string(channel.message_encoding);
  out.string_map(channel.metadata);
  out.end_record(started);
}

Result<Channel> parse_channel(std::span<const std::uint8_t> content) {
  ByteReader in(content);
  const auto id = in.u16();
  const auto schema_id = in.u16();
  auto topic = in.string();
  auto encoding = in.string();
  auto metadata = in.string_map();
  if (!id || !schema_id || !topic || !encoding || !metadata) {
    return does_not_parse("a Channel record");
  }
  return Channel{*id, *schema_id, std::move(*topic), std::move(*encoding), std::move(*metadata)};
}

void put_message(ByteBuilder& out, std::uint16_t channel_id, std::uint32_t sequence,
                 std::uint64_t log_time, std::uint64_t publish_time,
                 std::span<const std::uint8_t> data) {
  const auto started = out.begin_record(Opcode::kMessage);
  out.u16(channel_id);
  out.u32(sequence);
  out.u64(log_time);
  out.u64(publish_time);
  out.raw(data);
  out.end_record(started);
}

Result<Message> parse_message(std::span<const std::uint8_t> content) {
  ByteReader in(content);
  const auto channel_id = in.u16();
  const auto sequence = in.u32();
  const auto log_time = in.u64();
  const auto publish_time = in.u64();
  if (!channel_id || !sequence || !log_time || !publish_time) {
    return Error{ErrorCode::kInvalidValue, "a Message record is shorter than its fields"};
  }
  const auto data = in.take(in.remaining());
  return Message{*channel_id, *sequence, *log_time, *publish_time,
                 Bytes(data->begin(), data->end())};
}

void put_chunk(ByteBuilder& out, const ChunkRecord& chunk) {
  const auto started = out.begin_record(Opcode::kChunk);
  out.u64(chunk.message_start_time);
  out.u64(chunk.message_end_time);
  out.u64(chunk.uncompressed_size);
  out.u32(chunk.uncompressed_crc);
  out.string(chunk.compression);
  out.u64(chunk.records.size());
  out.raw(chunk.records);
  out.end_record(started);
}

Result<ChunkRecord> parse_chunk(std::span<const std::uint8_t> content) {
  ByteReader in(content);
  const auto start_time = in.u64();
  const auto end_time = in.u64();
  const auto uncompressed_size = in.u64();
  const auto uncompressed_crc = in.u32();
  auto compression = in.string();
  const auto records_size = in.u64();
  if (!start_time || !end_time || !uncompressed_size || !uncompressed_crc || !compression ||
      !records_size) {
    return does_not_parse("a Chunk record");
  }
  const auto records = in.take(*records_size);
  if (!records) {
    return Error{ErrorCode::kInvalidValue, "a chunk's records are longer than the chunk"};
  }
  return ChunkRecord{
      *start_time, *end_time, *uncompressed_size, *uncompressed_crc, std::move(*compression),
      *records};
}

void put_message_index(ByteBuilder& out, std::uint16_t channel_id,
                       const std::vector<std::pair<std::uint64_t, std::uint64_t>>& entries) {
  const auto started = out.begin_record(Opcode::kMessageIndex);
  out.u16(channel_id);
  out.u32(static_cast<std::uint32_t>(entries.size() * 16));
  for (const auto& [log_time, offset] : entries) {
    out.u64(log_time);
    out.u64(offset);
  }
  out.end_record(started);
}

void put_chunk_index(ByteBuilder& out, const ChunkIndex& index) {
  const auto started = out.begin_record(Opcode::kChunkIndex);
  out.u64(index.message_start_time);
  out.u64(index.message_end_time);
  out.u64(index.chunk_start_offset);
  out.u64(index.chunk_length);
  out.u16_u64_map(index.message_index_offsets);
  out.u64(index.message_index_length);
  out.string(index.compression);
  out.u64(index.compressed_size);
  out.u64(index.uncompressed_size);
  out.end_record(started);
}

Result<ChunkIndex> parse_chunk_index(std::span<const std::uint8_t> content) {
  ByteReader in(content);
  const auto start = in.u64();
  const auto end = in.u64();
  const auto offset = in.u64();
  const auto chunk_length = in.u64();
  auto offsets = in.u16_u64_map();
  const auto index_length = in.u64();
  auto compression = in.string();
  const auto compressed = in.u64();
  const auto uncompressed = in.u64();
  if (!start || !end || !offset || !chunk_length || !offsets || !index_length || !compression ||
      !compressed || !uncompressed) {
    return does_not_parse("a Chunk Index record");
  }
  return ChunkIndex{*start,
                    *end,
                    *offset,
                    *chunk_length,
                    std::move(*offsets),
                    *index_length,
                    std::move(*compression),
                    *compressed,
                    *uncompressed};
}

void put_statistics(ByteBuilder& out, const Statistics& statistics) {
  const auto started = out.begin_record(Opcode::kStatistics);
  out.u64(statistics.message_count);
  out.u16(statistics.schema_count);
  out.u32(statistics.channel_count);
  out.u32(statistics.attachment_count);
  out.u32(statistics.metadata_count);
  out.u32(statistics.chunk_count);
  out.u64(statistics.message_start_time);
  out.u64(statistics.message_end_time);
  out.u16_u64_map(statistics.channel_message_counts);
  out.end_record(started);
}

Result<Statistics> parse_statistics(std::span<const std::uint8_t> content) {
  ByteReader in(content);
  const auto messages = in.u64();
  const auto schemas = in.u16();
  const auto channels = in.u32();
  const auto attachments = in.u32();
  const auto metadata = in.u32();
  const auto chunks = in.u32();
  const auto start = in.u64();
  const auto end = in.u64();
  auto counts = in.u16_u64_map();
  if (!messages || !schemas || !channels || !attachments || !metadata || !chunks || !start ||
      !end || !counts) {
    return does_not_parse("the Statistics record");
  }
  return Statistics{*messages, *schemas, *channels, *attachments,      *metadata,
                    *chunks,   *start,   *end,      std::move(*counts)};
}

void put_summary_offset(ByteBuilder& out, Opcode group, std::uint64_t start, std::uint64_t length) {
  const auto started = out.begin_record(Opcode::kSummaryOffset);
  out.u8(static_cast<std::uint8_t>(group));
  out.u64(start);
  out.u64(length);
  out.end_record(started);
}

void put_data_end(ByteBuilder& out, std::uint32_t data_crc) {
  const auto started = out.begin_record(Opcode::kDataEnd);
  out.u32(data_crc);
  out.end_record(started);
}

}  // namespace teejet::mcap
