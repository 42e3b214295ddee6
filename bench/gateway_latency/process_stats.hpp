#pragma once

// What the kernel says about a running process and a network interface (/proc, /sys).

#include <cstdint>
#include <optional>
#include <string>

namespace teejet::bench {

// utime + stime of a process in clock ticks; nullopt when there is no such process.
std::optional<std::uint64_t> cpu_ticks(int pid);

// The number on a "Name:   value" line of /proc/PID/status: "VmRSS", "VmHWM" (KiB), "Threads";
// 0 when missing.
std::uint64_t status_value(int pid, const std::string& name);

// Open file descriptors (entries of /proc/PID/fd) and threads (Threads: of /proc/PID/status).
std::uint64_t open_fds(int pid);
std::uint64_t thread_count(int pid);

// The command name of a process (/proc/PID/comm).
std::string process_name(int pid);

// Frames the interface carried (vcan counts every frame sent on it as tx); nullopt when there
// is no such interface.
std::optional<std::uint64_t> bus_frames(const std::string& interface);

}  // namespace teejet::bench
