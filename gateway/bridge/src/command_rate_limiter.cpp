#include "command_rate_limiter.hpp"

#include <algorithm>

namespace teejet::bridge {

bool CommandRateLimiter::admit(std::uint32_t serial, bool stop, SteadyTime now) {
  if (per_second_ <= 0) return true;
  auto [it, fresh] = buckets_.try_emplace({serial, stop}, Bucket{burst_, now});
  Bucket& bucket = it->second;
  if (!fresh && now > bucket.refilled) {
    const double elapsed = std::chrono::duration<double>(now - bucket.refilled).count();
    bucket.tokens = std::min(burst_, bucket.tokens + elapsed * per_second_);
    bucket.refilled = now;
  }
  if (bucket.tokens < 1.0) return false;
  bucket.tokens -= 1.0;
  return true;
}

}  // namespace teejet::bridge
