#pragma once

// The one error vocabulary of every layer: a value or an Error that says why not. Nothing in the
// gateway throws across a layer boundary; bad input and failed system calls come back as Errors.

#include <string>
#include <string_view>
#include <utility>
#include <variant>

namespace teejet {

enum class ErrorCode {
  // The valve protocol: frames that are not ours or do not decode, values the sheet refuses.
  kNotExtendedFrame,      // 11-bit id, remote request: not this protocol
  kNotThisPgn,            // 29-bit id outside 0x18EFxxxx
  kNotControllerTraffic,  // neither source nor destination is the controller (0xD5)
  kNotValveAddress,       // the valve side is outside 0xD8..0xF7
  kTooShort,              // fewer data bytes than the message needs
  kUnknownMessageId,      // first data byte is not a message of this direction
  kInvalidMarker,         // a marker byte (0xA5/0x55 of the baud-rate messages) is wrong
  kInvalidValue,          // a value that is not defined: an enumeration byte, a configuration word
  kOutOfRange,            // a number outside its allowed range
  // Running.
  kSystem,       // an operating-system call failed; Error::os_error holds its errno
  kUnavailable,  // not open, already running, link down: try again when the state changes
  kDds,          // the DDS middleware refused (participant, profiles, topic, writer, reader)
  kStalled,  // a library's thread stopped for good (a deadlock): end the process, not the object
};

const char* to_string(ErrorCode code);

struct Error {
  ErrorCode code = ErrorCode::kInvalidValue;
  std::string reason;  // for people: names the thing, the offending value and what is allowed
  int os_error = 0;    // errno for kSystem (and link faults), 0 otherwise
  // A value refused by a check: the field it is about ("speed_percent") and what is wrong with
  // the value ("101 is outside 0 to 100"), so that a caller can name the field its own way
  // (valvectl says --speed) without taking `reason` apart. Empty for other errors.
  std::string field;
  std::string complaint;
};

// An Error about one field's value, for people "<field> <complaint>".
Error field_error(ErrorCode code, std::string field, std::string complaint);

// `error` said in a context, "<context>: <reason>" ("manual: speed_percent 101 is outside 0 to
// 100"); its field and complaint stay as they are.
Error in_context(std::string_view context, Error error);

// Either a value or an Error, in the manner of C++23's std::expected.
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
  T* operator->() { return &value(); }
  const T& operator*() const& { return value(); }
  T& operator*() & { return value(); }

  const Error& error() const { return std::get<1>(state_); }

 private:
  std::variant<T, Error> state_;
};

// Success, or an Error.
template <>
class [[nodiscard]] Result<void> {
 public:
  Result() = default;
  Result(Error error) : error_(std::move(error)), failed_(true) {}  // NOLINT

  bool ok() const { return !failed_; }
  explicit operator bool() const { return ok(); }
  const Error& error() const { return error_; }

 private:
  Error error_;
  bool failed_ = false;
};

using Status = Result<void>;

}  // namespace teejet
