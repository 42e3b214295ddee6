#include "process_stats.hpp"

#include <filesystem>
#include <fstream>
#include <sstream>

namespace teejet::bench {

namespace {

std::string read_file(const std::string& path) {
  std::ifstream file(path);
  std::stringstream text;
  text << file.rdbuf();
  return text.str();
}

std::string proc_path(int pid, const char* file) {
  std::string path = "/proc/";
  path.append(std::to_string(pid)).append("/").append(file);
  return path;
}

}  // namespace

// Fields 14 and 15 of /proc/PID/stat; the command name in field 2 may contain spaces, so fields
// are counted after its closing parenthesis.
std::optional<std::uint64_t> cpu_ticks(int pid) {
  const std::string stat = read_file(proc_path(pid, "stat"));
  const auto name_end = stat.rfind(')');
  if (name_end == std::string::npos) return std::nullopt;
  std::istringstream fields(stat.substr(name_end + 2));
  std::string field;
  std::uint64_t user = 0, system = 0;
  for (int number = 3; number <= 15 && fields >> field; ++number) {
    if (number == 14) user = std::stoull(field);
    if (number == 15) system = std::stoull(field);
  }
  return user + system;
}

std::uint64_t status_value(int pid, const std::string& name) {
  std::istringstream status(read_file(proc_path(pid, "status")));
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind(name + ":", 0) == 0) return std::stoull(line.substr(name.size() + 1));
  }
  return 0;
}

std::uint64_t open_fds(int pid) {
  std::error_code error;
  std::uint64_t count = 0;
  for (std::filesystem::directory_iterator it(proc_path(pid, "fd"), error), end;
       !error && it != end; it.increment(error)) {
    ++count;
  }
  return count;
}

std::uint64_t thread_count(int pid) { return status_value(pid, "Threads"); }

std::string process_name(int pid) {
  std::string name = read_file(proc_path(pid, "comm"));
  if (!name.empty() && name.back() == '\n') name.pop_back();
  return name;
}

std::optional<std::uint64_t> bus_frames(const std::string& interface) {
  std::string path = "/sys/class/net/";
  path.append(interface).append("/statistics/tx_packets");
  const std::string count = read_file(path);
  if (count.empty()) return std::nullopt;
  return std::stoull(count);
}

}  // namespace teejet::bench
