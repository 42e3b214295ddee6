#include "teejet/codec/codec.hpp"

#include <array>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <optional>

#include "message_table.hpp"
#include "teejet/codec/table.hpp"

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
  if (failure) return in_context(s.name, *std::move(failure));
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
            return in_context(kSpec<T>.name, *std::move(failure));
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

// ---- The table as data (table.hpp) ------------------------------------------------------

std::string_view without_prefix(std::string_view name, std::string_view prefix) {
  return name.starts_with(prefix) ? name.substr(prefix.size()) : name;
}

std::string_view without_suffix(std::string_view name, std::string_view suffix) {
  return name.ends_with(suffix) ? name.substr(0, name.size() - suffix.size()) : name;
}

template <class Msg>
MessageInfo info_of(Flow flow) {
  constexpr auto& s = kSpec<Msg>;
  MessageInfo info;
  info.id = s.id;
  info.name = s.name;
  info.flow = flow;
  std::apply([&](const auto&... f) { (info.fields.push_back(f.info()), ...); }, s.fields);
  info.run_command = s.run_command;
  info.reply = s.reply;
  info.telemetry_request = s.telemetry_request;
  if (s.error) info.error_kind = without_suffix(s.name, "_error");
  return info;
}

template <class... Ts>
std::vector<MessageInfo> infos_of(std::type_identity<std::variant<Ts...>>, Flow flow) {
  return {info_of<Ts>(flow)...};
}

// Both directions, in the order of the variants (the sheet's); a request's subject is its name
// without "request_", and its reply has the same subject.
struct Tables {
  std::vector<MessageInfo> to_valve =
      infos_of(std::type_identity<ToValveMessage>{}, Flow::kToValve);
  std::vector<MessageInfo> from_valve =
      infos_of(std::type_identity<FromValveMessage>{}, Flow::kFromValve);
  std::vector<std::string_view> telemetry;
  std::vector<std::string_view> errors;

  Tables() {
    for (MessageInfo& request : to_valve) {
      if (!request.reply) continue;
      request.subject = without_prefix(request.name, "request_");
      if (request.telemetry_request) telemetry.push_back(request.subject);
      for (MessageInfo& reply : from_valve) {
        if (reply.id == *request.reply) reply.subject = request.subject;
      }
    }
    for (const MessageInfo& message : from_valve) {
      if (!message.error_kind.empty()) errors.push_back(message.error_kind);
    }
  }
};

const Tables& tables() {
  static const Tables made;
  return made;
}

// The message of the variant's alternative `index`, every field zero.
template <class... Ts>
std::variant<Ts...> blank(std::type_identity<std::variant<Ts...>>, std::size_t index) {
  static const std::array<std::variant<Ts...>, sizeof...(Ts)> blanks{std::variant<Ts...>{Ts{}}...};
  return blanks.at(index);
}

// A word as people type it, in the table's spelling: lower case, '_' for '-', and the older
// words of the command line (valvectl request dps|speed, valve-sim's min-dps) for today's.
std::string table_spelling(std::string_view word) {
  std::string spelled(word);
  for (char& c : spelled) {
    if (c == '-') c = '_';
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  }
  static constexpr std::array<std::pair<std::string_view, std::string_view>, 3> kOlderWords{{
      {"dps", "degrees_per_second"},
      {"speed", "speed_direction"},
      {"min_dps", "min_degrees_per_second"},
  }};
  for (const auto& [older, today] : kOlderWords) {
    if (spelled == older) return std::string(today);
  }
  return spelled;
}

template <class Variant>
Status set_field_of(Variant& message, std::string_view name, const FieldValue& value) {
  return std::visit(
      [&](auto& msg) -> Status {
        constexpr auto& s = kSpec<std::decay_t<decltype(msg)>>;
        std::optional<FieldError> result;
        std::apply(
            [&](const auto&... f) {
              (void)((f.name == name ? (result = f.assign(msg, value), true) : false) || ...);
            },
            s.fields);
        if (!result) {
          return Error{ErrorCode::kInvalidValue,
                       std::string(s.name) + " has no field " + std::string(name), 0,
                       std::string(name), "is not a field of " + std::string(s.name)};
        }
        if (*result) return in_context(s.name, **std::move(result));
        return {};
      },
      message);
}

