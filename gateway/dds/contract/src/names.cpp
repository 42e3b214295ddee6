#include "teejet/dds/names.hpp"

#include "teejet/codec/table.hpp"
#include "teejet/dds/conversions.hpp"

namespace teejet::dds {

std::string_view to_string(CommandKind kind) {
  switch (kind) {
    case COMMAND_STOP:
      return "stop";
    case COMMAND_MANUAL:
      return "manual";
    case COMMAND_TARGET_DEGREES:
      return "target_degrees";
    case COMMAND_DEGREES_FROM_POSITION:
      return "degrees_from_position";
    case COMMAND_CLEAR_ERRORS:
      return "clear_errors";
    case COMMAND_MILLISECONDS_TO_RUN:
      return "milliseconds_to_run";
    case COMMAND_REQUEST:
      return "request";
    case COMMAND_SET_BAUD_RATE:
      return "set_baud_rate";
    case COMMAND_REQUEST_BAUD_RATE:
      return "request_baud_rate";
  }
  return "unknown_command";
}

std::string_view to_string(CommandState state) {
  switch (state) {
    case COMMAND_ACCEPTED:
      return "accepted";
    case COMMAND_REJECTED:
      return "rejected";
    case COMMAND_COMPLETED:
      return "completed";
    case COMMAND_TIMED_OUT:
      return "timed_out";
    case COMMAND_SUPERSEDED:
      return "superseded";
  }
  return "unknown_state";
}

std::string_view to_string(Direction direction) {
  const auto word = direction_word(direction);
  return word.empty() ? "unknown" : word;
}

std::string_view to_string(ErrorKind kind) {
  const auto message = error_message_of(kind);
  return message ? codec::error_kind(*message) : "unknown";
}

std::string_view to_string(Telemetry telemetry) {
  const auto request = request_of(telemetry);
  return request ? codec::subject(*request) : "unknown";
}

std::string_view to_string(BusState state) {
  switch (state) {
    case BUS_ERROR_ACTIVE:
      return "error_active";
    case BUS_ERROR_WARNING:
      return "error_warning";
    case BUS_ERROR_PASSIVE:
      return "error_passive";
    case BUS_OFF:
      return "bus_off";
    case BUS_DOWN:
      return "down";
  }
  return "unknown";
}

std::string_view to_string(AddressClaimState state) { return isobus::to_string(from_idl(state)); }

std::string_view to_string(LocationRole role) {
  switch (role) {
    case ROLE_SECTION:
      return "section";
    case ROLE_MASTER:
      return "master";
    case ROLE_RATE:
      return "rate";
    case ROLE_OTHER:
      return "other";
  }
  return "unknown";
}

std::string_view to_string(LocationState state) {
  switch (state) {
    case LOCATION_OK:
      return "ok";
    case LOCATION_MISSING:
      return "missing";
    case LOCATION_EMPTY:
      return "empty";
  }
  return "unknown";
}

std::string_view to_string(LayoutChangeKind kind) {
  switch (kind) {
    case LAYOUT_ASSIGN:
      return "assign";
    case LAYOUT_UNASSIGN:
      return "unassign";
  }
  return "unknown";
}

std::string_view to_string(LayoutChangeState state) {
  switch (state) {
    case LAYOUT_CHANGE_APPLIED:
      return "applied";
    case LAYOUT_CHANGE_REJECTED:
      return "rejected";
  }
  return "unknown";
}

}  // namespace teejet::dds
