#include "info.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <nlohmann/json.hpp>

#include "teejet/mcap/reader.hpp"
#include "teejet/recording/clock_steps.hpp"

namespace teejet::record {
namespace {

struct ChannelInfo {
  std::uint16_t id = 0;
  std::string topic;
  std::string schema;
  std::uint64_t messages = 0;
};

// The summary held against the messages read.
enum class Verdict { kNone, kAgrees, kDisagrees, kDamaged };

struct FileInfo {
  Verdict summary = Verdict::kNone;
  std::vector<std::string> summary_differences;  // kDisagrees, kDamaged: why
  std::uint64_t size = 0;
  bool complete = true;
  std::string incomplete;
  std::string library;
  std::uint64_t messages = 0;
  std::uint64_t chunks = 0;
  std::string compression;
  std::uint64_t compressed = 0, uncompressed = 0;
  std::uint64_t start = 0, end = 0;
  std::uint64_t span = 0;  // from the first message to the last, without the clock's steps
  std::uint64_t clock_steps = 0;
  std::int64_t largest_step = 0;
  std::uint64_t largest_step_at = 0;
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

std::string channel_text(std::uint16_t id, const std::string& topic) {
  return "channel " + std::to_string(id) + " (" + topic + ")";
}

// What the summary says that the messages read do not: empty when it agrees.
std::vector<std::string> summary_differences(const mcap::Summary& summary, const FileInfo& read) {
  std::vector<std::string> differences;
  const auto& statistics = summary.statistics;
  if (statistics.message_count != read.messages) {
    differences.push_back("it counts " + std::to_string(statistics.message_count) +
                          " messages, the file holds " + std::to_string(read.messages));
  }
  if (statistics.chunk_count != read.chunks || summary.chunk_indexes.size() != read.chunks) {
    differences.push_back("it counts " + std::to_string(statistics.chunk_count) + " chunks and " +
                          std::to_string(summary.chunk_indexes.size()) +
                          " chunk indexes, the file holds " + std::to_string(read.chunks) +
                          " chunks");
  }
  if (read.messages > 0 &&
      (statistics.message_start_time != read.start || statistics.message_end_time != read.end)) {
    differences.push_back("it says the messages span " + utc(statistics.message_start_time) +
                          " to " + utc(statistics.message_end_time) + ", they span " +
                          utc(read.start) + " to " + utc(read.end));
  }
  for (const auto& channel : read.channels) {
    if (!summary.channels.contains(channel.id)) {
      differences.push_back(channel_text(channel.id, channel.topic) + " (" +
                            std::to_string(channel.messages) + " messages) is missing from it");
      continue;
    }
    const auto count = statistics.channel_message_counts.find(channel.id);
    const std::uint64_t counted =
        count == statistics.channel_message_counts.end() ? 0 : count->second;
    if (counted != channel.messages) {
      differences.push_back("it counts " + std::to_string(counted) + " messages on " +
                            channel_text(channel.id, channel.topic) + ", the file holds " +
                            std::to_string(channel.messages));
    }
  }
  for (const auto& [id, channel] : summary.channels) {
    const bool in_file =
        std::any_of(read.channels.begin(), read.channels.end(),
                    [id = id](const ChannelInfo& listed) { return listed.id == id; });
    if (!in_file) {
      differences.push_back("it lists " + channel_text(id, channel.topic) +
                            ", which the file does not have");
    }
  }
  return differences;
}

// What the file holds, as read through from its first record; its summary, when it has one, is
// held against that and never shown in its place (a crafted or damaged summary may say anything).
Result<FileInfo> inspect(mcap::Source& file) {
  FileInfo info;
  info.size = file.size();
  std::map<std::uint16_t, std::uint64_t> counts;
  bool first = true;
  recording::ClockSteps steps;
  auto contents =
      mcap::read_messages(file, [&](const mcap::Channel& channel, const mcap::Message& message) {
        ++counts[channel.id];
        info.span = steps.next(message.log_time, message.publish_time);
        info.start = first ? message.log_time : std::min(info.start, message.log_time);
        info.end = std::max(info.end, message.log_time);
        first = false;
      });
  if (!contents) return contents.error();
  info.library = contents->header.library;
  info.clock_steps = steps.steps();
  info.largest_step = steps.largest_step_ns();
  info.largest_step_at = steps.largest_step_at();
  if (!contents->incomplete.empty()) {
    info.complete = false;
    info.incomplete = contents->incomplete;
  }
  info.messages = contents->messages;
  info.chunks = contents->chunks;
  for (const auto& [id, channel] : contents->channels) {
    info.channels.push_back(
        {id, channel.topic, schema_name(contents->schemas, channel.schema_id), counts[id]});
  }
  if (!info.complete) return info;  // its summary, if any, is not reached
  auto summary = mcap::read_summary(file);
  if (!summary) {
    info.summary = Verdict::kDamaged;
    info.summary_differences = {summary.error().reason};
    return info;
  }
  if (!*summary) return info;
  info.summary_differences = summary_differences(**summary, info);
  info.summary = info.summary_differences.empty() ? Verdict::kAgrees : Verdict::kDisagrees;
  if (info.summary == Verdict::kAgrees) {
    for (const auto& index : (*summary)->chunk_indexes) {
      info.compression = index.compression.empty() ? "none" : index.compression;
      info.compressed += index.compressed_size;
      info.uncompressed += index.uncompressed_size;
    }
  }
  return info;
}

const char* verdict_name(Verdict verdict) {
  switch (verdict) {
    case Verdict::kNone:
      return "none";
    case Verdict::kAgrees:
      return "agrees";
    case Verdict::kDisagrees:
      return "disagrees";
    case Verdict::kDamaged:
      return "damaged";
  }
  return "none";
}

std::string summary_text(const FileInfo& info) {
  switch (info.summary) {
    case Verdict::kNone:
      return info.complete ? "none (a reader must read the whole file)"
                           : "none (the file ends before it)";
    case Verdict::kAgrees:
      return "agrees with the messages read";
    case Verdict::kDisagrees:
    case Verdict::kDamaged: {
      std::string text = info.summary == Verdict::kDamaged ? "damaged, not used: "
                                                           : "disagrees with the file, not used: ";
      for (std::size_t i = 0; i < info.summary_differences.size(); ++i) {
        text += (i > 0 ? "; " : "") + info.summary_differences[i];
      }
      return text;
    }
  }
  return "";
}

}  // namespace

int print_info(const std::string& path, bool json, std::ostream& out, std::ostream& err) {
  auto file = mcap::FileSource::open(path);
  if (!file) {
    err << "teejet-record: " << path << ": " << file.error().reason << '\n';
    return 1;
  }
  return print_info(**file, path, json, out, err);
}

int print_info(mcap::Source& file, const std::string& path, bool json, std::ostream& out,
               std::ostream& err) {
  auto info = inspect(file);
  if (!info) {
    err << "teejet-record: " << path << ": " << info.error().reason << '\n';
    return 1;
  }
  const double seconds = static_cast<double>(info->span) / 1e9;
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
                            {"channels", channels},
                            {"summary", verdict_name(info->summary)},
                            {"clock_steps", info->clock_steps}};
    if (!info->complete) document["incomplete"] = info->incomplete;
    if (!info->summary_differences.empty()) {
      document["summary_differences"] = info->summary_differences;
    }
    if (!info->compression.empty()) {
      document["compression"] = info->compression;
      document["compressed_bytes"] = info->compressed;
      document["uncompressed_bytes"] = info->uncompressed;
    }
    out << document.dump() << '\n';
  } else {
    out << fmt::format("file:        {} ({} bytes)\n", path, info->size);
    out << fmt::format("recorded by: {}\n", info->library.empty() ? "(unknown)" : info->library);
    out << fmt::format("complete:    {}\n", info->complete ? "yes" : "no: " + info->incomplete);
    out << fmt::format("summary:     {}\n", summary_text(*info));
    if (info->messages > 0) {
      out << fmt::format("start:       {}\nend:         {}\n", utc(info->start), utc(info->end));
    }
    out << fmt::format("duration:    {:.3f} s\nmessages:    {}\n", seconds, info->messages);
    if (info->clock_steps > 0) {
      out << fmt::format(
          "clock steps: {} in the recorder's log times (the largest by {:+.3f} s, before message "
          "{}): the duration and a replay leave them out\n",
          info->clock_steps, static_cast<double>(info->largest_step) / 1e9, info->largest_step_at);
    }
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
