#pragma once

// The Foxglove WebSocket protocol (foxglove/ws-protocol, docs/spec.md, version 1) as teejet-web
// speaks it to Foxglove and Lichtblick: the messages it sends, built, and the client's messages,
// parsed and bounded. No network here, so that the unit tests cover every byte.
//
// Channels are the recording's (gateway/recording): every teejet topic with encoding "cdr",
// schema encoding "omgidl", the type's name as schema name and the whole IDL as schema, and a
// "<topic>/disposed" channel for the disposals of each keyed state topic, so that a layout made
// on a recording works live.

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

#include "teejet/core/result.hpp"

namespace teejet::web::foxglove {

// Both names the protocol goes by: the spec's, and the one Foxglove's SDK servers and newer
// apps offer. The messages are the same.
inline constexpr std::array<std::string_view, 2> kSubprotocols{"foxglove.websocket.v1",
                                                               "foxglove.sdk.v1"};

// The first subprotocol of a Sec-WebSocket-Protocol header (comma-separated, in the client's
// order of preference) that teejet-web speaks; nullopt when it speaks none of them.
std::optional<std::string_view> choose_subprotocol(std::string_view offered);

struct Channel {
  std::uint32_t id = 0;
  std::size_t topic = 0;  // the index of its type in recording::topic_types()
  bool disposed = false;  // the "/disposed" channel of a keyed state topic
  std::string name;       // the topic clients see
};

// Every teejet topic in the catalog's order, each keyed state topic followed by its "/disposed"
// channel; ids from 1 in that order.
const std::vector<Channel>& channels();
const Channel* find_channel(std::uint32_t id);
const Channel* find_channel(std::string_view topic);
// The id of the channel of topic index `topic`'s samples, or of its disposals; 0: none.
std::uint32_t channel_id(std::size_t topic, bool disposed);

enum class Level { kInfo = 0, kWarning = 1, kError = 2 };

// {"op":"serverInfo",...}: capabilities "clientPublish" only when a client may publish, and the
// encodings it may publish in.
std::string server_info(std::string_view name, bool client_publish, std::string_view session_id);
// {"op":"advertise","channels":[...]} of `channels`.
std::string advertise(const std::vector<Channel>& channels);
std::string status(Level level, std::string_view message);
// The binary Message Data frame: opcode 1, the subscription id and the timestamp (ns, little
// endian), then the CDR payload as it is.
std::string message_data(std::uint32_t subscription, std::uint64_t timestamp_ns,
                         std::span<const std::uint8_t> payload);

// ---- From the client ------------------------------------------------------------------------

// A text message larger than this is refused from its frame header, before it is buffered: a
// client advertise carries the IDL (16 KB) per channel, and a client publishes one topic.
inline constexpr std::size_t kMaxClientMessageBytes = 256 * 1024;
// Subscriptions and client channels one client may hold: a client subscribing to every channel
// twice over needs fewer than a hundred.
inline constexpr std::size_t kMaxSubscriptions = 1024;
inline constexpr std::size_t kMaxClientChannels = 16;

struct Subscription {
  std::uint32_t id = 0;
  std::uint32_t channel = 0;
};
struct Subscribe {
  std::vector<Subscription> subscriptions;
};
struct Unsubscribe {
  std::vector<std::uint32_t> subscriptions;
};
struct ClientChannel {
  std::uint32_t id = 0;
  std::string topic;
  std::string encoding;
  std::string schema_name;
};
struct ClientAdvertise {
  std::vector<ClientChannel> channels;
};
struct ClientUnadvertise {
  std::vector<std::uint32_t> channels;
};
using ClientText = std::variant<Subscribe, Unsubscribe, ClientAdvertise, ClientUnadvertise>;

// A client's text message; an Error whose reason the client is told (status, error level) for
// malformed JSON, a missing or mistyped field, or an op teejet-web does not serve (parameters,
// services, assets, the connection graph: it announces none of them).
Result<ClientText> parse_client_text(std::string_view text);

// A client's binary Client Message Data (opcode 1, client channel id, payload); an Error for any
// other opcode or a frame too short. The payload points into `frame`.
struct ClientData {
  std::uint32_t channel = 0;
  std::span<const std::uint8_t> payload;
};
Result<ClientData> parse_client_binary(std::span<const std::uint8_t> frame);

// The value of `name` in a request target's query ("/?token=abc%21" → "abc!"), decoded; nullopt
// when it is absent or badly escaped.
std::optional<std::string> query_parameter(std::string_view target, std::string_view name);

}  // namespace teejet::web::foxglove
