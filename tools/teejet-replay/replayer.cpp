#include "replayer.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <memory>
#include <set>
#include <thread>

#include "teejet/client/valve_view.hpp"
#include "teejet/dds/participant.hpp"
#include "teejet/dds/topics.hpp"
#include "teejet/mcap/reader.hpp"
#include "teejet/recording/catalog.hpp"
#include "teejet/recording/clock_steps.hpp"
#include "teejet/valvePubSubTypes.h"

namespace teejet::replay {
namespace {

using namespace std::chrono_literals;
using recording::TopicType;

constexpr Duration kStopCheck = 100ms;

struct Route {
  recording::TopicWriter* writer = nullptr;  // null: this channel is not replayed
  bool disposed = false;
  std::string topic;
};

std::string dds_topic_of(const mcap::Channel& channel) {
  const auto named = channel.metadata.find(recording::kDdsTopicKey);
  return named != channel.metadata.end() ? named->second : channel.topic;
}

bool is_disposal(const mcap::Channel& channel) {
  const auto state = channel.metadata.find(recording::kInstanceStateKey);
  return state != channel.metadata.end() && state->second == recording::kDisposed;
}

bool selected(const ReplayOptions& options, const std::string& topic) {
  if (topic == dds::topics::kCommand && !options.with_commands) return false;
  return options.topics.empty() ||
         std::any_of(options.topics.begin(), options.topics.end(), [&](const std::string& glob) {
           return recording::topic_matches(glob, topic);
         });
}

// Every channel of the file checked against the catalog before anything is published.
Status check_channel(const mcap::Channel& channel,
                     const std::map<std::uint16_t, mcap::Schema>& schemas) {
  const std::string where = "channel " + std::to_string(channel.id) + " '" + channel.topic + "'";
  if (channel.message_encoding != recording::kMessageEncoding) {
    return Error{ErrorCode::kInvalidValue,
                 where + ": message encoding '" + channel.message_encoding + "', not 'cdr'"};
  }
  const auto schema = schemas.find(channel.schema_id);
  if (schema == schemas.end()) {
    return Error{ErrorCode::kInvalidValue, where + ": no schema"};
  }
  const std::string topic = dds_topic_of(channel);
  const TopicType* type = recording::find_topic(topic);
  if (type == nullptr) {
    return Error{ErrorCode::kInvalidValue, where + ": '" + topic + "' is not a teejet topic"};
  }
  if (schema->second.name != type->type_name ||
      schema->second.encoding != recording::kSchemaEncoding) {
    return Error{ErrorCode::kInvalidValue, where + ": schema '" + schema->second.name + "' (" +
                                               schema->second.encoding +
                                               ") is not the one this replayer knows for " + topic +
                                               ": '" + type->type_name + "' (omgidl)"};
  }
  return {};
}

std::string seconds_text(std::uint64_t nanoseconds) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3f s", static_cast<double>(nanoseconds) / 1e9);
  return text;
}

// Something to replay between --start and --end, or the reason why not. Offsets count from the
// file's first message, without the steps of the recorder's clock.
Status check_window(const ReplayOptions& options, std::uint64_t from, std::uint64_t to) {
  if (from > to) {
    return Error{ErrorCode::kInvalidValue, "the channels to replay hold no message"};
  }
  const auto start = static_cast<std::uint64_t>(options.start.count());
  const auto end = options.end ? static_cast<std::uint64_t>(options.end->count()) : UINT64_MAX;
  if (start > to || end < from) {
    return Error{ErrorCode::kInvalidValue,
                 "nothing to replay from --start " + seconds_text(start) +
                     (options.end ? " to --end " + seconds_text(end) : std::string()) +
                     ": the messages" + (options.topics.empty() ? "" : " of the topics chosen") +
                     " are from " + seconds_text(from) + " to " + seconds_text(to) +
                     " into the recording"};
  }
  return {};
}

// The gateway a recorded status sample is of; nullopt when the bytes are not one.
std::optional<std::string> gateway_of(std::span<const std::uint8_t> data) {
  GatewayStatusPubSubType type;
  GatewayStatus status;
  if (!recording::decode_payload(data, type, &status)) return std::nullopt;
  return status.gateway().to_string();
}

// How long replay looks for live gateways before it publishes: the client library's picture of
// the domain is complete well within this when a gateway is there (docs/topics.md).
constexpr auto kLiveGatewayLookup = std::chrono::seconds(5);

// The names of the gateways alive on the domain, as a client sees them (the client library).
Result<std::set<std::string>> live_gateways(dds::Participant& participant,
                                            const std::atomic<bool>& stop) {
  auto view = client::ValveView::create(participant);
  if (!view) return view.error();
  (*view)->wait_until(
      [](const client::ValveTable& table) {
        return table.gateway_participants() == 0 ? table.discovery_settled()
                                                 : table.directory_complete();
      },
      std::chrono::steady_clock::now() + kLiveGatewayLookup, stop);
  std::set<std::string> names;
  for (const auto& gateway : (*view)->gateways()) {
    if (!gateway.lost) names.insert(gateway.name);
  }
  return names;
}

}  // namespace

