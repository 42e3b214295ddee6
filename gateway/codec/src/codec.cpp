#include "teejet/codec/codec.hpp"

#include <array>
#include <charconv>
#include <cstdio>
#include <optional>

#include "message_table.hpp"

namespace teejet::codec {
namespace detail {
namespace {

template <class T>
constexpr auto kSpec = spec(std::type_identity<T>{});

// Each direction's ids must be unique, or dispatch by the first byte would be ambiguous.
template <class... Ts>
constexpr bool ids_unique(std::type_identity<std::variant<Ts...>>) {
  const std::array ids{kSpec<Ts>.id...};
  for (std::size_t i = 0; i < ids.size(); ++i) {
    for (std::size_t j = i + 1; j < ids.size(); ++j) {
      if (ids[i] == ids[j]) return false;
    }
  }
  return true;
}
static_assert(ids_unique(std::type_identity<ToValveMessage>{}));
static_assert(ids_unique(std::type_identity<FromValveMessage>{}));

template <class Msg>
FieldError encode_fields(const Msg& msg, MutableBytes out) {
  FieldError failure;
  std::apply([&](const auto&... f) { (void)((failure = f.encode(msg, out), !failure) && ...); },
             kSpec<Msg>.fields);
  return failure;
}

template <class Msg>
Result<Msg> decode_fields(Bytes payload) {
  constexpr auto& s = kSpec<Msg>;
  if (payload.size() < s.length()) {
    return Error{ErrorCode::kTooShort, std::string(s.name) + " needs " +
                                           std::to_string(s.length()) + " bytes, got " +
                                           std::to_string(payload.size())};
  }
  Msg msg{};
  FieldError failure;
  std::apply([&](const auto&... f) { (void)((failure = f.decode(payload, msg), !failure) && ...); },
             s.fields);
  if (failure) {
    failure->reason = std::string(s.name) + ": " + failure->reason;
    return *std::move(failure);
  }
  return msg;
}

template <class Variant>
struct Dispatch;

template <class... Ts>
struct Dispatch<std::variant<Ts...>> {
  using Message = std::variant<Ts...>;

  static Result<Message> decode(Bytes payload, Flow flow) {
    if (payload.empty()) return Error{ErrorCode::kTooShort, "no data bytes: message id missing"};
    std::optional<Result<Message>> decoded;
    const auto try_one = [&](auto identity) {
      using T = typename decltype(identity)::type;
      if (kSpec<T>.id != payload[0]) return false;
      auto one = decode_fields<T>(payload);
      decoded =
          one ? Result<Message>(Message{std::move(one).value()}) : Result<Message>(one.error());
      return true;
    };
    (try_one(std::type_identity<Ts>{}) || ...);
    if (!decoded) {
      return Error{ErrorCode::kUnknownMessageId,
                   "unknown message id " + hex_byte(payload[0]) + " " + to_string(flow)};
    }
    return *std::move(decoded);
  }

