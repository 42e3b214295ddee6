#include "teejet/gateway/bus_backend.hpp"

#include <unistd.h>

#include <atomic>
#include <charconv>

#include "teejet/can/open_bus.hpp"
#include "teejet/can/virtual_bus.hpp"
#include "teejet/codec/can_id.hpp"

namespace teejet::gateway {
namespace {

Result<std::vector<sim::ValveConfig>> simulated_valves(const GatewayConfig& config, int count) {
  if (!config.sim_serials.empty() && config.sim_serials.size() != static_cast<std::size_t>(count)) {
    return Error{ErrorCode::kInvalidValue, "--can " + config.can + ": simulator.serials lists " +
                                               std::to_string(config.sim_serials.size()) +
                                               " serials for " + std::to_string(count) + " valves"};
  }
  std::vector<sim::ValveConfig> valves;
  for (int i = 0; i < count; ++i) {
    sim::ValveConfig valve;
    valve.serial = config.sim_serials.empty()
                       ? config.sim_first_serial + static_cast<std::uint32_t>(i)
                       : config.sim_serials[static_cast<std::size_t>(i)];
    valve.degrees_per_second = config.sim_degrees_per_second;
    valve.closed_degrees = config.sim_closed_degrees;
    valve.opened_degrees = config.sim_opened_degrees;
    valves.push_back(valve);
  }
  return valves;
}

}  // namespace

Result<std::optional<int>> simulated_valve_count(const std::string& can) {
  constexpr std::string_view kPrefix = "sim:";
  if (!can.starts_with(kPrefix)) return std::optional<int>{};
  const std::string_view digits = std::string_view(can).substr(kPrefix.size());
  int count = 0;
  const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), count);
  if (digits.empty() || ec != std::errc() || end != digits.data() + digits.size() || count < 1 ||
      count > codec::kValveAddressCount) {
    return Error{ErrorCode::kOutOfRange,
                 "--can " + can + ": sim:N takes 1 to 32 valves (one per address 0xD8..0xF7)"};
  }
  return std::optional<int>{count};
}

Result<BusBackend> make_bus_backend(const GatewayConfig& config) {
  auto simulated = simulated_valve_count(config.can);
  if (!simulated) return simulated.error();
  if (!*simulated) {
    // A gateway started before its CAN interface exists waits for it (docs/faults.md).
    return BusBackend{can::make_bus(config.can, {.filters = bridge::frames_to_hear(config.bridge),
                                                 .wait_for_interface = true}),
                      {}};
  }
  // Unique per gateway, so that two embedded simulations in one process never share a bus.
  static std::atomic<int> instances{0};
  const std::string bus_name =
      "teejet-sim-" + std::to_string(::getpid()) + "-" + std::to_string(++instances);
  auto valves = simulated_valves(config, **simulated);
  if (!valves) return valves.error();
  BusBackend backend;
  backend.simulator = std::make_unique<sim::Simulator>(
      std::make_unique<can::VirtualBus>(bus_name,
                                        can::VirtualBusOptions{can::valve_side_filters()}),
      sim::SimulatorOptions{.valves = std::move(*valves),
                            .errors = config.sim_errors,
                            .churn = {.period = config.sim_churn_period,
                                      .off_for = config.sim_churn_off_time(),
                                      .seed = config.sim_churn_seed}});
  backend.bus = can::make_bus("virtual:" + bus_name, bridge::frames_to_hear(config.bridge));
  return backend;
}

}  // namespace teejet::gateway
