#include "teejet/core/result.hpp"

namespace teejet {

const char* to_string(ErrorCode code) {
  switch (code) {
    case ErrorCode::kNotExtendedFrame:
      return "not an extended data frame";
    case ErrorCode::kNotThisPgn:
      return "not this PGN";
    case ErrorCode::kNotControllerTraffic:
      return "not to or from the controller";
    case ErrorCode::kNotValveAddress:
      return "not a valve address";
    case ErrorCode::kTooShort:
      return "too short";
    case ErrorCode::kUnknownMessageId:
      return "unknown message id";
    case ErrorCode::kInvalidMarker:
      return "invalid marker byte";
    case ErrorCode::kInvalidValue:
      return "invalid value";
    case ErrorCode::kOutOfRange:
      return "out of range";
    case ErrorCode::kSystem:
      return "system error";
    case ErrorCode::kUnavailable:
      return "unavailable";
    case ErrorCode::kDds:
      return "DDS error";
    case ErrorCode::kStalled:
      return "stalled";
  }
  return "unknown error";
}

Error field_error(ErrorCode code, std::string field, std::string complaint) {
  std::string reason = field + " " + complaint;
  return Error{.code = code,
               .reason = std::move(reason),
               .field = std::move(field),
               .complaint = std::move(complaint)};
}

Error in_context(std::string_view context, Error error) {
  error.reason = std::string(context) + ": " + error.reason;
  return error;
}

}  // namespace teejet