Result<RecordingCheck> check_recording(mcap::Source& file, const ReplayOptions& options) {
  RecordingCheck checked;
  std::uint64_t selected_first = UINT64_MAX;
  std::uint64_t selected_last = 0;
  auto contents =
      mcap::read_messages(file, [&](const mcap::Channel& channel, const mcap::Message& message) {
        const std::uint64_t offset = checked.steps.next(message.log_time, message.publish_time);
        const std::string topic = dds_topic_of(channel);
        if (!selected(options, topic)) return;
        if (topic == dds::topics::kGatewayStatus && !is_disposal(channel)) {
          if (auto gateway = gateway_of(message.data)) checked.gateways.insert(*gateway);
        }
        selected_first = std::min(selected_first, offset);
        selected_last = std::max(selected_last, offset);
      });
  if (!contents) return contents.error();
  bool any_channel = false;
  for (const auto& [id, channel] : contents->channels) {
    if (!selected(options, dds_topic_of(channel))) continue;
    if (auto channel_checked = check_channel(channel, contents->schemas); !channel_checked) {
      return channel_checked.error();
    }
    any_channel = true;
  }
  if (!any_channel) {
    return Error{
        ErrorCode::kInvalidValue,
        "no channel to replay" + (options.topics.empty() ? std::string() : " matches --topic")};
  }
  if (auto window = check_window(options, selected_first, selected_last); !window) {
    return window.error();
  }
  checked.contents = std::move(*contents);
  return checked;
}

