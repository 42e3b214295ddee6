#include "token_guard.hpp"

#include <algorithm>
#include <utility>

namespace teejet::web {

using std::chrono::milliseconds;

bool tokens_equal(std::string_view given, std::string_view expected) {
  if (expected.empty()) return given.empty();
  // Every byte of `given` is compared, whatever it holds and however long `expected` is.
  unsigned difference = given.size() != expected.size() ? 1 : 0;
  for (std::size_t i = 0; i < given.size(); ++i) {
    difference |= static_cast<unsigned>(static_cast<unsigned char>(given[i])) ^
                  static_cast<unsigned>(static_cast<unsigned char>(expected[i % expected.size()]));
  }
  return difference == 0;
}

TokenGuard::TokenGuard(std::string token, Clock clock, TokenLimits limits)
    : token_(std::move(token)), clock_(std::move(clock)), limits_(limits) {}

TokenGuard::Answer TokenGuard::check(std::uint64_t connection, std::string_view given) {
  const auto seconds = [](milliseconds wait) {
    return std::to_string((wait.count() + 999) / 1000);
  };
  std::lock_guard lock(mutex_);
  const auto now = clock_();
  Tries& tries = connections_[connection];
  if (now < tries.locked_until) {
    return {Verdict::kLockedOut, std::chrono::ceil<milliseconds>(tries.locked_until - now), ""};
  }
  if (now - window_start_ >= std::chrono::seconds(1)) {
    window_start_ = now;
    window_wrong_ = 0;
    window_logged_ = false;
  }
  if (window_wrong_ >= limits_.per_second) {
    const auto wait =
        std::chrono::ceil<milliseconds>(window_start_ + std::chrono::seconds(1) - now);
    std::string log;
    if (!std::exchange(window_logged_, true)) {
      log = std::to_string(window_wrong_) +
            " wrong tokens in a second over all connections: no token is checked for " +
            seconds(wait) + " s";
    }
    return {Verdict::kServerBusy, wait, log};
  }
  if (tokens_equal(given, token_)) {
    tries.wrong = 0;
    return {Verdict::kAccepted, milliseconds(0), ""};
  }
  ++window_wrong_;
  ++tries.wrong;
  if (tries.wrong < limits_.free_tries) {
    return {Verdict::kWrong, milliseconds(0), tries.wrong == 1 ? "wrong token" : ""};
  }
  const int doublings = std::min(tries.wrong - limits_.free_tries, 30);
  const milliseconds lockout =
      std::min(limits_.max_lockout, limits_.first_lockout * (std::int64_t{1} << doublings));
  tries.locked_until = now + lockout;
  return {Verdict::kWrong, lockout,
          std::to_string(tries.wrong) + " wrong tokens on one connection: its tokens are not " +
              "checked for " + seconds(lockout) + " s"};
}

void TokenGuard::forget(std::uint64_t connection) {
  std::lock_guard lock(mutex_);
  connections_.erase(connection);
}

std::string TokenGuard::reason(const Answer& answer) {
  const std::string seconds = std::to_string((answer.wait.count() + 999) / 1000);
  switch (answer.verdict) {
    case Verdict::kLockedOut:
      return "too many wrong tokens on this connection: not checked for " + seconds + " s";
    case Verdict::kServerBusy:
      return "too many wrong tokens on this server: not checked for " + seconds + " s";
    default:
      return "missing or wrong \"token\"";
  }
}

}  // namespace teejet::web
