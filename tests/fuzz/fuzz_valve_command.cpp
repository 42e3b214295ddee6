// The command validation path of the gateway (bridge.cpp, Bridge::on_command): a ValveCommand
// as any DDS participant may write it, through teejet::dds::to_message and codec::encode.
//
// Input: valve address, then every ValveCommand member in IDL order: serial and command_id
// (4 bytes each), origin (length byte plus bytes, up to 255: string<64> is cut at its bound),
// kind, direction and telemetry as 4-byte enumerations (values outside the IDL's included),
// speed_percent (1 byte), degrees (a float, NaN, infinities and huge values included),
// milliseconds (2 bytes), resend_tenths (1 byte), bit_rate (4 bytes).
//
// Properties: either a reason that fits CommandStatus.reason (string<256>) uncut, or a frame
// whose bytes are in the sheet's ranges (checked here against the sheet, not the codec's
// table) and carry exactly what the command asked for; to_command gives the command back.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_input.hpp"
#include "teejet/codec/codec.hpp"
#include "teejet/dds/conversions.hpp"

namespace {

using namespace teejet;

constexpr std::size_t kReasonBound = 256;  // CommandStatus.reason is string<256>

std::uint32_t be16(const codec::CanFrame& frame, std::size_t offset) {
  return static_cast<std::uint32_t>(frame.data[offset] << 8 | frame.data[offset + 1]);
}

// The sheet, message by message: a run command's speed 0..100, direction 0/1 (2, shortest, for
// Target Degrees only), degrees 0..3599 tenths; resend period 0..255 tenths; baud marker 0xA5
// (set) or 0x55 (request) and rate code 0 (250k) or 1 (500k).
void check_frame(const codec::CanFrame& frame, const ValveCommand& command, std::uint8_t valve) {
  const std::string what = "frame for command kind " + std::to_string(command.kind());
  FUZZ_CHECK(frame.id == codec::to_valve_id(valve) && frame.extended && !frame.remote, what);
  FUZZ_CHECK(frame.dlc == 8, what);
  const auto id = frame.data[0];
  const auto speed = frame.data[1];
  const auto direction = frame.data[2];
  switch (command.kind()) {
    case COMMAND_STOP:
      FUZZ_CHECK(id == 0x00, what);
      return;
    case COMMAND_CLEAR_ERRORS:
      FUZZ_CHECK(id == 0x04, what);
      return;
    case COMMAND_MANUAL:
      FUZZ_CHECK(id == 0x01, what);
      break;
    case COMMAND_TARGET_DEGREES:
      FUZZ_CHECK(id == 0x02, what);
      break;
    case COMMAND_DEGREES_FROM_POSITION:
      FUZZ_CHECK(id == 0x03, what);
      break;
    case COMMAND_MILLISECONDS_TO_RUN:
      FUZZ_CHECK(id == 0x05, what);
      FUZZ_CHECK(be16(frame, 3) == command.milliseconds(), what + ": milliseconds");
      break;
    case COMMAND_REQUEST:
      FUZZ_CHECK(id == 0x10 + command.telemetry(), what + ": request id");
      if (id == 0x10) {
        FUZZ_CHECK(command.resend_tenths() == 0, what + ": version with a resend period");
      } else {
        FUZZ_CHECK(frame.data[1] == command.resend_tenths(), what + ": resend_tenths");
      }
      return;
    case COMMAND_SET_BAUD_RATE:
      FUZZ_CHECK(id == 0x93 && frame.data[1] == 0xA5 && frame.data[2] <= 1, what);
      FUZZ_CHECK(command.bit_rate() == (frame.data[2] == 1 ? 500000U : 250000U), what);
      return;
    case COMMAND_REQUEST_BAUD_RATE:
      FUZZ_CHECK(id == 0x93 && frame.data[1] == 0x55 && frame.data[2] <= 1, what);
      return;
    default:
      FUZZ_CHECK(false, what + ": a kind the IDL does not define was sent");
  }
  // Run commands with speed and direction.
  FUZZ_CHECK(speed <= 100 && speed == command.speed_percent(), what + ": speed");
  FUZZ_CHECK(direction == command.direction(), what + ": direction");
  FUZZ_CHECK(direction <= (id == 0x02 ? 2 : 1), what + ": direction " + std::to_string(direction));
  if (id == 0x02 || id == 0x03) {
    const auto tenths = be16(frame, 3);
    FUZZ_CHECK(tenths <= 3599, what + ": degrees " + std::to_string(tenths) + " tenths");
    // The nearest tenth of what was asked, never a wrapped or saturated number.
    FUZZ_CHECK(std::isfinite(command.degrees()) &&
                   std::abs(tenths / 10.0 - static_cast<double>(command.degrees())) <= 0.05 + 1e-6,
               what + ": degrees " + std::to_string(command.degrees()) + " sent as " +
                   std::to_string(tenths) + " tenths");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fuzz::Input input(data, size);
  const auto valve = static_cast<std::uint8_t>(
      codec::kFirstValveAddress + input.take<std::uint8_t>() % codec::kValveAddressCount);
  ValveCommand command;
  command.serial(input.take<std::uint32_t>());
  command.command_id(input.take<std::uint32_t>());
  const auto origin = input.take_string();
  command.origin(origin);
  // string<64> is a C string cut at its bound: CDR cannot carry a NUL inside a string either.
  const auto kept = std::min<std::size_t>(origin.find('\0'), 64);
  FUZZ_CHECK(command.origin().to_string() == origin.substr(0, kept),
             "origin of " + std::to_string(origin.size()) + " characters kept " +
                 std::to_string(command.origin().size()));
  command.kind(input.take<CommandKind>());
  command.speed_percent(input.take<std::uint8_t>());
  command.direction(input.take<Direction>());
  command.degrees(input.take_float());
  command.milliseconds(input.take<std::uint16_t>());
  command.telemetry(input.take<Telemetry>());
  command.resend_tenths(input.take<std::uint8_t>());
  command.bit_rate(input.take<std::uint32_t>());

  const auto message = teejet::dds::to_message(command);
  if (!message) {
    FUZZ_CHECK(message.error().code == ErrorCode::kInvalidValue ||
                   message.error().code == ErrorCode::kOutOfRange,
               message.error().reason);
    FUZZ_CHECK(!message.error().reason.empty(), "refused without a reason");
    FUZZ_CHECK(message.error().reason.size() <= kReasonBound, message.error().reason);
    return 0;
  }
  // What a command can carry comes back unchanged through to_command (a NaN is never equal to
  // itself; encode refuses it below).
  const auto round_trip = teejet::dds::to_message(teejet::dds::to_command(*message));
  FUZZ_CHECK(round_trip, "to_command made a command that to_message refuses");
  FUZZ_CHECK(
      *round_trip == *message || std::isnan(command.degrees()),
      "to_message(to_command(m)) != m for " + std::string(teejet::codec::message_name(*message)));

  const auto frame = codec::encode(valve, *message);
  if (!frame) {
    FUZZ_CHECK(frame.error().code == ErrorCode::kOutOfRange, frame.error().reason);
    FUZZ_CHECK(!frame.error().reason.empty(), "refused without a reason");
    FUZZ_CHECK(frame.error().reason.size() <= kReasonBound, frame.error().reason);
    return 0;
  }
  check_frame(*frame, command, valve);
  return 0;
}