Result<ReplayReport> replay(const ReplayOptions& options, const std::atomic<bool>& stop) {
  auto file = mcap::FileSource::open(options.file);
  if (!file) return Error{file.error().code, options.file + ": " + file.error().reason};
  // The first pass checks the file and finds its channels, the steps of the recorder's clock,
  // and when the selected topics have messages.
  auto checked = check_recording(**file, options);
  if (!checked) return Error{checked.error().code, options.file + ": " + checked.error().reason};
  const mcap::Contents& contents = checked->contents;
  const recording::ClockSteps& steps = checked->steps;
  const std::set<std::string>& recorded_gateways = checked->gateways;
  if (!contents.incomplete.empty()) {
    // Still replayable: a killed recorder's file up to its last complete chunk.
    std::fprintf(stderr, "teejet-replay: %s: %s; replaying what is there\n", options.file.c_str(),
                 contents.incomplete.c_str());
  }
  if (steps.steps() > 0) {
    std::fprintf(stderr,
                 "teejet-replay: %s: the recorder's clock stepped %llu time(s) (the largest by "
                 "%+.3f s, before message %llu): replayed without the steps\n",
                 options.file.c_str(), static_cast<unsigned long long>(steps.steps()),
                 static_cast<double>(steps.largest_step_ns()) / 1e9,
                 static_cast<unsigned long long>(steps.largest_step_at()));
  }

  auto participant = dds::Participant::create(
      {.domain = options.domain, .profile_file = options.profile_file, .name = "teejet-replay"});
  if (!participant) return participant.error();
  if (!recorded_gateways.empty() && !options.into_live_gateways) {
    // Before any writer of ours exists, so that only the domain's own gateways are seen.
    auto live = live_gateways(**participant, stop);
    if (!live) return live.error();
    std::string both;
    for (const auto& name : recorded_gateways) {
      if (live->contains(name)) both += (both.empty() ? "'" : ", '") + name + "'";
    }
    if (!both.empty()) {
      return Error{ErrorCode::kInvalidValue,
                   options.file + ": gateway " + both + " of the recording is live on domain " +
                       std::to_string(options.domain) +
                       ": its state and the recorded one would mix; nothing was published "
                       "(replay into another --domain, or give --into-live-gateways)"};
    }
  }
  std::map<std::string, std::unique_ptr<recording::TopicWriter>> writers;
  std::map<std::uint16_t, Route> routes;
  for (const auto& [id, channel] : contents.channels) {
    const std::string topic = dds_topic_of(channel);
    if (!selected(options, topic)) continue;
    auto& writer = writers[topic];
    if (!writer) {
      auto opened = recording::find_topic(topic)->open_writer(**participant);
      if (!opened) return opened.error();
      writer = std::move(*opened);
    }
    routes[id] = Route{writer.get(), is_disposal(channel), channel.topic};
  }

  ReplayReport report;
  const SteadyTime give_up = std::chrono::steady_clock::now() + options.wait_for_readers;
  while (!stop && std::chrono::steady_clock::now() < give_up &&
         !std::all_of(writers.begin(), writers.end(),
                      [](const auto& entry) { return entry.second->matched_readers() > 0; })) {
    std::this_thread::sleep_for(10ms);
  }

  report.clock_steps = steps.steps();
  const auto start_ns = static_cast<std::uint64_t>(options.start.count());
  const std::uint64_t end_ns =
      options.end ? static_cast<std::uint64_t>(options.end->count()) : UINT64_MAX;
  do {
    const SteadyTime wall_start = std::chrono::steady_clock::now();
    recording::ClockSteps pass_steps;  // the same offsets as the first pass's
    auto pass = mcap::read_messages(
        **file, [&](const mcap::Channel& channel, const mcap::Message& message) {
          if (stop) return;
          const std::uint64_t at = pass_steps.next(message.log_time, message.publish_time);
          const auto route = routes.find(channel.id);
          if (route == routes.end() || at < start_ns || at > end_ns) return;
          const auto offset = std::chrono::duration<double, std::nano>(
              static_cast<double>(at - start_ns) / options.rate);
          const SteadyTime due = wall_start + std::chrono::duration_cast<Duration>(offset);
          // Sleep in slices, so that a signal is noticed during a long gap.
          for (SteadyTime now = std::chrono::steady_clock::now(); now < due && !stop;
               now = std::chrono::steady_clock::now()) {
            std::this_thread::sleep_until(std::min(due, now + kStopCheck));
          }
          if (stop) return;
          const Duration late = std::chrono::steady_clock::now() - due;
          if (late > report.worst_lateness) {
            report.worst_lateness = late;
            report.worst_index = report.published + report.failed + 1;
          }
          if (late > 1ms) ++report.late_over_1ms;
          const auto& [writer, disposed, topic] = route->second;
          const Status published = disposed ? writer->dispose(message.data, message.publish_time)
                                            : writer->write(message.data, message.publish_time);
          if (!published) {
            ++report.failed;
            report.last_failure =
                topic + " #" + std::to_string(message.sequence) + ": " + published.error().reason;
            return;
          }
          ++report.published;
          ++report.per_topic[topic];
        });
    if (!pass) return pass.error();
    ++report.loops;
  } while (options.loop && !stop);
  // Reliable readers get the last messages before the writers go.
  for (auto& [topic, writer] : writers) (void)writer->wait_for_acknowledgments(2000ms);
  return report;
}

}  // namespace teejet::replay
