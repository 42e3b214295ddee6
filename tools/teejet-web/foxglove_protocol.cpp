#include "foxglove_protocol.hpp"

#include <algorithm>
#include <cstring>
#include <nlohmann/json.hpp>

#include "page_command.hpp"
#include "teejet/recording/catalog.hpp"

namespace teejet::web::foxglove {
namespace {

using nlohmann::json;

// A client message is a few levels deep ({"op","channels":[{...}]}); deeper is refused unparsed.
constexpr int kMaxClientJsonDepth = 4;
constexpr std::uint8_t kMessageDataOpcode = 1;

Error refused(std::string reason) { return Error{ErrorCode::kInvalidValue, std::move(reason)}; }

std::vector<Channel> make_channels() {
  std::vector<Channel> made;
  const auto& types = recording::topic_types();
  for (std::size_t topic = 0; topic < types.size(); ++topic) {
    const auto& type = types[topic];
    made.push_back({static_cast<std::uint32_t>(made.size() + 1), topic, false, type.topic});
    if (type.keyed && type.durable) {
      made.push_back({static_cast<std::uint32_t>(made.size() + 1), topic, true,
                      type.topic + std::string(recording::kDisposedSuffix)});
    }
  }
  return made;
}

void put_le(std::string& out, std::uint64_t value, int bytes) {
  for (int i = 0; i < bytes; ++i) out.push_back(static_cast<char>((value >> (8 * i)) & 0xff));
}

// A uint32 field of `object`, or the refusal naming it within `what`.
Result<std::uint32_t> id_field(const json& object, const char* field, std::string_view what) {
  if (!object.is_object() || !object.contains(field)) {
    return refused(std::string(what) + ": missing \"" + field + "\"");
  }
  const json& value = object.at(field);
  if (!value.is_number_unsigned() || value.get<std::uint64_t>() > UINT32_MAX) {
    return refused(std::string(what) + ": \"" + field + "\" must be an integer from 0 to " +
                   std::to_string(UINT32_MAX));
  }
  return value.get<std::uint32_t>();
}

Result<std::string> string_field(const json& object, const char* field, std::string_view what) {
  if (!object.contains(field) || !object.at(field).is_string()) {
    return refused(std::string(what) + ": \"" + field + "\" must be a string");
  }
  return object.at(field).get<std::string>();
}

// The array `field` of `message`, at most `limit` long.
Result<const json*> array_field(const json& message, const char* field, std::string_view op,
                                std::size_t limit) {
  if (!message.contains(field) || !message.at(field).is_array()) {
    return refused(std::string(op) + ": \"" + field + "\" must be an array");
  }
  const json& array = message.at(field);
  if (array.size() > limit) {
    return refused(std::string(op) + ": " + std::to_string(array.size()) + " entries in \"" +
                   field + "\", at most " + std::to_string(limit));
  }
  return &array;
}

Result<ClientText> parse_subscribe(const json& message) {
  const auto entries = array_field(message, "subscriptions", "subscribe", kMaxSubscriptions);
  if (!entries) return entries.error();
  Subscribe subscribe;
  for (const json& entry : **entries) {
    const auto id = id_field(entry, "id", "subscribe");
    if (!id) return id.error();
    const auto channel = id_field(entry, "channelId", "subscribe");
    if (!channel) return channel.error();
    subscribe.subscriptions.push_back({*id, *channel});
  }
  return ClientText{std::move(subscribe)};
}

Result<std::vector<std::uint32_t>> ids(const json& message, const char* field, std::string_view op,
                                       std::size_t limit) {
  const auto entries = array_field(message, field, op, limit);
  if (!entries) return entries.error();
  std::vector<std::uint32_t> out;
  for (const json& entry : **entries) {
    if (!entry.is_number_unsigned() || entry.get<std::uint64_t>() > UINT32_MAX) {
      return refused(std::string(op) + ": \"" + field + "\" must hold integers from 0 to " +
                     std::to_string(UINT32_MAX));
    }
    out.push_back(entry.get<std::uint32_t>());
  }
  return out;
}

Result<ClientText> parse_client_advertise(const json& message) {
  const auto entries = array_field(message, "channels", "advertise", kMaxClientChannels);
  if (!entries) return entries.error();
  ClientAdvertise advertise;
  for (const json& entry : **entries) {
    const auto id = id_field(entry, "id", "advertise");
    if (!id) return id.error();
    auto topic = string_field(entry, "topic", "advertise");
    if (!topic) return topic.error();
    auto encoding = string_field(entry, "encoding", "advertise");
    if (!encoding) return encoding.error();
    auto schema_name = string_field(entry, "schemaName", "advertise");
    if (!schema_name) return schema_name.error();
    advertise.channels.push_back(
        {*id, std::move(*topic), std::move(*encoding), std::move(*schema_name)});
  }
  return ClientText{std::move(advertise)};
}

int hex_digit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

std::optional<std::string> percent_decoded(std::string_view text) {
  std::string out;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '+') {
      out.push_back(' ');
    } else if (text[i] != '%') {
      out.push_back(text[i]);
    } else {
      if (i + 2 >= text.size()) return std::nullopt;
      const int high = hex_digit(text[i + 1]);
      const int low = hex_digit(text[i + 2]);
      if (high < 0 || low < 0) return std::nullopt;
      out.push_back(static_cast<char>(high * 16 + low));
      i += 2;
    }
  }
  return out;
}

}  // namespace

