#pragma once

// Field codecs: how one field of a message sits on the wire. Each kind knows its width, its unit,
// range and resolution (info()), how to encode a typed member (refusing values outside the
// sheet's range), how to decode it (accepting whatever the wire says, unless the byte is not a
// defined value of an enumeration), how to present it to people and how to set it from what
// people give (assign()). Messages are assembled from these in message_table.hpp.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <tuple>
#include <type_traits>
#include <utility>
#include <variant>

#include "teejet/codec/codec.hpp"
#include "teejet/codec/table.hpp"

namespace teejet::codec::detail {

using Bytes = std::span<const std::uint8_t>;
using MutableBytes = std::span<std::uint8_t>;
using FieldError = std::optional<Error>;  // nullopt: the field is fine

std::string format_number(double value);
std::string hex_byte(std::uint8_t value);
std::string hex_id(std::uint32_t value, int digits);

inline std::uint32_t read_be(Bytes in, std::size_t offset, std::size_t width) {
  std::uint32_t value = 0;
  for (std::size_t i = 0; i < width; ++i) value = value << 8 | in[offset + i];
  return value;
}

inline void write_be(MutableBytes out, std::size_t offset, std::size_t width, std::uint32_t value) {
  for (std::size_t i = width; i-- > 0;) {
    out[offset + i] = static_cast<std::uint8_t>(value & 0xFF);
    value >>= 8;
  }
}

inline Error out_of_range(std::string_view field, double value, double min, double max) {
  return field_error(
      ErrorCode::kOutOfRange, std::string(field),
      format_number(value) + " is outside " + format_number(min) + " to " + format_number(max));
}

inline Error invalid_field(std::string_view field, std::string complaint) {
  return field_error(ErrorCode::kInvalidValue, std::string(field), std::move(complaint));
}

// What people give for a field, as a number: an integer or a double; nullopt otherwise.
inline std::optional<double> number_of(const FieldValue& value) {
  if (const auto* integer = std::get_if<std::int64_t>(&value)) return static_cast<double>(*integer);
  if (const auto* real = std::get_if<double>(&value)) return *real;
  return std::nullopt;
}

inline std::string describe_value(const FieldValue& value) {
  return std::visit(
      [](const auto& v) -> std::string {
        using V = std::decay_t<decltype(v)>;
        if constexpr (std::is_same_v<V, std::string>) return "\"" + v + "\"";
        if constexpr (std::is_same_v<V, bool>) return v ? "true" : "false";
        if constexpr (std::is_same_v<V, double>) return format_number(v);
        if constexpr (std::is_same_v<V, std::int64_t>) return std::to_string(v);
      },
      value);
}

// A whole number from `min` to `max`, as an integer field takes it.
inline Result<double> whole_number(std::string_view field, const FieldValue& value, double min,
                                   double max) {
  const auto number = number_of(value);
  if (!number) return invalid_field(field, describe_value(value) + " is not a number");
  if (!std::isfinite(*number) || *number != std::floor(*number)) {
    return invalid_field(field, format_number(*number) + " is not a whole number");
  }
  if (*number < min || *number > max) return out_of_range(field, *number, min, max);
  return *number;
}

// ---- Enumerations: the wire value is the enumerator's underlying value ----------------------

template <class E>
struct EnumEntry {
  E value;
  std::string_view name;
};

constexpr auto enum_entries(std::type_identity<Direction>) {
  return std::array{EnumEntry<Direction>{Direction::kClose, "close"},
                    EnumEntry<Direction>{Direction::kOpen, "open"}};
}
constexpr auto enum_entries(std::type_identity<TargetDirection>) {
  return std::array{EnumEntry<TargetDirection>{TargetDirection::kClose, "close"},
                    EnumEntry<TargetDirection>{TargetDirection::kOpen, "open"},
                    EnumEntry<TargetDirection>{TargetDirection::kShortest, "shortest"}};
}
constexpr auto enum_entries(std::type_identity<Rotation>) {
  return std::array{EnumEntry<Rotation>{Rotation::kCounterclockwise, "counterclockwise"},
                    EnumEntry<Rotation>{Rotation::kClockwise, "clockwise"}};
}
constexpr auto enum_entries(std::type_identity<BaudAction>) {
  return std::array{EnumEntry<BaudAction>{BaudAction::kSet, "set"},
                    EnumEntry<BaudAction>{BaudAction::kRequest, "request"}};
}

template <class E>
inline constexpr auto kEntries = enum_entries(std::type_identity<E>{});

template <class E>
constexpr const EnumEntry<E>* find_enum(std::uint8_t wire) {
  for (const auto& entry : kEntries<E>) {
    if (static_cast<std::uint8_t>(entry.value) == wire) return &entry;
  }
  return nullptr;
}

// ---- Field kinds ----------------------------------------------------------------------------

// Unsigned big-endian integer; the member is any unsigned integer type.
struct UnsignedField {
  std::size_t width;
  std::uint32_t max;
  std::string_view unit = {};

