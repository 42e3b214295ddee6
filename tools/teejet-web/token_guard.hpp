#pragma once

// The command token against guessing: compared in constant time, and wrong tokens limited per
// connection and over all connections, so that a script cannot try thousands a second while the
// operator who mistyped once is not hurt. No HTTP in it and a clock passed in, so that the tests
// count exactly what is checked and any transport calls the same code.

#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <string_view>

namespace teejet::web {

// Whether `given` is `expected`, in a time that depends on the length of `given` only.
bool tokens_equal(std::string_view given, std::string_view expected);

struct TokenLimits {
  int free_tries = 5;  // wrong tokens a connection may send before its first lockout
  std::chrono::milliseconds first_lockout{1000};  // doubled by every wrong token after it
  std::chrono::milliseconds max_lockout{60000};
  int per_second = 10;  // wrong tokens checked in each second over all connections
};

class TokenGuard {
 public:
  using Clock = std::function<std::chrono::steady_clock::time_point()>;

  enum class Verdict {
    kAccepted,
    kWrong,       // checked and wrong
    kLockedOut,   // not checked: this connection sent too many wrong tokens
    kServerBusy,  // not checked: too many wrong tokens over all connections this second
  };
  struct Answer {
    Verdict verdict;
    std::chrono::milliseconds wait{0};  // until tokens are checked again (a lockout's length)
    std::string log;                    // what to log, once per burst; empty: nothing
  };

  TokenGuard(std::string token, Clock clock, TokenLimits limits = {});

  // The verdict on `given` from `connection` (any number the transport keeps per connection).
  Answer check(std::uint64_t connection, std::string_view given);
  // The connection closed.
  void forget(std::uint64_t connection);

  // The refusal the page shows for a verdict other than kAccepted.
  static std::string reason(const Answer& answer);

 private:
  struct Tries {
    int wrong = 0;
    std::chrono::steady_clock::time_point locked_until{};
  };

  const std::string token_;
  const Clock clock_;
  const TokenLimits limits_;
  std::mutex mutex_;
  std::map<std::uint64_t, Tries> connections_;
  std::chrono::steady_clock::time_point window_start_{};
  int window_wrong_ = 0;
  bool window_logged_ = false;
};

}  // namespace teejet::web
