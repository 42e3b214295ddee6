// codec::decode of an arbitrary frame, the gateway's first contact with the bus.
//
// Input: identifier (4 bytes, little-endian), flags (bit 0: 11-bit identifier, bit 1: remote),
// DLC (low four bits: 0..15, as a controller may report it), then up to eight data bytes.
//
// Properties: an error always has a reason; a decoded frame has the route route_of gives, its
// message id is data[0], every field presents as the codec documents, and the message encodes
// back to the same bytes unless it is telemetry outside the sheet's range (the decoder takes
// what the valve says; the encoder refuses what the sheet does not allow). DLC 9..15 reads as
// eight bytes.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string>
#include <variant>

#include "fuzz_input.hpp"
#include "teejet/codec/codec.hpp"

namespace {

using namespace teejet;
using namespace teejet::codec;

bool printable_ascii(const std::string& text) {
  return std::all_of(text.begin(), text.end(), [](char c) { return c >= 0x20 && c <= 0x7E; });
}

void check_fields(const auto& message) {
  for_each_field(message, [](std::string_view name, const FieldValue& value) {
    FUZZ_CHECK(!name.empty(), "a field without a name");
    if (const auto* text = std::get_if<std::string>(&value)) {
      // Versions and serials end up in JSON and DDS strings.
      FUZZ_CHECK(printable_ascii(*text), std::string(name) + " = '" + *text + "'");
      FUZZ_CHECK(*text != "invalid", std::string(name) + " presents an undefined enumerator");
    }
    if (const auto* number = std::get_if<double>(&value)) {
      FUZZ_CHECK(std::isfinite(*number) && *number >= 0, std::string(name));
    }
  });
}

template <class Message>
void check_reencodes(const Message& message, const CanFrame& frame, const Route& route) {
  const auto again = encode(route.valve_address, message, EncodeOptions{.pad_to_eight = false});
  if (!again) {
    FUZZ_CHECK(again.error().code == ErrorCode::kOutOfRange, again.error().reason);
    FUZZ_CHECK(again.error().reason.starts_with(std::string(message_name(message)) + ": "),
               again.error().reason);
    return;
  }
  FUZZ_CHECK(again->id == frame.id, "re-encoded to another identifier");
  FUZZ_CHECK(again->dlc <= std::min<std::uint8_t>(frame.dlc, CanFrame::kMaxData),
             "re-encoded longer than the frame it came from");
  FUZZ_CHECK(std::equal(again->data.begin(), again->data.begin() + again->dlc, frame.data.begin()),
             "re-encoded to other bytes");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fuzz::Input input(data, size);
  CanFrame frame;
  frame.id = input.take<std::uint32_t>();
  const auto flags = input.take<std::uint8_t>();
  frame.extended = (flags & 1) == 0;
  frame.remote = (flags & 2) != 0;
  const auto dlc = static_cast<std::uint8_t>(input.take<std::uint8_t>() & 0x0F);
  for (auto& byte : frame.data) byte = input.take<std::uint8_t>();

  if (dlc > CanFrame::kMaxData) {
    // What a classic CAN controller means by DLC 9..15: eight bytes.
    CanFrame eight = frame;
    eight.dlc = CanFrame::kMaxData;
    frame.dlc = dlc;
    const auto as_reported = decode(frame);
    const auto as_eight = decode(eight);
    FUZZ_CHECK(as_reported.ok() == as_eight.ok(), "DLC " + std::to_string(dlc));
    if (as_reported) FUZZ_CHECK(as_reported->message == as_eight->message, "DLC above 8");
    return 0;
  }
  frame.dlc = dlc;

  const auto route = route_of(frame);
  const auto decoded = decode(frame);
  if (!decoded) {
    FUZZ_CHECK(!decoded.error().reason.empty(), "an error without a reason");
    if (!route) FUZZ_CHECK(decoded.error().code == route.error().code, decoded.error().reason);
    return 0;
  }
  FUZZ_CHECK(route && *route == decoded->route, "decode and route_of disagree");
  FUZZ_CHECK(is_valve_address(route->valve_address), "route outside the valve range");
  FUZZ_CHECK(frame.extended && !frame.remote && frame.dlc >= 1, "decoded a frame that is not ours");
  const auto expected_id = route->flow == Flow::kToValve ? to_valve_id(route->valve_address)
                                                         : from_valve_id(route->valve_address);
  FUZZ_CHECK(frame.id == expected_id, "routed an identifier that is not the route's");
  FUZZ_CHECK(decoded->message.index() == (route->flow == Flow::kToValve ? 0U : 1U),
             "message of the wrong direction");

  std::visit(
      [&](const auto& message) {
        FUZZ_CHECK(message_id(message) == frame.data[0], "message id is not the first byte");
        FUZZ_CHECK(!message_name(message).empty(), "message without a name");
        check_fields(message);
        check_reencodes(message, frame, *route);
      },
      decoded->message);

  // The payload-level entry points agree with the frame level.
  if (route->flow == Flow::kToValve) {
    const auto payload = decode_to_valve(frame.payload());
    FUZZ_CHECK(payload && *payload == std::get<0>(decoded->message), "decode_to_valve differs");
  } else {
    const auto payload = decode_from_valve(frame.payload());
    FUZZ_CHECK(payload && *payload == std::get<1>(decoded->message), "decode_from_valve differs");
  }
  return 0;
}
