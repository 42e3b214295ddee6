#include "subprocess.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <stdexcept>

extern char** environ;

namespace teejet::testing {
namespace {

void close_fd(int& fd) {
  if (fd >= 0) ::close(fd);
  fd = -1;
}

}  // namespace

Subprocess::Subprocess(const std::vector<std::string>& argv) {
  int out_pipe[2];
  int err_pipe[2];
  if (::pipe2(out_pipe, O_CLOEXEC) != 0 || ::pipe2(err_pipe, O_CLOEXEC) != 0) {
    throw std::runtime_error(std::string("pipe: ") + std::strerror(errno));
  }
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, out_pipe[1], STDOUT_FILENO);
  posix_spawn_file_actions_adddup2(&actions, err_pipe[1], STDERR_FILENO);
  std::vector<char*> args;
  for (const auto& arg : argv) args.push_back(const_cast<char*>(arg.c_str()));
  args.push_back(nullptr);
  started_ = std::chrono::steady_clock::now();
  const int spawned = ::posix_spawn(&pid_, args[0], &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(out_pipe[1]);
  ::close(err_pipe[1]);
  out_fd_ = out_pipe[0];
  err_fd_ = err_pipe[0];
  if (spawned != 0) {
    close_fd(out_fd_);
    close_fd(err_fd_);
    pid_ = -1;
    throw std::runtime_error("cannot start " + argv[0] + ": " + std::strerror(spawned));
  }
}

Subprocess::~Subprocess() {
  if (pid_ > 0) {
    ::kill(pid_, SIGKILL);
    ::waitpid(pid_, nullptr, 0);
  }
  close_fd(out_fd_);
  close_fd(err_fd_);
}

bool Subprocess::pump(std::chrono::steady_clock::time_point until) {
  if (out_fd_ < 0 && err_fd_ < 0) return false;
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
      until - std::chrono::steady_clock::now());
  std::array<pollfd, 2> fds{{{out_fd_, POLLIN, 0}, {err_fd_, POLLIN, 0}}};
  const int ready =
      ::poll(fds.data(), fds.size(), static_cast<int>(std::max<long long>(left.count(), 0)));
  if (ready <= 0) return true;
  std::array<char, 4096> buffer{};
  for (std::size_t i = 0; i < fds.size(); ++i) {
    if (fds[i].fd < 0 || fds[i].revents == 0) continue;
    const ssize_t n = ::read(fds[i].fd, buffer.data(), buffer.size());
    if (n > 0) {
      (i == 0 ? finished_.out : finished_.err).append(buffer.data(), static_cast<std::size_t>(n));
    } else {
      close_fd(i == 0 ? out_fd_ : err_fd_);
    }
  }
  return true;
}

bool Subprocess::wait_for_output(const std::string& part, std::chrono::milliseconds limit) {
  const auto until = started_ + limit;
  while (finished_.out.find(part) == std::string::npos) {
    if (std::chrono::steady_clock::now() >= until || !pump(until)) return false;
  }
  return true;
}

void Subprocess::signal(int signal_number) {
  if (pid_ > 0) ::kill(pid_, signal_number);
}

Finished Subprocess::wait(std::chrono::milliseconds limit) {
  const auto until = started_ + limit;
  while (pump(until)) {
    if (std::chrono::steady_clock::now() >= until) {
      ::kill(pid_, SIGKILL);
      break;
    }
  }
  close_fd(out_fd_);
  close_fd(err_fd_);
  int status = 0;
  ::waitpid(pid_, &status, 0);
  pid_ = -1;
  Finished finished = std::move(finished_);
  finished.took = std::chrono::duration_cast<std::chrono::milliseconds>(
      std::chrono::steady_clock::now() - started_);
  finished.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return finished;
}

Finished run(const std::vector<std::string>& argv, std::chrono::milliseconds limit) {
  return Subprocess(argv).wait(limit);
}

}  // namespace teejet::testing
