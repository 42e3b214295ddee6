// Linked into every executable of the tsan build only (cmake/TeejetSanitizers.cmake).
//
// ThreadSanitizer of LLVM 14 intercepts pthread_mutex_lock, _trylock and _timedlock but not
// pthread_mutex_clocklock (glibc 2.30). libstdc++'s std::timed_mutex and
// std::recursive_timed_mutex call it for every try_lock_until/try_lock_for on steady_clock, and
// Fast DDS 2.9 guards nearly all its state that way. TSan then sees those mutexes unlocked but
// never locked: "unlock of an unlocked mutex" in Fast DDS, and no happens-before through them,
// so false races on whatever they protect, ours included (samples handed to listeners).
//
// Defined in the executable, this definition wins over glibc's for the executable and for every
// shared library it loads (libfastrtps.so calls it through the PLT). It turns the deadline into
// one on CLOCK_REALTIME and calls pthread_mutex_timedlock, which TSan intercepts. A wall-clock
// jump while waiting changes how long the wait lasts; no test depends on that.

#include <pthread.h>
#include <time.h>

#include <cerrno>
#include <cstdint>

namespace {

constexpr std::int64_t kNanosPerSecond = 1'000'000'000;

std::int64_t to_nanos(const timespec& t) {
  return static_cast<std::int64_t>(t.tv_sec) * kNanosPerSecond + t.tv_nsec;
}

timespec from_nanos(std::int64_t nanos) {
  timespec t{};
  t.tv_sec = static_cast<time_t>(nanos / kNanosPerSecond);
  t.tv_nsec = static_cast<long>(nanos % kNanosPerSecond);
  return t;
}

}  // namespace

extern "C" int pthread_mutex_clocklock(pthread_mutex_t* mutex, clockid_t clock,
                                       const timespec* abstime) {
  if (clock == CLOCK_REALTIME) return pthread_mutex_timedlock(mutex, abstime);
  if (clock != CLOCK_MONOTONIC) return EINVAL;  // glibc accepts only these two as well
  timespec now_clock{};
  timespec now_real{};
  clock_gettime(clock, &now_clock);
  clock_gettime(CLOCK_REALTIME, &now_real);
  const std::int64_t remaining = to_nanos(*abstime) - to_nanos(now_clock);
  // A deadline already past still tries once: timedlock locks a free mutex before it looks at
  // the time, as clocklock does.
  const timespec real_deadline = from_nanos(to_nanos(now_real) + (remaining > 0 ? remaining : 0));
  return pthread_mutex_timedlock(mutex, &real_deadline);
}
