#pragma once

// The four modes of gateway_latency; main.cpp reads the command line and runs one. Each returns
// the process's exit status.

#include "options.hpp"

namespace teejet::bench {

// command->frame and frame->sample through a running teejet-gateway (gateway_mode.cpp).
int run_gateway(const Options& options);
// Bare Fast DDS publish->receive to a child process, and that child (baseline_mode.cpp).
int run_baseline(const Options& options);
int run_receive(const Options& options);
// CPU and memory of running processes over a window, and the bus frame rate
// (resources_mode.cpp).
int run_resources(const Options& options);

}  // namespace teejet::bench
