#pragma once

// ISO 11783-5 / SAE J1939-81 network management, as far as a controller at a fixed address
// needs it: the 64-bit NAME that identifies an ECU and ranks it when two claim one address, and
// the frames of address claiming (Address Claimed, Cannot Claim Address, Request for Address
// Claimed). Pure: bytes and values, no I/O. docs/isobus.md.

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <variant>

#include "teejet/codec/frame.hpp"
#include "teejet/core/result.hpp"

namespace teejet::isobus {

// A NAME's fields by ISO 11783-5's names (J1939-81 calls the device class "vehicle system").
struct Name {
  std::uint32_t identity_number = 0;       // 21 bits
  std::uint16_t manufacturer_code = 0;     // 11 bits
  std::uint8_t ecu_instance = 0;           // 3 bits
  std::uint8_t function_instance = 0;      // 5 bits
  std::uint8_t function = 0;               // 8 bits
  std::uint8_t device_class = 0;           // 7 bits
  std::uint8_t device_class_instance = 0;  // 4 bits
  std::uint8_t industry_group = 0;         // 3 bits; 2 = agricultural and forestry equipment
  bool arbitrary_address_capable = false;  // 1 bit

  friend bool operator==(const Name&, const Name&) = default;
};

// One field of the NAME: where it sits in the 64-bit value and its largest value. The one table
// the encoding, the decoding, the configuration's ranges and the docs derive from.
struct NameField {
  std::string_view name;  // the configuration's key
  int first_bit;
  int bits;
  std::uint32_t max() const { return (1U << bits) - 1U; }
};
std::span<const NameField> name_fields();

// The value of `field` in `name`, and `name` with it set (`value` must be within max()).
std::uint32_t field_value(const Name& name, const NameField& field);
void set_field(Name& name, const NameField& field, std::uint32_t value);

// The NAME as its 64-bit value (bit 0 the identity number's lowest, bit 63 arbitrary address
// capable) and back. A lower value has the higher priority.
std::uint64_t to_value(const Name& name);
Name from_value(std::uint64_t value);
// Whether `a` keeps an address that `b` claims too: a lower NAME wins.
inline bool wins_over(const Name& a, const Name& b) { return to_value(a) < to_value(b); }

// "0xA00C81045A20021B" and back (16 hex digits; 0x optional); an Error says what is wrong.
std::string to_text(const Name& name);
Result<Name> parse_name(std::string_view text);

// PGNs of network management.
inline constexpr std::uint32_t kAddressClaimedPgn = 0xEE00;  // 60928
inline constexpr std::uint32_t kRequestPgn = 0xEA00;         // 59904
inline constexpr std::uint8_t kGlobalAddress = 0xFF;
inline constexpr std::uint8_t kNullAddress = 0xFE;  // the source of Cannot Claim Address
inline constexpr std::uint8_t kPriority = 6;

// Address Claimed from `source` (0x18EEFF<source>), the NAME in 8 bytes, least significant
// first; Cannot Claim Address is the same from kNullAddress.
codec::CanFrame address_claimed(const Name& name, std::uint8_t source);
codec::CanFrame cannot_claim_address(const Name& name);
// Request for Address Claimed to `destination` (kGlobalAddress: every ECU) from `source`:
// 0x18EA<destination><source>, data 00 EE 00.
codec::CanFrame request_for_address_claimed(std::uint8_t destination, std::uint8_t source);

// The frames a controller at `address` must hear for address claiming, as extended-id filters
// (accepted when (id & mask) == (filter id & mask)): claims from anyone to anyone, requests to
// everyone and to it, and any frame from its own address (a second ECU there).
struct IdFilter {
  std::uint32_t id;
  std::uint32_t mask;
};
std::array<IdFilter, 4> claiming_filters(std::uint8_t address);

// What a frame of another ECU means to address claiming.
struct AddressClaim {
  std::uint8_t source;  // kNullAddress: Cannot Claim Address
  Name name;
  friend bool operator==(const AddressClaim&, const AddressClaim&) = default;
};
struct ClaimRequest {
  std::uint8_t destination;
  std::uint8_t source;
  friend bool operator==(const ClaimRequest&, const ClaimRequest&) = default;
};
struct OtherFrame {
  std::optional<std::uint8_t> source;  // a 29-bit frame's source address; none for 11-bit
  friend bool operator==(const OtherFrame&, const OtherFrame&) = default;
};
using NetworkFrame = std::variant<AddressClaim, ClaimRequest, OtherFrame>;
NetworkFrame classify(const codec::CanFrame& frame);

}  // namespace teejet::isobus
