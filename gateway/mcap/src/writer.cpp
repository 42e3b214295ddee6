#include "teejet/mcap/writer.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "bytes.hpp"
#include "compression.hpp"
#include "layouts.hpp"

namespace teejet::mcap {
namespace {

class FileSink final : public Sink {
 public:
  FileSink(int fd, std::string path) : fd_(fd), path_(std::move(path)) {}
  ~FileSink() override { ::close(fd_); }

  Status write(std::span<const std::uint8_t> bytes) override {
    while (!bytes.empty()) {
      const ssize_t written = ::write(fd_, bytes.data(), bytes.size());
      if (written < 0) {
        if (errno == EINTR) continue;
        const int error = errno;
        return Error{ErrorCode::kSystem, path_ + ": write failed: " + std::strerror(error), error};
      }
      bytes = bytes.subspan(static_cast<std::size_t>(written));
    }
    return {};
  }

 private:
  int fd_;
  std::string path_;
};

}  // namespace

Result<std::unique_ptr<Sink>> open_file_sink(const std::string& path) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    const int error = errno;
    return Error{ErrorCode::kSystem, path + ": cannot create: " + std::strerror(error), error};
  }
  return std::unique_ptr<Sink>(std::make_unique<FileSink>(fd, path));
}

Writer::Writer(std::unique_ptr<Sink> sink, WriterOptions options)
    : sink_(std::move(sink)), options_(std::move(options)) {}

Writer::~Writer() = default;

Result<std::unique_ptr<Writer>> Writer::create(std::unique_ptr<Sink> sink, WriterOptions options) {
  if (!options.compression.empty() && options.compression != "zstd" &&
      options.compression != "lz4") {
    return Error{ErrorCode::kInvalidValue,
                 "unknown compression '" + options.compression + "' (known: zstd, lz4, none)"};
  }
  if (options.chunk_size == 0) {
    return Error{ErrorCode::kOutOfRange, "the chunk size must be at least 1 byte"};
  }
  std::unique_ptr<Writer> writer(new Writer(std::move(sink), std::move(options)));
  Bytes start(std::begin(kMagic), std::end(kMagic));
  ByteBuilder out(start);
  put_header(out, {writer->options_.profile, writer->options_.library});
  if (Status written = writer->emit(start, true); !written) return written.error();
  return writer;
}

Status Writer::emit(const Bytes& bytes, bool data_section) {
  if (!failed_) return failed_;
  if (data_section) data_crc_ = crc32(bytes, data_crc_);
  if (Status written = sink_->write(bytes); !written) {
    failed_ = written;
    return written;
  }
  position_ += bytes.size();
  return {};
}

Result<std::uint16_t> Writer::add_schema(const std::string& name, const std::string& encoding,
                                         std::span<const std::uint8_t> data) {
  if (finished_) return Error{ErrorCode::kUnavailable, "the recording is finished"};
  if (schemas_.size() >= 0xFFFF) return Error{ErrorCode::kOutOfRange, "65535 schemas at most"};
  Schema schema{static_cast<std::uint16_t>(schemas_.size() + 1), name, encoding,
                Bytes(data.begin(), data.end())};
  Bytes record;
  ByteBuilder out(record);
  put_schema(out, schema);
  if (Status written = emit(record, true); !written) return written.error();
  schemas_.push_back(std::move(schema));
  ++statistics_.schema_count;
  return schemas_.back().id;
}

Result<std::uint16_t> Writer::add_channel(std::uint16_t schema_id, const std::string& topic,
                                          const std::string& message_encoding,
                                          const std::map<std::string, std::string>& metadata) {
  if (finished_) return Error{ErrorCode::kUnavailable, "the recording is finished"};
  if (schema_id > schemas_.size()) {
    return Error{ErrorCode::kInvalidValue,
                 "channel " + topic + ": no schema " + std::to_string(schema_id)};
  }
  if (channels_.size() > 0xFFFF) return Error{ErrorCode::kOutOfRange, "65536 channels at most"};
  Channel channel{static_cast<std::uint16_t>(channels_.size()), schema_id, topic, message_encoding,
                  metadata};
  Bytes record;
  ByteBuilder out(record);
  put_channel(out, channel);
  if (Status written = emit(record, true); !written) return written.error();
  channels_.push_back(std::move(channel));
  ++statistics_.channel_count;
  return channels_.back().id;
}