  FieldInfo info() const {
    return {.width = width, .unit = unit, .min = 0, .max = static_cast<double>(max)};
  }
  template <class M>
  FieldError assign(std::string_view name, const FieldValue& value, M& member) const {
    const auto number = whole_number(name, value, 0, max);
    if (!number) return number.error();
    member = static_cast<M>(*number);
    return std::nullopt;
  }
  template <class M>
  FieldError encode(std::string_view name, const M& value, MutableBytes out,
                    std::size_t offset) const {
    if (value > max) return out_of_range(name, static_cast<double>(value), 0, max);
    write_be(out, offset, width, static_cast<std::uint32_t>(value));
    return std::nullopt;
  }
  template <class M>
  FieldError decode(std::string_view, Bytes in, std::size_t offset, M& value) const {
    value = static_cast<M>(read_be(in, offset, width));
    return std::nullopt;
  }
  template <class M>
  FieldValue present(const M& value) const {
    return static_cast<std::int64_t>(value);
  }
};

// Unsigned big-endian integer carrying value * divisor; the member is a double in engineering
// units. Encoding rounds to the field's resolution first, then checks the range.
struct ScaledField {
  std::size_t width;
  double divisor;
  std::uint32_t max_raw;
  std::string_view unit = {};

  FieldInfo info() const {
    return {.width = width,
            .unit = unit,
            .min = 0,
            .max = max_raw / divisor,
            .resolution = 1.0 / divisor};
  }
  FieldError assign(std::string_view name, const FieldValue& value, double& member) const {
    const auto number = number_of(value);
    if (!number) return invalid_field(name, describe_value(value) + " is not a number");
    std::array<std::uint8_t, 8> scratch{};
    if (auto failure = encode(name, *number, scratch, 0)) return failure;
    member = *number;
    return std::nullopt;
  }

  FieldError encode(std::string_view name, double value, MutableBytes out,
                    std::size_t offset) const {
    const double scaled = std::round(value * divisor);
    if (!std::isfinite(value) || scaled < 0 || scaled > max_raw) {
      return out_of_range(name, value, 0, max_raw / divisor);
    }
    write_be(out, offset, width, static_cast<std::uint32_t>(scaled));
    return std::nullopt;
  }
  FieldError decode(std::string_view, Bytes in, std::size_t offset, double& value) const {
    value = read_be(in, offset, width) / divisor;
    return std::nullopt;
  }
  FieldValue present(double value) const { return value; }
};

// One two's-complement byte of whole degrees Celsius; the member is an int.
struct SignedByteField {
  static constexpr std::size_t width = 1;
  int min;
  int max;
  std::string_view unit = {};

  FieldInfo info() const {
    return {.width = width, .unit = unit, .min = double(min), .max = double(max)};
  }
  FieldError assign(std::string_view name, const FieldValue& value, int& member) const {
    const auto number = whole_number(name, value, min, max);
    if (!number) return number.error();
    member = static_cast<int>(*number);
    return std::nullopt;
  }