  static Result<CanFrame> encode(const Message& message, std::uint32_t can_id,
                                 const EncodeOptions& options) {
    return std::visit(
        [&](const auto& msg) -> Result<CanFrame> {
          using T = std::decay_t<decltype(msg)>;
          CanFrame frame;
          frame.id = can_id;
          frame.data.fill(options.pad_byte);
          frame.data[0] = kSpec<T>.id;
          if (auto failure = encode_fields(msg, frame.data)) {
            failure->reason = std::string(kSpec<T>.name) + ": " + failure->reason;
            return *std::move(failure);
          }
          frame.dlc = static_cast<std::uint8_t>(options.pad_to_eight ? CanFrame::kMaxData
                                                                     : kSpec<T>.length());
          return frame;
        },
        message);
  }
};

template <class Variant>
std::uint8_t id_of(const Variant& message) {
  return std::visit([](const auto& m) { return kSpec<std::decay_t<decltype(m)>>.id; }, message);
}

template <class Variant>
std::string_view name_of(const Variant& message) {
  return std::visit([](const auto& m) { return kSpec<std::decay_t<decltype(m)>>.name; }, message);
}

template <class Variant>
void visit_fields(const Variant& message, const FieldVisitor& visitor) {
  std::visit(
      [&](const auto& msg) {
        std::apply([&](const auto&... f) { (f.visit(msg, visitor), ...); },
                   kSpec<std::decay_t<decltype(msg)>>.fields);
      },
      message);
}

Result<std::uint8_t> check_valve_address(std::uint8_t address) {
  if (is_valve_address(address)) return address;
  return Error{ErrorCode::kNotValveAddress,
               "address " + hex_byte(address) + " is outside the valve range 0xD8..0xF7"};
}

template <class T>
std::string_view enum_name(T value) {
  const auto* entry = find_enum<T>(static_cast<std::uint8_t>(value));
  return entry != nullptr ? entry->name : std::string_view("invalid");
}

}  // namespace

std::string format_number(double value) {
  std::array<char, 32> text{};
  const auto [end, ec] = std::to_chars(text.data(), text.data() + text.size(), value);
  return ec == std::errc() ? std::string(text.data(), end) : std::string("?");
}

std::string hex_byte(std::uint8_t value) { return hex_id(value, 2); }

std::string hex_id(std::uint32_t value, int digits) {
  std::array<char, 16> text{};
  std::snprintf(text.data(), text.size(), "0x%0*X", digits, value);
  return text.data();
}

}  // namespace detail

using detail::Dispatch;

const char* to_string(Flow flow) { return flow == Flow::kToValve ? "to_valve" : "from_valve"; }

Result<Route> route_of(const CanFrame& frame) {
  if (frame.remote) return Error{ErrorCode::kNotExtendedFrame, "remote request frame"};
  if (!frame.extended) {
    return Error{ErrorCode::kNotExtendedFrame,
                 "11-bit identifier " + detail::hex_id(frame.id, 3) + " is not a valve frame"};
  }
  if ((frame.id & 0xFFFF0000) != kIdBase) {
    return Error{ErrorCode::kNotThisPgn,
                 "identifier " + detail::hex_id(frame.id, 8) + " is not 0x18EFxxxx (PGN 0xEF00)"};
  }
  const auto destination = static_cast<std::uint8_t>(frame.id >> 8);
  const auto source = static_cast<std::uint8_t>(frame.id);
  Route route{};
  if (source == kControllerAddress && destination != kControllerAddress) {
    route = {Flow::kToValve, destination};
  } else if (destination == kControllerAddress && source != kControllerAddress) {
    route = {Flow::kFromValve, source};
  } else {
    return Error{ErrorCode::kNotControllerTraffic,
                 "from " + detail::hex_byte(source) + " to " + detail::hex_byte(destination) +
                     ": neither side is the controller or both are"};
  }
  if (auto checked = detail::check_valve_address(route.valve_address); !checked) {
    return checked.error();
  }
  return route;
}

Result<ToValveMessage> decode_to_valve(std::span<const std::uint8_t> payload) {
  return Dispatch<ToValveMessage>::decode(payload, Flow::kToValve);
}

Result<FromValveMessage> decode_from_valve(std::span<const std::uint8_t> payload) {
  return Dispatch<FromValveMessage>::decode(payload, Flow::kFromValve);
}

Result<DecodedFrame> decode(const CanFrame& frame) {
  auto route = route_of(frame);
  if (!route) return route.error();
  if (route->flow == Flow::kToValve) {
    auto message = decode_to_valve(frame.payload());
    if (!message) return message.error();
    return DecodedFrame{*route, AnyMessage{std::in_place_index<0>, std::move(message).value()}};
  }
  auto message = decode_from_valve(frame.payload());
  if (!message) return message.error();
  return DecodedFrame{*route, AnyMessage{std::in_place_index<1>, std::move(message).value()}};
}

Result<CanFrame> encode(std::uint8_t valve_address, const ToValveMessage& message,
                        const EncodeOptions& options) {
  if (auto checked = detail::check_valve_address(valve_address); !checked) return checked.error();
  return Dispatch<ToValveMessage>::encode(message, to_valve_id(valve_address), options);
}

Result<CanFrame> encode(std::uint8_t valve_address, const FromValveMessage& message,
                        const EncodeOptions& options) {
  if (auto checked = detail::check_valve_address(valve_address); !checked) return checked.error();
  return Dispatch<FromValveMessage>::encode(message, from_valve_id(valve_address), options);
}

bool is_run_command(const ToValveMessage& message) {
  return std::visit(
      [](const auto& m) { return detail::kSpec<std::decay_t<decltype(m)>>.run_command; }, message);
}

std::optional<std::uint8_t> reply_id(const ToValveMessage& message) {
  return std::visit([](const auto& m) { return detail::kSpec<std::decay_t<decltype(m)>>.reply; },
                    message);
}

std::uint8_t message_id(const ToValveMessage& message) { return detail::id_of(message); }
std::uint8_t message_id(const FromValveMessage& message) { return detail::id_of(message); }
std::string_view message_name(const ToValveMessage& message) { return detail::name_of(message); }
std::string_view message_name(const FromValveMessage& message) { return detail::name_of(message); }

void for_each_field(const ToValveMessage& message, const FieldVisitor& visit) {
  detail::visit_fields(message, visit);
}
void for_each_field(const FromValveMessage& message, const FieldVisitor& visit) {
  detail::visit_fields(message, visit);
}

std::string format_serial(std::uint32_t serial) {
  std::array<char, 16> text{};
  std::snprintf(text.data(), text.size(), "TJV%06u", serial);
  return text.data();
}

Result<std::uint32_t> parse_serial(std::string_view text) {
  const std::string original(text);
  if (text.size() >= 3 && (text[0] == 'T' || text[0] == 't') &&
      (text[1] == 'J' || text[1] == 'j') && (text[2] == 'V' || text[2] == 'v')) {
    text.remove_prefix(3);
  }
  std::uint32_t value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (text.empty() || ec != std::errc() || end != text.data() + text.size()) {
    return Error{ErrorCode::kInvalidValue,
                 "serial '" + original + "' is not TJV followed by digits, nor digits alone"};
  }
  if (value > 0xFFFFFF) {
    return Error{ErrorCode::kOutOfRange,
                 "serial '" + original + "' does not fit the 24 bits of I'm Here"};
  }
  return value;
}

std::string format_version(const SoftwareVersion& version) {
  std::array<char, 32> text{};
  std::snprintf(text.data(), text.size(), "%u.%02u", version.major, version.minor);
  std::string result = text.data();
  const auto test = static_cast<unsigned char>(version.test);
  if (test >= 0x21 && test <= 0x7E) {
    result += version.test;
  } else if (test != 0) {
    // Keep the text printable ASCII (it ends up in JSON and DDS strings); show the raw byte.
    std::snprintf(text.data(), text.size(), "[0x%02X]", test);
    result += text.data();
  }
  return result;
}

std::string_view to_string(Direction direction) { return detail::enum_name(direction); }
std::string_view to_string(TargetDirection direction) { return detail::enum_name(direction); }
std::string_view to_string(Rotation rotation) { return detail::enum_name(rotation); }
std::string_view to_string(BaudAction action) { return detail::enum_name(action); }

}  // namespace teejet::codec
