#include "subprocess.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <thread>

extern char** environ;

namespace teejet::testing {
namespace {

void close_fd(int& fd) {
  if (fd >= 0) ::close(fd);
  fd = -1;
}

std::runtime_error system_error(const std::string& what, int error_number) {
  return std::runtime_error(what + ": " + std::strerror(error_number));
}

// Writes to a pipe whose reader may be gone: EPIPE, without the SIGPIPE that would end the test.
ssize_t write_without_sigpipe(int fd, std::string_view data) {
  sigset_t pipe_signal;
  sigset_t previous;
  sigset_t pending;
  ::sigemptyset(&pipe_signal);
  ::sigaddset(&pipe_signal, SIGPIPE);
  ::pthread_sigmask(SIG_BLOCK, &pipe_signal, &previous);
  ::sigpending(&pending);
  const bool was_pending = ::sigismember(&pending, SIGPIPE) == 1;
  const ssize_t written = ::write(fd, data.data(), data.size());
  const int error = errno;
  if (written < 0 && error == EPIPE && !was_pending) {
    const timespec no_wait{0, 0};
    ::sigtimedwait(&pipe_signal, nullptr, &no_wait);  // the SIGPIPE this write raised
  }
  ::pthread_sigmask(SIG_SETMASK, &previous, nullptr);
  errno = error;
  return written;
}

// A cross build (tools/package/check-arm64) runs the programs it built through the emulator CMake
// runs the tests with; the machine's own programs run as they are.
std::vector<std::string> through_emulator(const std::vector<std::string>& argv) {
#ifdef TEEJET_TEST_EMULATOR
  if (argv[0].rfind(TEEJET_TEST_BUILD_DIR "/", 0) == 0) {
    std::vector<std::string> emulated{TEEJET_TEST_EMULATOR};
    emulated.insert(emulated.end(), argv.begin(), argv.end());
    return emulated;
  }
#endif
  return argv;
}

// A pseudo-terminal without line translation: {read end, the terminal}; throws when it cannot.
std::array<int, 2> open_terminal() {
  const int reading = ::posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC);
  if (reading < 0) throw system_error("posix_openpt", errno);
  const char* name = nullptr;
  if (::grantpt(reading) != 0 || ::unlockpt(reading) != 0 ||
      (name = ::ptsname(reading)) == nullptr) {
    const int error = errno;
    ::close(reading);
    throw system_error("pseudo-terminal", error);
  }
  const int terminal = ::open(name, O_RDWR | O_NOCTTY | O_CLOEXEC);
  if (terminal < 0) {
    const int error = errno;
    ::close(reading);
    throw system_error(std::string("open ") + name, error);
  }
  termios raw{};
  ::tcgetattr(terminal, &raw);
  ::cfmakeraw(&raw);
  ::tcsetattr(terminal, TCSANOW, &raw);
  return {reading, terminal};
}

}  // namespace