  FieldError encode(std::string_view name, int value, MutableBytes out, std::size_t offset) const {
    if (value < min || value > max) return out_of_range(name, value, min, max);
    out[offset] = static_cast<std::uint8_t>(static_cast<std::int8_t>(value));
    return std::nullopt;
  }
  FieldError decode(std::string_view, Bytes in, std::size_t offset, int& value) const {
    value = static_cast<std::int8_t>(in[offset]);
    return std::nullopt;
  }
  FieldValue present(int value) const { return std::int64_t{value}; }
};

// 24-bit serial number, presented as "TJV123456".
struct SerialField {
  static constexpr std::size_t width = 3;
  UnsignedField bits{width, 0xFFFFFF};

  FieldInfo info() const {
    return {.width = width, .type = FieldType::kSerial, .min = 0, .max = 0xFFFFFF};
  }
  FieldError assign(std::string_view name, const FieldValue& value, std::uint32_t& member) const {
    if (const auto* text = std::get_if<std::string>(&value)) {
      const auto serial = parse_serial(*text);
      if (!serial)
        return field_error(serial.error().code, std::string(name), serial.error().reason);
      member = *serial;
      return std::nullopt;
    }
    return bits.assign(name, value, member);
  }

  FieldError encode(std::string_view name, std::uint32_t value, MutableBytes out,
                    std::size_t offset) const {
    return bits.encode(name, value, out, offset);
  }
  FieldError decode(std::string_view name, Bytes in, std::size_t offset,
                    std::uint32_t& value) const {
    return bits.decode(name, in, offset, value);
  }
  FieldValue present(std::uint32_t value) const { return format_serial(value); }
};

// A byte that must be 0 or 1.
struct FlagField {
  static constexpr std::size_t width = 1;

  FieldInfo info() const { return {.width = width, .type = FieldType::kFlag, .max = 1}; }
  FieldError assign(std::string_view name, const FieldValue& value, bool& member) const {
    const auto* flag = std::get_if<bool>(&value);
    if (flag == nullptr)
      return invalid_field(name, describe_value(value) + " is neither true nor false");
    member = *flag;
    return std::nullopt;
  }

  FieldError encode(std::string_view, bool value, MutableBytes out, std::size_t offset) const {
    out[offset] = value ? 1 : 0;
    return std::nullopt;
  }
  FieldError decode(std::string_view name, Bytes in, std::size_t offset, bool& value) const {
    if (in[offset] > 1) {
      return invalid_field(name, "byte " + hex_byte(in[offset]) + " is neither 0 nor 1");
    }
    value = in[offset] == 1;
    return std::nullopt;
  }
  FieldValue present(bool value) const { return value; }
};

// Bit-rate code byte: 0 = 250 kbit/s, 1 = 500 kbit/s; the member is the rate in bit/s.
struct BitRateField {
  static constexpr std::size_t width = 1;

  FieldInfo info() const {
    return {.width = width,
            .unit = "bit/s",
            .min = kBitRate250k,
            .max = kBitRate500k,
            .values = {kBitRate250k, kBitRate500k}};
  }
  FieldError assign(std::string_view name, const FieldValue& value, std::uint32_t& member) const {
    const auto number = whole_number(name, value, 0, 0xFFFFFFFF);
    if (!number) return number.error();
    std::array<std::uint8_t, 8> scratch{};
    if (auto failure = encode(name, static_cast<std::uint32_t>(*number), scratch, 0))
      return failure;
    member = static_cast<std::uint32_t>(*number);
    return std::nullopt;
  }