template <class Variant>
std::optional<FieldValue> field_value_of(const Variant& message, std::string_view name) {
  std::optional<FieldValue> found;
  visit_fields(message, [&](std::string_view field, const FieldValue& value) {
    if (field == name) found = value;
  });
  return found;
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

std::string format_address(std::uint8_t address) {
  std::array<char, 8> text{};
  std::snprintf(text.data(), text.size(), "0x%02X", address);
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

Result<SoftwareVersion> parse_version(std::string_view text) {
  const std::string original(text);
  const auto fail = [&] {
    return Error{ErrorCode::kInvalidValue,
                 "version '" + original +
                     "' is not MAJOR.MINOR with an optional test character, e.g. 1.02e"};
  };
  const auto dot = text.find('.');
  if (dot == std::string_view::npos) return fail();
  unsigned major = 0;
  unsigned minor = 0;
  const auto major_text = text.substr(0, dot);
  const auto [major_end, major_ec] =
      std::from_chars(major_text.data(), major_text.data() + major_text.size(), major);
  if (major_text.empty() || major_ec != std::errc() ||
      major_end != major_text.data() + major_text.size() || major > 255) {
    return fail();
  }
  auto rest = text.substr(dot + 1);
  const auto [minor_end, minor_ec] = std::from_chars(rest.data(), rest.data() + rest.size(), minor);
  if (minor_ec != std::errc() || minor > 255) return fail();
  rest.remove_prefix(static_cast<std::size_t>(minor_end - rest.data()));
  char test = 0;
  if (rest.size() == 1 && rest[0] >= 0x21 && rest[0] <= 0x7E) {
    test = rest[0];
  } else if (!rest.empty()) {
    return fail();
  }
  return SoftwareVersion{major, minor, test};
}

// ---- table.hpp ------------------------------------------------------------------------------

const std::vector<MessageInfo>& message_table(Flow flow) {
  return flow == Flow::kToValve ? detail::tables().to_valve : detail::tables().from_valve;
}

const MessageInfo& describe(const ToValveMessage& message) {
  return detail::tables().to_valve.at(message.index());
}

const MessageInfo& describe(const FromValveMessage& message) {
  return detail::tables().from_valve.at(message.index());
}

std::optional<ToValveMessage> to_valve_message(std::uint8_t id) {
  const auto& messages = detail::tables().to_valve;
  for (std::size_t i = 0; i < messages.size(); ++i) {
    if (messages[i].id == id) return detail::blank(std::type_identity<ToValveMessage>{}, i);
  }
  return std::nullopt;
}

std::optional<FromValveMessage> from_valve_message(std::uint8_t id) {
  const auto& messages = detail::tables().from_valve;
  for (std::size_t i = 0; i < messages.size(); ++i) {
    if (messages[i].id == id) return detail::blank(std::type_identity<FromValveMessage>{}, i);
  }
  return std::nullopt;
}

std::optional<FromValveMessage> reply_to(const ToValveMessage& request) {
  const auto reply = describe(request).reply;
  return reply ? from_valve_message(*reply) : std::nullopt;
}

const FieldInfo* find_field(const MessageInfo& message, std::string_view name) {
  for (const FieldInfo& field : message.fields) {
    if (field.name == name) return &field;
  }
  return nullptr;
}

std::string_view subject(const ToValveMessage& message) { return describe(message).subject; }
std::string_view subject(const FromValveMessage& message) { return describe(message).subject; }

const std::vector<std::string_view>& telemetry_names() { return detail::tables().telemetry; }

std::optional<ToValveMessage> telemetry_request(std::string_view word) {
  const std::string spelled = detail::table_spelling(word);
  const auto& requests = detail::tables().to_valve;
  for (std::size_t i = 0; i < requests.size(); ++i) {
    if (requests[i].telemetry_request && requests[i].subject == spelled) {
      return detail::blank(std::type_identity<ToValveMessage>{}, i);
    }
  }
  return std::nullopt;
}

const std::vector<std::string_view>& error_kinds() { return detail::tables().errors; }

std::optional<FromValveMessage> error_message(std::string_view kind) {
  const std::string spelled = detail::table_spelling(kind);
  const auto& messages = detail::tables().from_valve;
  for (std::size_t i = 0; i < messages.size(); ++i) {
    if (!messages[i].error_kind.empty() && messages[i].error_kind == spelled) {
      return detail::blank(std::type_identity<FromValveMessage>{}, i);
    }
  }
  return std::nullopt;
}

std::string_view error_kind(const FromValveMessage& message) {
  return describe(message).error_kind;
}

Status set_field(ToValveMessage& message, std::string_view field, const FieldValue& value) {
  return detail::set_field_of(message, field, value);
}

Status set_field(FromValveMessage& message, std::string_view field, const FieldValue& value) {
  return detail::set_field_of(message, field, value);
}

std::optional<FieldValue> field_value(const ToValveMessage& message, std::string_view field) {
  return detail::field_value_of(message, field);
}

std::optional<FieldValue> field_value(const FromValveMessage& message, std::string_view field) {
  return detail::field_value_of(message, field);
}

FromValveMessage as_sent(const FromValveMessage& message) {
  const auto frame = encode(kFirstValveAddress, message);
  if (!frame) return message;
  auto decoded = decode_from_valve(frame->payload());
  return decoded ? std::move(decoded).value() : message;
}

ToValveMessage as_sent(const ToValveMessage& message) {
  const auto frame = encode(kFirstValveAddress, message);
  if (!frame) return message;
  auto decoded = decode_to_valve(frame->payload());
  return decoded ? std::move(decoded).value() : message;
}

Status check_valve_limits(double closed_degrees, double opened_degrees) {
  using detail::format_number;
  const auto limit = [](const char* field, std::string complaint) {
    return field_error(ErrorCode::kOutOfRange, field, std::move(complaint));
  };
  if (!std::isfinite(closed_degrees)) return limit("closed_degrees", "must be a number");
  if (!std::isfinite(opened_degrees)) return limit("opened_degrees", "must be a number");
  if (opened_degrees != kFullTurnOpenedDegrees && opened_degrees > kMaxLimitedOpenedDegrees) {
    return limit("opened_degrees", format_number(opened_degrees) +
                                       " is neither 360 (full turn) nor at most 340 (the sheet)");
  }
  if (opened_degrees == kFullTurnOpenedDegrees) {
    if (closed_degrees < 0.0 || closed_degrees >= kFullTurnOpenedDegrees) {
      return limit("closed_degrees", format_number(closed_degrees) + " is outside [0, 360)");
    }
    return {};
  }
  if (closed_degrees < 0.0 || closed_degrees >= opened_degrees) {
    return limit("closed_degrees", format_number(closed_degrees) +
                                       " must be at least 0 and below opened_degrees " +
                                       format_number(opened_degrees));
  }
  return {};
}

std::string_view to_string(Direction direction) { return detail::enum_name(direction); }
std::string_view to_string(TargetDirection direction) { return detail::enum_name(direction); }
std::string_view to_string(Rotation rotation) { return detail::enum_name(rotation); }
std::string_view to_string(BaudAction action) { return detail::enum_name(action); }

}  // namespace teejet::codec
