#include "support/test_domain.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <mutex>
#include <stdexcept>
#include <string>

namespace teejet::testing {
namespace {

// Domain 0 is every program's default and stays free for people; 232 is the highest id.
constexpr int kFirst = 1;
constexpr int kLast = 232;

int reserve() {
  static std::mutex mutex;
  std::lock_guard lock(mutex);
  for (int domain = kFirst; domain <= kLast; ++domain) {
    const std::string path = "/tmp/teejet-test-domain-" + std::to_string(domain) + ".lock";
    const int fd = ::open(path.c_str(), O_CREAT | O_RDWR | O_CLOEXEC, 0666);
    if (fd < 0) continue;
    // Held until the process exits: the kernel releases it however the test ends.
    if (::flock(fd, LOCK_EX | LOCK_NB) == 0) return domain;
    ::close(fd);
  }
  throw std::runtime_error("every DDS test domain is taken by a running test");
}

}  // namespace

int test_domain() {
  static const int domain = reserve();
  return domain;
}

int another_test_domain() {
  (void)test_domain();  // the first reservation stays the process's own domain
  return reserve();
}

}  // namespace teejet::testing