Status Writer::write(std::uint16_t channel_id, std::uint32_t sequence, std::uint64_t log_time,
                     std::uint64_t publish_time, std::span<const std::uint8_t> data) {
  if (finished_) return Error{ErrorCode::kUnavailable, "the recording is finished"};
  if (!failed_) return failed_;
  if (channel_id >= channels_.size()) {
    return Error{ErrorCode::kInvalidValue, "no channel " + std::to_string(channel_id)};
  }
  if (chunk_.empty()) {
    chunk_start_time_ = chunk_end_time_ = log_time;
  } else {
    chunk_start_time_ = std::min(chunk_start_time_, log_time);
    chunk_end_time_ = std::max(chunk_end_time_, log_time);
  }
  chunk_index_[channel_id].emplace_back(log_time, chunk_.size());
  ByteBuilder out(chunk_);
  put_message(out, channel_id, sequence, log_time, publish_time, data);

  if (statistics_.message_count == 0) {
    statistics_.message_start_time = statistics_.message_end_time = log_time;
  } else {
    statistics_.message_start_time = std::min(statistics_.message_start_time, log_time);
    statistics_.message_end_time = std::max(statistics_.message_end_time, log_time);
  }
  ++statistics_.message_count;
  ++statistics_.channel_message_counts[channel_id];
  if (chunk_.size() >= options_.chunk_size) return close_chunk();
  return {};
}

Status Writer::flush() {
  if (finished_) return {};
  return close_chunk();
}

Status Writer::close_chunk() {
  if (chunk_.empty()) return failed_;
  auto compressed = compress(options_.compression, chunk_);
  if (!compressed) return compressed.error();

  ChunkIndex index;
  index.message_start_time = chunk_start_time_;
  index.message_end_time = chunk_end_time_;
  index.chunk_start_offset = position_;
  index.compression = options_.compression;
  index.compressed_size = compressed->size();
  index.uncompressed_size = chunk_.size();

  Bytes record;
  ByteBuilder out(record);
  put_chunk(out, {.message_start_time = chunk_start_time_,
                  .message_end_time = chunk_end_time_,
                  .uncompressed_size = chunk_.size(),
                  .uncompressed_crc = crc32(chunk_),
                  .compression = options_.compression,
                  .records = *compressed});
  index.chunk_length = record.size();

  // The Message Index records follow the chunk; their offsets are known before writing.
  std::uint64_t at = position_ + record.size();
  const std::size_t indexes_start = record.size();
  for (const auto& [channel_id, entries] : chunk_index_) {
    index.message_index_offsets[channel_id] = at;
    const std::size_t before = record.size();
    put_message_index(out, channel_id, entries);
    at += record.size() - before;
  }
  index.message_index_length = record.size() - indexes_start;

  chunk_.clear();
  chunk_index_.clear();
  if (Status written = emit(record, true); !written) return written;
  chunk_indexes_.push_back(std::move(index));
  ++statistics_.chunk_count;
  return {};
}

Status Writer::finish() {
  if (finished_) return failed_;
  if (Status closed = close_chunk(); !closed) return closed;
  finished_ = true;

  Bytes data_end;
  ByteBuilder end(data_end);
  put_data_end(end, data_crc_);
  if (Status written = emit(data_end, false); !written) return written;

  // The summary: one group per opcode, each found again through a Summary Offset record.
  const std::uint64_t summary_start = position_;
  Bytes summary;
  ByteBuilder out(summary);
  struct Group {
    Opcode opcode;
    std::uint64_t start, length;
  };
  std::vector<Group> groups;
  const auto group = [&](Opcode opcode, auto&& put_all) {
    const std::size_t before = summary.size();
    put_all();
    if (summary.size() > before) {
      groups.push_back({opcode, summary_start + before, summary.size() - before});
    }
  };
  group(Opcode::kSchema, [&] {
    for (const Schema& schema : schemas_) put_schema(out, schema);
  });
  group(Opcode::kChannel, [&] {
    for (const Channel& channel : channels_) put_channel(out, channel);
  });
  group(Opcode::kStatistics, [&] { put_statistics(out, statistics_); });
  group(Opcode::kChunkIndex, [&] {
    for (const ChunkIndex& index : chunk_indexes_) put_chunk_index(out, index);
  });
  const std::uint64_t summary_offset_start = summary_start + summary.size();
  for (const Group& each : groups) put_summary_offset(out, each.opcode, each.start, each.length);
  put_footer(summary, summary_start, summary_offset_start);
  summary.insert(summary.end(), std::begin(kMagic), std::end(kMagic));
  return emit(summary, false);
}

}  // namespace teejet::mcap