std::optional<std::string_view> choose_subprotocol(std::string_view offered) {
  while (!offered.empty()) {
    const auto comma = offered.find(',');
    std::string_view name = offered.substr(0, comma);
    offered = comma == std::string_view::npos ? std::string_view() : offered.substr(comma + 1);
    while (!name.empty() && (name.front() == ' ' || name.front() == '\t')) name.remove_prefix(1);
    while (!name.empty() && (name.back() == ' ' || name.back() == '\t')) name.remove_suffix(1);
    for (const std::string_view ours : kSubprotocols) {
      if (name == ours) return ours;
    }
  }
  return std::nullopt;
}

const std::vector<Channel>& channels() {
  static const std::vector<Channel> kChannels = make_channels();
  return kChannels;
}

const Channel* find_channel(std::uint32_t id) {
  const auto& all = channels();
  if (id == 0 || id > all.size()) return nullptr;
  return &all[id - 1];
}

const Channel* find_channel(std::string_view topic) {
  const auto& all = channels();
  const auto found =
      std::find_if(all.begin(), all.end(), [&](const Channel& c) { return c.name == topic; });
  return found == all.end() ? nullptr : &*found;
}

std::uint32_t channel_id(std::size_t topic, bool disposed) {
  // By topic index: the samples' channel and the disposals' (0: none).
  static const std::vector<std::pair<std::uint32_t, std::uint32_t>> kIds = [] {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> ids(recording::topic_types().size());
    for (const Channel& channel : channels()) {
      (channel.disposed ? ids[channel.topic].second : ids[channel.topic].first) = channel.id;
    }
    return ids;
  }();
  if (topic >= kIds.size()) return 0;
  return disposed ? kIds[topic].second : kIds[topic].first;
}

std::string server_info(std::string_view name, bool client_publish, std::string_view session_id) {
  json capabilities = json::array();
  json info{{"op", "serverInfo"},
            {"name", name},
            {"metadata", json::object()},
            {"sessionId", session_id}};
  if (client_publish) {
    capabilities.push_back("clientPublish");
    info["supportedEncodings"] = json::array({recording::kMessageEncoding});
  }
  info["capabilities"] = std::move(capabilities);
  return info.dump();
}

std::string advertise(const std::vector<Channel>& channels) {
  const auto& types = recording::topic_types();
  const std::string schema(recording::valve_idl());
  json list = json::array();
  for (const Channel& channel : channels) {
    list.push_back({{"id", channel.id},
                    {"topic", channel.name},
                    {"encoding", recording::kMessageEncoding},
                    {"schemaName", types[channel.topic].type_name},
                    {"schema", schema},
                    {"schemaEncoding", recording::kSchemaEncoding}});
  }
  return json{{"op", "advertise"}, {"channels", std::move(list)}}.dump();
}

