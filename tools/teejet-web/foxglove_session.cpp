#include "foxglove_session.hpp"

#include <algorithm>
#include <type_traits>
#include <utility>

#include "teejet/codec/codec.hpp"
#include "teejet/dds/topics.hpp"
#include "teejet/recording/catalog.hpp"
#include "teejet/valvePubSubTypes.h"

namespace teejet::web::foxglove {
namespace {

std::string error_status(std::string_view message) { return status(Level::kError, message); }

const std::string& command_type_name() {
  static const std::string kName = recording::find_topic(dds::topics::kCommand)->type_name;
  return kName;
}

}  // namespace

bool Outbox::post_data(std::string frame) {
  if (data_bytes_ + frame.size() > max_queued_bytes_) {
    ++dropped_;
    return false;
  }
  data_bytes_ += frame.size();
  waiting_.push_back({Kind::kBinary, false, std::move(frame)});
  return true;
}

void Outbox::post_text(std::string text) {
  waiting_.push_back({Kind::kText, false, std::move(text)});
}

bool Outbox::post_status(std::string text) {
  if (statuses_ >= kMaxQueuedStatuses) return false;
  ++statuses_;
  waiting_.push_back({Kind::kText, true, std::move(text)});
  return true;
}

std::optional<Outbox::Write> Outbox::start_write() {
  if (writing_ || waiting_.empty()) return std::nullopt;
  Queued next = std::move(waiting_.front());
  waiting_.pop_front();
  if (next.kind == Kind::kBinary) data_bytes_ -= next.bytes.size();
  if (next.status) --statuses_;
  writing_ = true;
  return Write{next.kind, std::move(next.bytes)};
}

void Outbox::write_done() { writing_ = false; }

PublishAnswer answer_publish(const Publish& publish, const client::ValveTable& table,
                             const CommandPolicy& policy, std::optional<std::string_view> token,
                             CommandSender& sender, const TokenCheck& check_token) {
  const auto not_sent = [](std::string why) {
    return PublishAnswer{Level::kError, "command not sent: " + std::move(why)};
  };
  if (const auto refusal = policy_refusal(policy, token, check_token)) return not_sent(*refusal);
  ValveCommand published;
  ValveCommandPubSubType type;
  if (const auto decoded = recording::decode_payload(publish.payload, type, &published); !decoded) {
    return not_sent("not a " + command_type_name() + " in CDR (" + decoded.error().reason + ")");
  }
  const auto checked = check_published_command(published, table);
  if (!checked) return not_sent(checked.error().reason);
  ValveCommand command = checked->command;
  command.serial(checked->serials.front());
  const auto id = sender.send(command);
  const std::string valve = codec::format_serial(command.serial());
  if (!id) return not_sent("to " + valve + ": " + id.error().reason);
  return {Level::kInfo, "command #" + std::to_string(*id) + " sent to " + valve +
                            ": its statuses follow on " + dds::topics::kCommandStatus};
}

Session::Session(std::optional<std::string> publish_refusal, std::size_t max_queued_bytes)
    : outbox(max_queued_bytes), publish_refusal_(std::move(publish_refusal)) {}

Session::Reaction Session::on_text(std::string_view text) {
  Reaction reaction;
  auto message = parse_client_text(text);
  if (!message) {
    reaction.statuses.push_back(error_status(message.error().reason));
    return reaction;
  }
  std::visit(
      [&](const auto& request) {
        using Request = std::decay_t<decltype(request)>;
        if constexpr (std::is_same_v<Request, Subscribe>) {
          subscribe(request, reaction);
        } else if constexpr (std::is_same_v<Request, Unsubscribe>) {
          unsubscribe(request, reaction);
        } else if constexpr (std::is_same_v<Request, ClientAdvertise>) {
          advertise(request, reaction);
        } else {
          unadvertise(request, reaction);
        }
      },
      *message);
  return reaction;
}

void Session::subscribe(const Subscribe& request, Reaction& reaction) {
  for (const Subscription& subscription : request.subscriptions) {
    const Channel* channel = find_channel(subscription.channel);
    if (channel == nullptr) {
      reaction.statuses.push_back(error_status(
          "subscribe: no channel " + std::to_string(subscription.channel) + " is advertised"));
    } else if (subscriptions_.count(subscription.id) != 0) {
      reaction.statuses.push_back(error_status("subscribe: subscription id " +
                                               std::to_string(subscription.id) + " is in use"));
    } else if (subscriptions_.size() >= kMaxSubscriptions) {
      reaction.statuses.push_back(error_status("subscribe: at most " +
                                               std::to_string(kMaxSubscriptions) +
                                               " subscriptions per connection"));
    } else {
      subscriptions_.emplace(subscription.id, subscription.channel);
      by_channel_[subscription.channel].push_back(subscription.id);
      reaction.subscribed.push_back(subscription);
    }
  }
}

void Session::unsubscribe(const Unsubscribe& request, Reaction& reaction) {
  for (const std::uint32_t id : request.subscriptions) {
    const auto found = subscriptions_.find(id);
    if (found == subscriptions_.end()) {
      reaction.statuses.push_back(
          status(Level::kWarning, "unsubscribe: no subscription " + std::to_string(id)));
      continue;
    }
    auto& ids = by_channel_[found->second];
    ids.erase(std::remove(ids.begin(), ids.end(), id), ids.end());
    if (ids.empty()) by_channel_.erase(found->second);
    subscriptions_.erase(found);
  }
}

void Session::advertise(const ClientAdvertise& request, Reaction& reaction) {
  if (publish_refusal_) {
    reaction.statuses.push_back(error_status("advertise refused: " + *publish_refusal_));
    return;
  }
  for (const ClientChannel& channel : request.channels) {
    std::string refusal;
    if (channel.topic != dds::topics::kCommand) {
      refusal = "only " + std::string(dds::topics::kCommand) + " takes messages from clients";
    } else if (channel.encoding != recording::kMessageEncoding) {
      refusal = "encoding \"" + channel.encoding.substr(0, 64) + "\": only \"" +
                recording::kMessageEncoding + "\"";
    } else if (channel.schema_name != command_type_name()) {
      refusal = "schema \"" + channel.schema_name.substr(0, 64) + "\": only \"" +
                command_type_name() + "\"";
    } else if (client_channels_.count(channel.id) != 0) {
      refusal = "channel id " + std::to_string(channel.id) + " is advertised already";
    } else if (client_channels_.size() >= kMaxClientChannels) {
      refusal = "at most " + std::to_string(kMaxClientChannels) + " channels per connection";
    }
    if (!refusal.empty()) {
      reaction.statuses.push_back(
          error_status("advertise of channel " + std::to_string(channel.id) + " (" +
                       channel.topic.substr(0, 64) + ") refused: " + refusal));
      continue;
    }
    client_channels_.emplace(channel.id, channel);
  }
}

void Session::unadvertise(const ClientUnadvertise& request, Reaction& reaction) {
  for (const std::uint32_t id : request.channels) {
    if (client_channels_.erase(id) == 0) {
      reaction.statuses.push_back(
          status(Level::kWarning, "unadvertise: no client channel " + std::to_string(id)));
    }
  }
}

std::variant<Publish, std::string> Session::on_binary(std::span<const std::uint8_t> frame) {
  const auto data = parse_client_binary(frame);
  if (!data) return error_status(data.error().reason);
  const auto channel = client_channels_.find(data->channel);
  if (channel == client_channels_.end()) {
    return error_status("message on client channel " + std::to_string(data->channel) +
                        ", which this connection has not advertised: not sent");
  }
  return Publish{channel->second, {data->payload.begin(), data->payload.end()}};
}

std::span<const std::uint32_t> Session::subscriptions(std::uint32_t channel) const {
  const auto found = by_channel_.find(channel);
  if (found == by_channel_.end()) return {};
  return found->second;
}

}  // namespace teejet::web::foxglove
