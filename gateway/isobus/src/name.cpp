#include "teejet/isobus/name.hpp"

#include <cctype>
#include <cstdio>

namespace teejet::isobus {
namespace {

// ISO 11783-5 / J1939-81: the NAME from its least significant bit up (bit 48 is reserved, 0).
constexpr std::array<NameField, 9> kNameFields{{
    {"identity_number", 0, 21},
    {"manufacturer_code", 21, 11},
    {"ecu_instance", 32, 3},
    {"function_instance", 35, 5},
    {"function", 40, 8},
    {"device_class", 49, 7},
    {"device_class_instance", 56, 4},
    {"industry_group", 60, 3},
    {"arbitrary_address_capable", 63, 1},
}};

// The member of Name that field `index` of kNameFields is.
template <class NameRef, class Visit>
void with_member(NameRef& name, std::size_t index, Visit&& visit) {
  switch (index) {
    case 0:
      visit(name.identity_number);
      break;
    case 1:
      visit(name.manufacturer_code);
      break;
    case 2:
      visit(name.ecu_instance);
      break;
    case 3:
      visit(name.function_instance);
      break;
    case 4:
      visit(name.function);
      break;
    case 5:
      visit(name.device_class);
      break;
    case 6:
      visit(name.device_class_instance);
      break;
    case 7:
      visit(name.industry_group);
      break;
    default:
      visit(name.arbitrary_address_capable);
      break;
  }
}

std::size_t index_of(const NameField& field) {
  return static_cast<std::size_t>(&field - kNameFields.data());
}

constexpr std::uint32_t id_of(std::uint32_t pgn, std::uint8_t destination, std::uint8_t source) {
  return static_cast<std::uint32_t>(kPriority) << 26 | pgn << 8 |
         static_cast<std::uint32_t>(destination) << 8 | source;
}

codec::CanFrame claim_frame(const Name& name, std::uint8_t source) {
  codec::CanFrame frame;
  frame.id = id_of(kAddressClaimedPgn, kGlobalAddress, source);
  frame.dlc = 8;
  const std::uint64_t value = to_value(name);
  for (std::size_t i = 0; i < 8; ++i) frame.data[i] = static_cast<std::uint8_t>(value >> (8 * i));
  return frame;
}

}  // namespace

std::span<const NameField> name_fields() { return kNameFields; }

std::uint32_t field_value(const Name& name, const NameField& field) {
  std::uint32_t value = 0;
  with_member(name, index_of(field),
              [&](const auto& member) { value = static_cast<std::uint32_t>(member); });
  return value;
}

void set_field(Name& name, const NameField& field, std::uint32_t value) {
  with_member(name, index_of(field), [&](auto& member) {
    member = static_cast<std::remove_reference_t<decltype(member)>>(value & field.max());
  });
}

std::uint64_t to_value(const Name& name) {
  std::uint64_t value = 0;
  for (const NameField& field : kNameFields) {
    value |= static_cast<std::uint64_t>(field_value(name, field) & field.max()) << field.first_bit;
  }
  return value;
}

Name from_value(std::uint64_t value) {
  Name name;
  for (const NameField& field : kNameFields) {
    set_field(name, field, static_cast<std::uint32_t>(value >> field.first_bit) & field.max());
  }
  return name;
}

std::string to_text(const Name& name) {
  char text[19];
  std::snprintf(text, sizeof text, "0x%016llX", static_cast<unsigned long long>(to_value(name)));
  return text;
}

Result<Name> parse_name(std::string_view text) {
  const std::string_view digits =
      text.starts_with("0x") || text.starts_with("0X") ? text.substr(2) : text;
  if (digits.size() != 16) {
    return Error{
        ErrorCode::kInvalidValue,
        "a NAME is 16 hexadecimal digits (0xA00C81045A20021B), not \"" + std::string(text) + "\""};
  }
  std::uint64_t value = 0;
  for (const char c : digits) {
    if (!std::isxdigit(static_cast<unsigned char>(c))) {
      return Error{ErrorCode::kInvalidValue,
                   "a NAME is 16 hexadecimal digits, \"" + std::string(text) + "\" is not"};
    }
    value = value << 4 | static_cast<std::uint64_t>(
                             std::isdigit(static_cast<unsigned char>(c))
                                 ? c - '0'
                                 : std::tolower(static_cast<unsigned char>(c)) - 'a' + 10);
  }
  return from_value(value);
}

codec::CanFrame address_claimed(const Name& name, std::uint8_t source) {
  return claim_frame(name, source);
}

codec::CanFrame cannot_claim_address(const Name& name) { return claim_frame(name, kNullAddress); }

codec::CanFrame request_for_address_claimed(std::uint8_t destination, std::uint8_t source) {
  codec::CanFrame frame;
  frame.id = id_of(kRequestPgn, destination, source);
  frame.dlc = 3;
  frame.data[0] = static_cast<std::uint8_t>(kAddressClaimedPgn);
  frame.data[1] = static_cast<std::uint8_t>(kAddressClaimedPgn >> 8);
  frame.data[2] = static_cast<std::uint8_t>(kAddressClaimedPgn >> 16);
  return frame;
}

std::array<IdFilter, 4> claiming_filters(std::uint8_t address) {
  // The PGN's data page and PDU format (bits 16-25); for PDU1 the destination (bits 8-15).
  constexpr std::uint32_t kPgnMask = 0x03FF0000;
  constexpr std::uint32_t kDestinationMask = 0x0000FF00;
  return {{
      {kAddressClaimedPgn << 8, kPgnMask},
      {kRequestPgn << 8 | std::uint32_t{kGlobalAddress} << 8, kPgnMask | kDestinationMask},
      {kRequestPgn << 8 | std::uint32_t{address} << 8, kPgnMask | kDestinationMask},
      {address, 0xFF},
  }};
}

NetworkFrame classify(const codec::CanFrame& frame) {
  if (!frame.extended) return OtherFrame{};
  const auto source = static_cast<std::uint8_t>(frame.id);
  // PDU1 (PF below 0xF0): the PS byte is the destination, not part of the PGN.
  const std::uint32_t pdu_format = (frame.id >> 16) & 0xFF;
  const auto destination = static_cast<std::uint8_t>(frame.id >> 8);
  if (frame.remote || pdu_format >= 0xF0 || ((frame.id >> 24) & 0x03) != 0) {
    return OtherFrame{source};
  }
  if (pdu_format << 8 == kAddressClaimedPgn && frame.dlc == 8) {
    std::uint64_t value = 0;
    for (std::size_t i = 0; i < 8; ++i)
      value |= static_cast<std::uint64_t>(frame.data[i]) << (8 * i);
    return AddressClaim{source, from_value(value)};
  }
  if (pdu_format << 8 == kRequestPgn && frame.dlc == 3) {
    const std::uint32_t pgn = std::uint32_t{frame.data[0]} | std::uint32_t{frame.data[1]} << 8 |
                              std::uint32_t{frame.data[2]} << 16;
    if (pgn == kAddressClaimedPgn) return ClaimRequest{destination, source};
  }
  return OtherFrame{source};
}

}  // namespace teejet::isobus