  FieldError encode(std::string_view name, std::uint32_t value, MutableBytes out,
                    std::size_t offset) const {
    if (value != kBitRate250k && value != kBitRate500k) {
      return field_error(ErrorCode::kOutOfRange, std::string(name),
                         std::to_string(value) + " is neither 250000 nor 500000");
    }
    out[offset] = value == kBitRate500k ? 1 : 0;
    return std::nullopt;
  }
  FieldError decode(std::string_view name, Bytes in, std::size_t offset,
                    std::uint32_t& value) const {
    if (in[offset] > 1) {
      return invalid_field(name,
                           "code " + hex_byte(in[offset]) + " is neither 0 (250k) nor 1 (500k)");
    }
    value = in[offset] == 1 ? kBitRate500k : kBitRate250k;
    return std::nullopt;
  }
  FieldValue present(std::uint32_t value) const { return std::int64_t{value}; }
};

// Major, minor, test character; presented as "1.02e".
struct VersionField {
  static constexpr std::size_t width = 3;

  FieldInfo info() const { return {.width = width, .type = FieldType::kVersion}; }
  FieldError assign(std::string_view name, const FieldValue& value, SoftwareVersion& member) const {
    const auto* text = std::get_if<std::string>(&value);
    if (text == nullptr)
      return invalid_field(name, describe_value(value) + " is not a version like 1.02e");
    const auto version = parse_version(*text);
    if (!version)
      return field_error(version.error().code, std::string(name), version.error().reason);
    member = *version;
    return std::nullopt;
  }

  FieldError encode(std::string_view name, const SoftwareVersion& value, MutableBytes out,
                    std::size_t offset) const {
    if (value.major > 0xFF || value.minor > 0xFF) {
      return field_error(ErrorCode::kOutOfRange, std::string(name),
                         format_version(value) + " has a part above 255");
    }
    out[offset] = static_cast<std::uint8_t>(value.major);
    out[offset + 1] = static_cast<std::uint8_t>(value.minor);
    out[offset + 2] = static_cast<std::uint8_t>(value.test);
    return std::nullopt;
  }
  FieldError decode(std::string_view, Bytes in, std::size_t offset, SoftwareVersion& value) const {
    value = {in[offset], in[offset + 1], static_cast<char>(in[offset + 2])};
    return std::nullopt;
  }
  FieldValue present(const SoftwareVersion& value) const { return format_version(value); }
};

// An enumeration byte; a value the sheet does not define is reported with `invalid`.
template <class E>
struct EnumField {
  static constexpr std::size_t width = 1;
  ErrorCode invalid = ErrorCode::kInvalidValue;

  FieldInfo info() const {
    FieldInfo field{.width = width, .type = FieldType::kWord};
    for (const auto& entry : kEntries<E>) field.words.push_back(entry.name);
    return field;
  }
  FieldError assign(std::string_view name, const FieldValue& value, E& member) const {
    if (const auto* word = std::get_if<std::string>(&value)) {
      for (const auto& entry : kEntries<E>) {
        if (entry.name == *word) {
          member = entry.value;
          return std::nullopt;
        }
      }
    }
    std::string words;
    for (const auto& entry : kEntries<E>) {
      if (!words.empty()) words += ", ";
      words += entry.name;
    }
    return invalid_field(name, describe_value(value) + " is not one of " + words);
  }

  FieldError encode(std::string_view name, E value, MutableBytes out, std::size_t offset) const {
    const auto wire = static_cast<std::uint8_t>(value);
    if (find_enum<E>(wire) == nullptr) {
      return field_error(ErrorCode::kOutOfRange, std::string(name),
                         hex_byte(wire) + " is not a defined value");
    }
    out[offset] = wire;
    return std::nullopt;
  }
  FieldError decode(std::string_view name, Bytes in, std::size_t offset, E& value) const {
    const auto* entry = find_enum<E>(in[offset]);
    if (entry == nullptr) {
      return field_error(invalid, std::string(name),
                         "byte " + hex_byte(in[offset]) + " is not a defined value");
    }
    value = entry->value;
    return std::nullopt;
  }
  FieldValue present(E value) const {
    return std::string(find_enum<E>(static_cast<std::uint8_t>(value))->name);
  }
};

// ---- Fields bound to message members --------------------------------------------------------

template <class Msg, class Member, class Kind>
struct Field {
  std::string_view name;
  std::size_t offset;
  Member Msg::*member;
  Kind kind;

