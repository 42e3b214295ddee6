// codec::encode of fuzzed typed messages, both directions, and decode(encode(m)).
//
// Input: direction byte (bit 0: valve to controller), alternative index byte, valve address,
// options byte (bit 0: do not pad to eight), pad byte, then the message's members in declaration
// order: unsigned and int as 4 bytes, enumerations and char as 1 byte, bool as 1 byte (bit 0),
// doubles as a mode byte plus its value (fuzz_input.hpp, take_double).
//
// Properties: encode refuses a non-valve address and every value outside the sheet's range,
// naming the message; a frame it builds has the route's identifier, the message id first, the
// padding asked for, and decodes to the same message when the message's numbers are on the
// field's resolution (otherwise to the nearest value on it, within half a step), and to a
// message that encodes to the identical frame.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <type_traits>
#include <variant>

#include "fuzz_input.hpp"
#include "teejet/codec/codec.hpp"

namespace {

using namespace teejet;
using namespace teejet::codec;

// Fills every member the typed messages have; the overloads mirror messages.hpp.
void fill(fuzz::Input& in, unsigned& v) { v = in.take<std::uint32_t>(); }
static_assert(std::is_same_v<unsigned, std::uint32_t>, "one overload serves both");
void fill(fuzz::Input& in, int& v) { v = in.take<std::int32_t>(); }
void fill(fuzz::Input& in, bool& v) { v = in.take<bool>(); }
void fill(fuzz::Input& in, char& v) { v = static_cast<char>(in.take<std::uint8_t>()); }
void fill(fuzz::Input& in, double& v) { v = in.take_double(); }
template <class E>
requires std::is_enum_v<E>
void fill(fuzz::Input& in, E& v) { v = static_cast<E>(in.take<std::uint8_t>()); }
void fill(fuzz::Input& in, SoftwareVersion& v) {
  fill(in, v.major);
  fill(in, v.minor);
  fill(in, v.test);
}

// Aggregates of up to three members, by structured binding.
template <class M>
void fill_message(fuzz::Input& in, M& m) {
  if constexpr (std::is_empty_v<M>) {
    // no members
  } else if constexpr (requires { [](M& x) { auto& [a] = x; }; }) {
    auto& [a] = m;
    fill(in, a);
  } else if constexpr (requires { [](M& x) { auto& [a, b] = x; }; }) {
    auto& [a, b] = m;
    fill(in, a);
    fill(in, b);
  } else {
    auto& [a, b, c] = m;
    fill(in, a);
    fill(in, b);
    fill(in, c);
  }
}

template <class Variant, std::size_t... I>
Variant make_message(fuzz::Input& in, std::size_t index, std::index_sequence<I...>) {
  Variant message;
  (void)((index == I ? (message.template emplace<I>(), true) : false) || ...);
  std::visit([&](auto& m) { fill_message(in, m); }, message);
  return message;
}

// How many steps a scaled field has per unit (its divisor on the wire).
double steps_per_unit(std::string_view field) {
  static const std::map<std::string_view, double> kDivisors{
      {"degrees", 10.0}, {"volts", 10.0},       {"limit_volts", 10.0},
      {"amps", 100.0},   {"limit_amps", 100.0}, {"last_running_amps", 100.0}};
  const auto it = kDivisors.find(field);
  FUZZ_CHECK(it != kDivisors.end(),
             "a double field without a known resolution: " + std::string(field));
  return it->second;
}

std::map<std::string, FieldValue> fields_of(const auto& message) {
  std::map<std::string, FieldValue> fields;
  for_each_field(message, [&](std::string_view name, const FieldValue& value) {
    fields.emplace(std::string(name), value);
  });
  return fields;
}

template <class Variant>
void check(const Variant& message, std::uint8_t valve, const EncodeOptions& options) {
  constexpr bool kToValve = std::is_same_v<Variant, ToValveMessage>;
  const auto frame = encode(valve, message, options);
  const std::string name(message_name(message));
  if (!is_valve_address(valve)) {
    FUZZ_CHECK(!frame && frame.error().code == ErrorCode::kNotValveAddress, name);
    return;
  }
  if (!frame) {
    FUZZ_CHECK(frame.error().code == ErrorCode::kOutOfRange, frame.error().reason);
    FUZZ_CHECK(frame.error().reason.starts_with(name + ": "), frame.error().reason);
    return;
  }

  FUZZ_CHECK(frame->id == (kToValve ? to_valve_id(valve) : from_valve_id(valve)), name);
  FUZZ_CHECK(frame->extended && !frame->remote, name);
  FUZZ_CHECK(frame->data[0] == message_id(message), name);
  if (options.pad_to_eight) {
    FUZZ_CHECK(frame->dlc == CanFrame::kMaxData, name);
  } else {
    FUZZ_CHECK(frame->dlc >= 1 && frame->dlc <= CanFrame::kMaxData, name);
    for (std::size_t i = frame->dlc; i < CanFrame::kMaxData; ++i) {
      FUZZ_CHECK(frame->data[i] == options.pad_byte, name + ": unused byte " + std::to_string(i));
    }
  }

  const auto decoded = decode(*frame);
  FUZZ_CHECK(decoded, name + ": encoded frame does not decode: " +
                          (decoded ? std::string() : decoded.error().reason));
  FUZZ_CHECK(decoded->route.valve_address == valve, name);
  FUZZ_CHECK(decoded->route.flow == (kToValve ? Flow::kToValve : Flow::kFromValve), name);
  const auto& back = std::get < kToValve ? 0 : 1 > (decoded->message);
  FUZZ_CHECK(back.index() == message.index(),
             name + " decoded as " + std::string(message_name(back)));

  // Field by field: whole values exactly, scaled values to the nearest step.
  const auto sent = fields_of(message);
  const auto received = fields_of(back);
  FUZZ_CHECK(sent.size() == received.size(), name);
  for (const auto& [field, value] : sent) {
    const auto& got = received.at(field);
    if (const auto* number = std::get_if<double>(&value)) {
      const double divisor = steps_per_unit(field);
      const double back_value = std::get<double>(got);
      const double delta = std::abs(back_value - *number);
      FUZZ_CHECK(delta <= 0.5 / divisor + 1e-9,
                 name + "." + field + " moved by " + std::to_string(delta));
      // A number already on the field's resolution comes back unchanged.
      const double on_grid = std::round(*number * divisor) / divisor;
      if (on_grid == *number) FUZZ_CHECK(back_value == *number, name + "." + field);
    } else {
      FUZZ_CHECK(got == value, name + "." + field);
    }
  }

  // What was decoded encodes to the identical frame.
  const auto again = encode(valve, back, options);
  FUZZ_CHECK(again && *again == *frame, name + ": decode then encode changed the frame");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fuzz::Input input(data, size);
  const bool from_valve = input.take<bool>();
  const auto index = input.take<std::uint8_t>();
  const auto valve = input.take<std::uint8_t>();
  EncodeOptions options;
  options.pad_to_eight = !input.take<bool>();
  options.pad_byte = input.take<std::uint8_t>();
  if (from_valve) {
    constexpr auto n = std::variant_size_v<FromValveMessage>;
    check(make_message<FromValveMessage>(input, index % n, std::make_index_sequence<n>{}), valve,
          options);
  } else {
    constexpr auto n = std::variant_size_v<ToValveMessage>;
    check(make_message<ToValveMessage>(input, index % n, std::make_index_sequence<n>{}), valve,
          options);
  }
  return 0;
}