Subprocess::Subprocess(const std::vector<std::string>& program_argv, Input input, Output output)
    : input_is_pipe_(input == Input::kPipe) {
  if (program_argv.empty()) throw std::invalid_argument("Subprocess: no program");
  const auto argv = through_emulator(program_argv);
  int in_pipe[2] = {-1, -1};
  int out_pipe[2] = {-1, -1};
  int err_pipe[2] = {-1, -1};
  if (output == Output::kTerminal) {
    const auto terminal = open_terminal();
    out_pipe[0] = terminal[0];
    out_pipe[1] = terminal[1];
  }
  if ((input_is_pipe_ && ::pipe2(in_pipe, O_CLOEXEC) != 0) ||
      (out_pipe[0] < 0 && ::pipe2(out_pipe, O_CLOEXEC) != 0) || ::pipe2(err_pipe, O_CLOEXEC) != 0) {
    const int error = errno;
    for (int* fd :
         {&in_pipe[0], &in_pipe[1], &out_pipe[0], &out_pipe[1], &err_pipe[0], &err_pipe[1]}) {
      close_fd(*fd);
    }
    throw system_error("pipe", error);
  }
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  if (input_is_pipe_) {
    posix_spawn_file_actions_adddup2(&actions, in_pipe[0], STDIN_FILENO);
  } else {
    posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  }
  posix_spawn_file_actions_adddup2(&actions, out_pipe[1], STDOUT_FILENO);
  posix_spawn_file_actions_adddup2(&actions, err_pipe[1], STDERR_FILENO);
  std::vector<char*> args;
  for (const auto& arg : argv) args.push_back(const_cast<char*>(arg.c_str()));
  args.push_back(nullptr);
  started_ = std::chrono::steady_clock::now();
  const int spawned = ::posix_spawn(&pid_, args[0], &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  close_fd(in_pipe[0]);
  close_fd(out_pipe[1]);
  close_fd(err_pipe[1]);
  in_fd_ = in_pipe[1];
  out_fd_ = out_pipe[0];
  err_fd_ = err_pipe[0];
  if (spawned != 0) {
    close_fd(in_fd_);
    close_fd(out_fd_);
    close_fd(err_fd_);
    pid_ = -1;
    throw system_error("cannot start " + argv[0], spawned);
  }
  // Input is written only as far as the pipe takes it; the rest waits for the next pump.
  if (in_fd_ >= 0) ::fcntl(in_fd_, F_SETFL, ::fcntl(in_fd_, F_GETFL) | O_NONBLOCK);
}

Subprocess::~Subprocess() {
  if (pid_ > 0) {
    ::kill(pid_, SIGKILL);
    ::waitpid(pid_, nullptr, 0);
  }
  close_fd(in_fd_);
  close_fd(out_fd_);
  close_fd(err_fd_);
}

void Subprocess::write_input(std::string_view text) {
  if (!input_is_pipe_ || close_input_when_written_) {
    throw std::logic_error("Subprocess: standard input is not open for writing");
  }
  if (in_fd_ >= 0) pending_input_.append(text);  // else the child has stopped reading
}

void Subprocess::close_input() {
  if (!input_is_pipe_) throw std::logic_error("Subprocess: standard input is not a pipe");
  close_input_when_written_ = true;
  if (pending_input_.empty()) close_fd(in_fd_);
}

void Subprocess::write_pending_input() {
  const ssize_t written = write_without_sigpipe(in_fd_, pending_input_);
  if (written > 0) {
    pending_input_.erase(0, static_cast<std::size_t>(written));
  } else if (written < 0 && errno != EAGAIN && errno != EINTR) {
    pending_input_.clear();  // the child closed its standard input or ended
    close_fd(in_fd_);
  }
  if (pending_input_.empty() && close_input_when_written_) close_fd(in_fd_);
}

bool Subprocess::pump(std::chrono::steady_clock::time_point until) {
  if (out_fd_ < 0 && err_fd_ < 0) return false;
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
      until - std::chrono::steady_clock::now());
  const int writing_fd = pending_input_.empty() ? -1 : in_fd_;
  std::array<pollfd, 3> fds{{{out_fd_, POLLIN, 0}, {err_fd_, POLLIN, 0}, {writing_fd, POLLOUT, 0}}};
  const int ready =
      ::poll(fds.data(), fds.size(), static_cast<int>(std::max<long long>(left.count(), 0)));
  if (ready <= 0) return true;
  if (fds[2].fd >= 0 && fds[2].revents != 0) write_pending_input();
  std::array<char, 4096> buffer{};
  for (std::size_t i = 0; i < 2; ++i) {
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

bool Subprocess::wait_for(const std::string& stream, const std::string& part,
                          std::chrono::milliseconds limit) {
  const auto until = started_ + limit;
  while (stream.find(part) == std::string::npos) {
    if (std::chrono::steady_clock::now() >= until || !pump(until)) return false;
  }
  return true;
}

bool Subprocess::wait_for_stdout(const std::string& part, std::chrono::milliseconds limit) {
  return wait_for(finished_.out, part, limit);
}

bool Subprocess::wait_for_stderr(const std::string& part, std::chrono::milliseconds limit) {
  return wait_for(finished_.err, part, limit);
}

std::chrono::milliseconds Subprocess::elapsed() const {
  return std::chrono::ceil<std::chrono::milliseconds>(std::chrono::steady_clock::now() - started_);
}

void Subprocess::signal(int signal_number) {
  if (pid_ > 0) ::kill(pid_, signal_number);
}

Finished Subprocess::wait(std::chrono::milliseconds limit) {
  if (pid_ <= 0) throw std::logic_error("Subprocess: wait() called twice");
  const auto until = started_ + limit;
  const auto kill_at_limit = [&] {
    if (finished_.timed_out || std::chrono::steady_clock::now() < until) return;
    ::kill(pid_, SIGKILL);
    finished_.timed_out = true;
  };
  while (!finished_.timed_out && pump(until)) kill_at_limit();
  close_fd(in_fd_);
  close_fd(out_fd_);
  close_fd(err_fd_);
  // The output may end a little before the child does.
  int status = 0;
  pid_t reaped = 0;
  while ((reaped = ::waitpid(pid_, &status, WNOHANG)) == 0 || (reaped < 0 && errno == EINTR)) {
    kill_at_limit();
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  pid_ = -1;
  Finished finished = std::move(finished_);
  finished.took = std::chrono::duration_cast<std::chrono::milliseconds>(
      std::chrono::steady_clock::now() - started_);
  finished.exit_code = reaped > 0 && WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return finished;
}

Finished run(const std::vector<std::string>& argv, std::chrono::milliseconds limit) {
  return Subprocess(argv).wait(limit);
}

std::string describe(const Finished& finished) {
  return "exit " + std::to_string(finished.exit_code) + " after " +
         std::to_string(finished.took.count()) + " ms\n--- stdout\n" + finished.out +
         "--- stderr\n" + finished.err;
}

}  // namespace teejet::testing
