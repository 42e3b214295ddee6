#pragma once

// The running gateway: a CAN bus (SocketCAN, virtual, or a virtual bus with embedded simulated
// valves), the bridge, and the DDS endpoints, with one thread reading the bus and one keeping
// time. DDS callbacks arrive on Fast DDS's own threads.

#include <atomic>
#include <memory>
#include <thread>

#include "config.hpp"
#include "teejet/bridge/bridge.hpp"
#include "teejet/can/bus.hpp"
#include "teejet/dds/gateway_endpoints.hpp"
#include "teejet/sim/simulator.hpp"

namespace teejet::gateway {

class Gateway {
 public:
  explicit Gateway(GatewayConfig config);
  ~Gateway();  // stop()
  Gateway(const Gateway&) = delete;
  Gateway& operator=(const Gateway&) = delete;

  // Opens the bus (and starts the simulator for sim:N), joins DDS and starts the threads.
  // Fails, saying why, without leaving anything running.
  can::Status start();

  // Stops the threads, stops every valve if configured, leaves DDS. Idempotent.
  void stop();

  const bridge::Bridge& bridge() const { return *bridge_; }
  sim::Simulator* simulator() { return simulator_.get(); }

 private:
  void commander_lost(const std::string& what, const std::string& commander);
  void read_bus();
  void keep_time();

  GatewayConfig config_;
  std::unique_ptr<sim::Simulator> simulator_;
  std::unique_ptr<can::Bus> bus_;
  std::unique_ptr<dds::Participant> participant_;
  std::unique_ptr<dds::GatewayPublisher> publisher_;
  std::unique_ptr<bridge::Bridge> bridge_;
  std::atomic<bridge::Bridge*> live_bridge_{nullptr};  // for DDS callbacks
  std::unique_ptr<dds::CommandSubscription> commands_;
  std::atomic<bool> running_{false};
  std::thread reader_;
  std::thread clock_;
};

}  // namespace teejet::gateway
