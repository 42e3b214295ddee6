#include "info.hpp"

#include <fmt/format.h>

#include <nlohmann/json.hpp>

#include "teejet/mcap/reader.hpp"

namespace teejet::record {
namespace {

struct ChannelInfo {
  std::uint16_t id = 0;
  std::string topic;
  std::string schema;
  std::uint64_t messages = 0;
};

struct FileInfo {
  std::uint64_t size = 0;
  bool complete = true;
  std::string incomplete;
  std::string library;
  std::uint64_t messages = 0;
  std::uint64_t chunks = 0;
  std::string compression;
  std::uint64_t compressed = 0, uncompressed = 0;
  std::uint64_t start = 0, end = 0;
  std::vector<ChannelInfo> channels;
};

std::string utc(std::uint64_t ns) {
  const std::time_t seconds = static_cast<std::time_t>(ns / 1'000'000'000);
  std::tm parts{};
  gmtime_r(&seconds, &parts);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%S", &parts);
  return fmt::format("{}.{:09}Z", text, ns % 1'000'000'000);
}

std::string schema_name(const std::map<std::uint16_t, mcap::Schema>& schemas, std::uint16_t id) {
  const auto found = schemas.find(id);
  return found == schemas.end() ? std::string() : found->second.name;
}

Result<FileInfo> inspect(const std::string& path) {
  auto file = mcap::FileSource::open(path);
  if (!file) return file.error();
  FileInfo info;
  info.size = (*file)->size();
  auto summary = mcap::read_summary(**file);
  if (!summary) return summary.error();
  if (*summary) {
    const auto& statistics = (*summary)->statistics;
    info.messages = statistics.message_count;
    info.chunks = statistics.chunk_count;
    info.start = statistics.message_start_time;
    info.end = statistics.message_end_time;
    for (const auto& index : (*summary)->chunk_indexes) {
      info.compression = index.compression.empty() ? "none" : index.compression;
      info.compressed += index.compressed_size;
      info.uncompressed += index.uncompressed_size;
    }
    for (const auto& [id, channel] : (*summary)->channels) {
      const auto count = statistics.channel_message_counts.find(id);
      info.channels.push_back(
          {id, channel.topic, schema_name((*summary)->schemas, channel.schema_id),
           count == statistics.channel_message_counts.end() ? 0 : count->second});
    }
  }
  // No summary (a killed recorder): read it through, which also says where it ends.
  std::map<std::uint16_t, std::uint64_t> counts;
  bool first = true;
  auto contents =
      mcap::read_messages(**file, [&](const mcap::Channel& channel, const mcap::Message& message) {
        if (*summary) return;
        ++counts[channel.id];
        info.start = first ? message.log_time : std::min(info.start, message.log_time);
        info.end = std::max(info.end, message.log_time);
        first = false;
      });
  if (!contents) return contents.error();
  info.library = contents->header.library;
  if (!contents->incomplete.empty()) {
    info.complete = false;
    info.incomplete = contents->incomplete;
  }
  if (!*summary) {
    info.messages = contents->messages;
    info.chunks = contents->chunks;
    for (const auto& [id, channel] : contents->channels) {
      info.channels.push_back(
          {id, channel.topic, schema_name(contents->schemas, channel.schema_id), counts[id]});
    }
  }
  return info;
}

}  // namespace

int print_info(const std::string& path, bool json, std::ostream& out, std::ostream& err) {
  auto info = inspect(path);
  if (!info) {
    err << "teejet-record: " << path << ": " << info.error().reason << '\n';
    return 1;
  }
  const double seconds =
      info->end > info->start ? static_cast<double>(info->end - info->start) / 1e9 : 0.0;
  if (json) {
    nlohmann::json channels = nlohmann::json::array();
    for (const auto& channel : info->channels) {
      channels.push_back({{"id", channel.id},
                          {"topic", channel.topic},
                          {"schema", channel.schema},
                          {"messages", channel.messages}});
    }
    nlohmann::json document{{"file", path},
                            {"size", info->size},
                            {"complete", info->complete},
                            {"library", info->library},
                            {"messages", info->messages},
                            {"chunks", info->chunks},
                            {"start_ns", info->start},
                            {"end_ns", info->end},
                            {"duration_s", seconds},
                            {"channels", channels}};
    if (!info->complete) document["incomplete"] = info->incomplete;
    if (!info->compression.empty()) {
      document["compression"] = info->compression;
      document["compressed_bytes"] = info->compressed;
      document["uncompressed_bytes"] = info->uncompressed;
    }
    out << document.dump() << '\n';
  } else {
    out << fmt::format("file:        {} ({} bytes)\n", path, info->size);
    out << fmt::format("recorded by: {}\n", info->library.empty() ? "(unknown)" : info->library);
    out << fmt::format("complete:    {}\n",
                       info->complete ? "yes (summary and chunk indexes: readers can seek)"
                                      : "no: " + info->incomplete);
    if (info->messages > 0) {
      out << fmt::format("start:       {}\nend:         {}\n", utc(info->start), utc(info->end));
    }
    out << fmt::format("duration:    {:.3f} s\nmessages:    {}\n", seconds, info->messages);
    if (info->compression.empty()) {
      out << fmt::format("chunks:      {}\n", info->chunks);
    } else {
      out << fmt::format("chunks:      {} ({}, {} bytes of records in {} bytes)\n", info->chunks,
                         info->compression, info->uncompressed, info->compressed);
    }
    std::size_t width = 5;
    for (const auto& channel : info->channels) width = std::max(width, channel.topic.size());
    out << fmt::format("channels:\n  {:>3}  {:<{}}  {:>9}  {:>8}  {}\n", "id", "topic", width,
                       "messages", "per s", "schema");
    for (const auto& channel : info->channels) {
      const double rate = seconds > 0 ? static_cast<double>(channel.messages) / seconds : 0.0;
      out << fmt::format("  {:>3}  {:<{}}  {:>9}  {:>8.1f}  {}\n", channel.id, channel.topic, width,
                         channel.messages, rate, channel.schema);
    }
  }
  if (!info->complete) {
    err << "teejet-record: " << path << ": incomplete: " << info->incomplete << '\n';
  }
  return 0;
}

}  // namespace teejet::record
