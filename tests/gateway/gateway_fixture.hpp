#pragma once

// What the in-process gateway suites share: a gateway on the embedded simulator, configured for
// quick tests, and views of the simulator behind it (where a valve really is, the wire).

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>

#include "support/eventually.hpp"
#include "support/test_domain.hpp"
#include "support/valve_commands.hpp"
#include "teejet/can/virtual_bus.hpp"
#include "teejet/gateway/bus_backend.hpp"
#include "teejet/gateway/gateway.hpp"

namespace teejet::gateway::fixture {

inline GatewayConfig sim_config(const std::string& name, int valves,
                                std::uint32_t first_serial = 1) {
  using namespace std::chrono_literals;
  GatewayConfig config;
  config.can = "sim:" + std::to_string(valves);
  config.domain = teejet::testing::test_domain();
  config.bridge.gateway_name = name;
  config.sim_first_serial = first_serial;
  config.sim_degrees_per_second = 180;  // quick moves keep the suites short
  config.bridge.offline_after = 1500ms;
  config.bridge.move_margin = 1s;
  config.bridge.layout = *layout::Layout::make({}, layout::Mechanics{0, 90});
  return config;
}

// The gateway as teejet-gateway makes it: the bus its configuration names.
inline std::unique_ptr<Gateway> make_gateway(const GatewayConfig& config) {
  auto backend = make_bus_backend(config);
  EXPECT_TRUE(backend) << backend.error().reason;
  return std::make_unique<Gateway>(config, backend ? std::move(*backend) : BusBackend{});
}

// Starts `gateway` and waits until its bridge knows `valves` valves, all online, and holds its
// address. Call it with
// ASSERT_NO_FATAL_FAILURE.
inline void start_and_wait_online(Gateway& gateway, std::size_t valves) {
  using namespace std::chrono_literals;
  ASSERT_TRUE(gateway.start());
  ASSERT_TRUE(teejet::testing::eventually(
      [&] {
        const auto known = gateway.bridge().valves();
        return known.size() == valves &&
               std::all_of(known.begin(), known.end(), [](auto& v) { return v.online; });
      },
      15s))
      << "the gateway never saw its simulated valves";
  // And holds its address: what waited for the claim (the valves' polls) has gone out.
  ASSERT_TRUE(teejet::testing::eventually(
      [&] { return gateway.bridge().claim_state() != isobus::ClaimState::kClaiming; }, 15s))
      << "the gateway never ended its address claim";
}

// Where a simulated valve really is: what the wire should have made it do.
inline double position_of(Gateway& gateway, std::uint32_t serial) {
  auto* simulator = gateway.simulator();
  return simulator->inspect([&](const sim::ValveBank& bank) {
    return bank.valve_with_serial(serial)->position(simulator->clock()->steady());
  });
}

// The wire as the valves see it: every controller-to-valve frame, in order, from now on.
inline std::unique_ptr<can::VirtualBus> watch_wire(Gateway& gateway) {
  auto wire = std::make_unique<can::VirtualBus>(
      gateway.simulator()->bus_name(),
      can::VirtualBusOptions{.filters = can::valve_side_filters(), .queue_limit = 1'000'000});
  EXPECT_TRUE(wire->open());
  return wire;
}

}  // namespace teejet::gateway::fixture
