#pragma once

#include <string>
#include <utility>
#include <variant>

namespace teejet::codec {

// Why a frame could not be decoded or a message could not be encoded.
enum class ErrorCode {
  kNotExtendedFrame,      // 11-bit id, remote request: not this protocol
  kNotThisPgn,            // 29-bit id outside 0x18EFxxxx
  kNotControllerTraffic,  // neither source nor destination is the controller (0xD5)
  kNotValveAddress,       // the valve side is outside 0xD8..0xF7
  kTooShort,              // fewer data bytes than the message needs
  kUnknownMessageId,      // first data byte is not a message of this direction
  kInvalidMarker,         // a marker byte (0xA5/0x55 of the baud-rate messages) is wrong
  kInvalidValue,          // an enumerated byte holds a value the sheet does not define
  kOutOfRange,            // encoder: a value outside the sheet's range
};

const char* to_string(ErrorCode code);

struct Error {
  ErrorCode code;
  std::string reason;  // human-readable, names the field and the offending value
};

// Either a value or an Error; the codec never throws and never crashes on bad input.
template <class T>
class [[nodiscard]] Result {
 public:
  Result(T value) : state_(std::move(value)) {}      // NOLINT(google-explicit-constructor)
  Result(Error error) : state_(std::move(error)) {}  // NOLINT(google-explicit-constructor)

  bool ok() const { return state_.index() == 0; }
  explicit operator bool() const { return ok(); }

  const T& value() const& { return std::get<0>(state_); }
  T& value() & { return std::get<0>(state_); }
  T&& value() && { return std::get<0>(std::move(state_)); }
  const T* operator->() const { return &value(); }
  const T& operator*() const { return value(); }

  const Error& error() const { return std::get<1>(state_); }

 private:
  std::variant<T, Error> state_;
};

}  // namespace teejet::codec
