#pragma once

// Field codecs: how one field of a message sits on the wire. Each kind knows its width, how to
// encode a typed member (refusing values outside the sheet's range), how to decode it (accepting
// whatever the wire says, unless the byte is not a defined value of an enumeration) and how to
// present it to people. Messages are assembled from these in message_table.hpp.

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

#include "teejet/codec/codec.hpp"

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
  return Error{ErrorCode::kOutOfRange, std::string(field) + " " + format_number(value) +
                                           " is outside " + format_number(min) + " to " +
                                           format_number(max)};
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

  FieldError encode(std::string_view, bool value, MutableBytes out, std::size_t offset) const {
    out[offset] = value ? 1 : 0;
    return std::nullopt;
  }
  FieldError decode(std::string_view name, Bytes in, std::size_t offset, bool& value) const {
    if (in[offset] > 1) {
      return Error{ErrorCode::kInvalidValue,
                   std::string(name) + " byte " + hex_byte(in[offset]) + " is neither 0 nor 1"};
    }
    value = in[offset] == 1;
    return std::nullopt;
  }
  FieldValue present(bool value) const { return value; }
};

// Bit-rate code byte: 0 = 250 kbit/s, 1 = 500 kbit/s; the member is the rate in bit/s.
struct BitRateField {
  static constexpr std::size_t width = 1;

  FieldError encode(std::string_view name, std::uint32_t value, MutableBytes out,
                    std::size_t offset) const {
    if (value != kBitRate250k && value != kBitRate500k) {
      return Error{ErrorCode::kOutOfRange, std::string(name) + " " + std::to_string(value) +
                                               " is neither 250000 nor 500000"};
    }
    out[offset] = value == kBitRate500k ? 1 : 0;
    return std::nullopt;
  }
  FieldError decode(std::string_view name, Bytes in, std::size_t offset,
                    std::uint32_t& value) const {
    if (in[offset] > 1) {
      return Error{ErrorCode::kInvalidValue, std::string(name) + " code " + hex_byte(in[offset]) +
                                                 " is neither 0 (250k) nor 1 (500k)"};
    }
    value = in[offset] == 1 ? kBitRate500k : kBitRate250k;
    return std::nullopt;
  }
  FieldValue present(std::uint32_t value) const { return std::int64_t{value}; }
};

// Major, minor, test character; presented as "1.02e".
struct VersionField {
  static constexpr std::size_t width = 3;

  FieldError encode(std::string_view name, const SoftwareVersion& value, MutableBytes out,
                    std::size_t offset) const {
    if (value.major > 0xFF || value.minor > 0xFF) {
      return Error{ErrorCode::kOutOfRange,
                   std::string(name) + " " + format_version(value) + " has a part above 255"};
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

  FieldError encode(std::string_view name, E value, MutableBytes out, std::size_t offset) const {
    const auto wire = static_cast<std::uint8_t>(value);
    if (find_enum<E>(wire) == nullptr) {
      return Error{ErrorCode::kOutOfRange,
                   std::string(name) + " " + hex_byte(wire) + " is not a defined value"};
    }
    out[offset] = wire;
    return std::nullopt;
  }
  FieldError decode(std::string_view name, Bytes in, std::size_t offset, E& value) const {
    const auto* entry = find_enum<E>(in[offset]);
    if (entry == nullptr) {
      return Error{invalid,
                   std::string(name) + " byte " + hex_byte(in[offset]) + " is not a defined value"};
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
    return Error{ErrorCode::kInvalidMarker, std::string(name) + " byte " + hex_byte(in[offset]) +
                                                " is not " + hex_byte(value)};
  }
  void visit(const Msg&, const FieldVisitor&) const {}
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