  constexpr std::size_t end() const { return offset + kind.width; }
  FieldError encode(const Msg& msg, MutableBytes out) const {
    return kind.encode(name, msg.*member, out, offset);
  }
  FieldError decode(Bytes in, Msg& msg) const { return kind.decode(name, in, offset, msg.*member); }
  void visit(const Msg& msg, const FieldVisitor& visitor) const {
    visitor(name, kind.present(msg.*member));
  }
  FieldInfo info() const {
    FieldInfo field = kind.info();
    field.name = name;
    field.offset = offset;
    return field;
  }
  FieldError assign(Msg& msg, const FieldValue& value) const {
    return kind.assign(name, value, msg.*member);
  }
};

// A byte with one valid value and no member (the 0xA5 of CAN Baud Rate Reply).
template <class Msg>
struct MarkerByte {
  std::string_view name;
  std::size_t offset;
  std::uint8_t value;

  constexpr std::size_t end() const { return offset + 1; }
  FieldError encode(const Msg&, MutableBytes out) const {
    out[offset] = value;
    return std::nullopt;
  }
  FieldError decode(Bytes in, Msg&) const {
    if (in[offset] == value) return std::nullopt;
    return field_error(ErrorCode::kInvalidMarker, std::string(name),
                       "byte " + hex_byte(in[offset]) + " is not " + hex_byte(value));
  }
  void visit(const Msg&, const FieldVisitor&) const {}
  FieldInfo info() const {
    return {.name = name,
            .offset = offset,
            .width = 1,
            .type = FieldType::kMarker,
            .min = double(value),
            .max = double(value)};
  }
  FieldError assign(Msg&, const FieldValue&) const {
    return invalid_field(name, "is fixed to " + hex_byte(value));
  }
};

// One message: its id, its name and its fields at their offsets.
template <class Msg, class... Fields>
struct MessageSpec {
  std::uint8_t id;
  std::string_view name;
  std::tuple<Fields...> fields;
  // Controller to valve only: what the message makes the valve do.
  bool run_command = false;             // replaces what the valve was doing (sheet, note 5)
  std::optional<std::uint8_t> reply{};  // the valve-to-controller message that answers it
  bool telemetry_request = false;       // asks for a value the valve measures or counts
  // Valve to controller only.
  bool error = false;  // one of the error messages

  constexpr MessageSpec runs() const {
    MessageSpec spec = *this;
    spec.run_command = true;
    return spec;
  }
  constexpr MessageSpec answered_by(std::uint8_t reply_id) const {
    MessageSpec spec = *this;
    spec.reply = reply_id;
    return spec;
  }
  constexpr MessageSpec asks_for_telemetry() const {
    MessageSpec spec = *this;
    spec.telemetry_request = true;
    return spec;
  }
  constexpr MessageSpec reports_error() const {
    MessageSpec spec = *this;
    spec.error = true;
    return spec;
  }

  // Bytes the message occupies, id byte included.
  constexpr std::size_t length() const {
    return std::apply(
        [](const auto&... f) {
          return std::max({std::size_t{1}, f.end()...});
        },
        fields);
  }
};

template <class Msg, class... Fields>
constexpr MessageSpec<Msg, Fields...> message(std::uint8_t id, std::string_view name,
                                              Fields... fields) {
  return {id, name, {fields...}};
}

template <class Msg, class Member, class Kind>
constexpr Field<Msg, Member, Kind> field(std::string_view name, std::size_t offset,
                                         Member Msg::*member, Kind kind) {
  return {name, offset, member, kind};
}

}  // namespace teejet::codec::detail