std::string status(Level level, std::string_view message) {
  return json{{"op", "status"}, {"level", static_cast<int>(level)}, {"message", message}}.dump(
      -1, ' ', false, json::error_handler_t::replace);
}

std::string message_data(std::uint32_t subscription, std::uint64_t timestamp_ns,
                         std::span<const std::uint8_t> payload) {
  std::string frame;
  frame.reserve(13 + payload.size());
  frame.push_back(static_cast<char>(kMessageDataOpcode));
  put_le(frame, subscription, 4);
  put_le(frame, timestamp_ns, 8);
  frame.append(reinterpret_cast<const char*>(payload.data()), payload.size());
  return frame;
}

Result<ClientText> parse_client_text(std::string_view text) {
  if (text.size() > kMaxClientMessageBytes) {
    return refused("message of " + std::to_string(text.size()) + " bytes is over the limit of " +
                   std::to_string(kMaxClientMessageBytes));
  }
  if (!nested_within(text, kMaxClientJsonDepth)) {
    return refused("JSON nested deeper than " + std::to_string(kMaxClientJsonDepth) + " levels");
  }
  const json message = json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (message.is_discarded()) return refused("malformed JSON");
  if (!message.is_object() || !message.contains("op") || !message.at("op").is_string()) {
    return refused("a message must be a JSON object with a string \"op\"");
  }
  const auto& op = message.at("op").get_ref<const std::string&>();
  if (op == "subscribe") return parse_subscribe(message);
  if (op == "unsubscribe") {
    auto subscriptions = ids(message, "subscriptionIds", op, kMaxSubscriptions);
    if (!subscriptions) return subscriptions.error();
    return ClientText{Unsubscribe{std::move(*subscriptions)}};
  }
  if (op == "advertise") return parse_client_advertise(message);
  if (op == "unadvertise") {
    auto client_channels = ids(message, "channelIds", op, kMaxClientChannels);
    if (!client_channels) return client_channels.error();
    return ClientText{ClientUnadvertise{std::move(*client_channels)}};
  }
  return refused("op \"" + op.substr(0, 64) +
                 "\" is not served: teejet-web serves subscribe, unsubscribe and, when it "
                 "announces clientPublish, advertise and unadvertise");
}

Result<ClientData> parse_client_binary(std::span<const std::uint8_t> frame) {
  if (frame.empty() || frame[0] != kMessageDataOpcode) {
    return refused("binary message with opcode " +
                   (frame.empty() ? std::string("(none)") : std::to_string(frame[0])) +
                   ": teejet-web takes only Client Message Data (1)");
  }
  if (frame.size() < 5)
    return refused("Client Message Data of " + std::to_string(frame.size()) +
                   " bytes: shorter than its 5-byte header");
  std::uint32_t channel = 0;
  for (std::size_t i = 0; i < 4; ++i)
    channel |= static_cast<std::uint32_t>(frame[1 + i]) << (8 * i);
  return ClientData{channel, frame.subspan(std::size_t{5})};
}

std::optional<std::string> query_parameter(std::string_view target, std::string_view name) {
  const auto question = target.find('?');
  if (question == std::string_view::npos) return std::nullopt;
  std::string_view query = target.substr(question + 1);
  if (const auto hash = query.find('#'); hash != std::string_view::npos) {
    query = query.substr(0, hash);
  }
  while (!query.empty()) {
    const auto amp = query.find('&');
    const std::string_view pair = query.substr(0, amp);
    query = amp == std::string_view::npos ? std::string_view() : query.substr(amp + 1);
    const auto equals = pair.find('=');
    if (pair.substr(0, equals) != name) continue;
    if (equals == std::string_view::npos) return std::string();
    return percent_decoded(pair.substr(equals + 1));
  }
  return std::nullopt;
}

}  // namespace teejet::web::foxglove
