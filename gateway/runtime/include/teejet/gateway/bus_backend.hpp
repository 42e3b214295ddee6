#pragma once

// The bus a gateway runs on, made from what --can says: a SocketCAN interface ("can0"), an
// in-process virtual bus ("virtual:NAME"), or "sim:N": a virtual bus shared with N simulated
// valves in this process (the demo, and gateways without hardware).

#include <memory>
#include <optional>
#include <string>

#include "teejet/can/bus.hpp"
#include "teejet/core/result.hpp"
#include "teejet/gateway/config.hpp"
#include "teejet/sim/simulator.hpp"

namespace teejet::gateway {

struct BusBackend {
  std::unique_ptr<can::Bus> bus;              // not opened yet
  std::unique_ptr<sim::Simulator> simulator;  // for sim:N, not started yet; else null
};

Result<BusBackend> make_bus_backend(const GatewayConfig& config);

// How many simulated valves "sim:N" asks for, or nullopt if `can` is not of that form.
Result<std::optional<int>> simulated_valve_count(const std::string& can);

}  // namespace teejet::gateway
