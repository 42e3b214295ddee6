#pragma once

// A gateway assembled in the test process from the project's own parts, the way teejet-gateway
// assembles them: simulated valves on a VirtualBus, the Bridge, and the DDS endpoints, with the
// commander fail-safe wired to the bridge. valvectl runs against it as a separate process.

#include <atomic>
#include <chrono>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "teejet/bridge/bridge.hpp"
#include "teejet/can/virtual_bus.hpp"
#include "teejet/dds/gateway_endpoints.hpp"
#include "teejet/sim/simulator.hpp"

namespace teejet::testing {

struct FakeGatewayOptions {
  int domain = 0;
  std::string name = "fake-gateway";
  std::vector<sim::ValveConfig> valves;
};

class FakeGateway {
 public:
  explicit FakeGateway(const FakeGatewayOptions& options);  // throws when it cannot start
  ~FakeGateway();
  FakeGateway(const FakeGateway&) = delete;
  FakeGateway& operator=(const FakeGateway&) = delete;

  // Sends one I'm Here for `serial` from `address`, as a valve that then falls silent: the
  // gateway shows it online at once and offline after its offline timeout.
  void announce_silent_valve(std::uint32_t serial, std::uint8_t address);

  bridge::Bridge& bridge() { return bridge_; }
  sim::Simulator& simulator() { return simulator_; }
  const std::string& name() const { return name_; }

  // Every command the gateway has handled, in order.
  std::vector<ValveCommand> commands() const;
  // A simulated valve's exact position now.
  double position_of(std::uint32_t serial) const;

 private:
  void drive();

  const std::string name_;
  const std::string bus_name_;
  can::VirtualBus bus_;         // the gateway's side: controller-side filters
  can::VirtualBus silent_bus_;  // for valves that announce themselves and fall silent
  sim::Simulator simulator_;
  dds::Participant participant_;
  dds::GatewayPublisher publisher_;
  bridge::Bridge bridge_;
  dds::CommandSubscription subscription_;

  mutable std::mutex mutex_;
  std::vector<ValveCommand> commands_;
  std::atomic<bool> stopping_{false};
  std::thread driver_;
};

}  // namespace teejet::testing
