#pragma once

// The running gateway: its bus (and the simulated valves of sim:N), the bridge, and the DDS
// endpoints, with two threads of its own: one reads the bus, one takes commands. Both keep the
// bridge's deadlines, waiting exactly until the next one. Fast DDS's threads only queue news of
// lost commanders.

#include <memory>
#include <mutex>
#include <thread>

#include "teejet/bridge/bridge.hpp"
#include "teejet/can/bus.hpp"
#include "teejet/dds/command_subscription.hpp"
#include "teejet/dds/event_watchdog.hpp"
#include "teejet/dds/frame_publisher.hpp"
#include "teejet/dds/gateway_publisher.hpp"
#include "teejet/gateway/bus_backend.hpp"
#include "teejet/gateway/config.hpp"
#include "teejet/sim/simulator.hpp"

namespace teejet::gateway {

class Gateway {
 public:
  // Runs on `backend`: its bus, and its simulator when there is one.
  Gateway(GatewayConfig config, BusBackend backend,
          std::shared_ptr<const Clock> clock = system_clock());
  ~Gateway();  // stop()
  Gateway(const Gateway&) = delete;
  Gateway& operator=(const Gateway&) = delete;

  // Starts the simulator, opens the bus, joins DDS and starts the threads. Fails, saying why,
  // without leaving anything running.
  Status start();

  // In this order: stops taking commands (the command reader is deleted), sends Stop to every
  // online valve if configured, stops reading the bus, leaves DDS, closes the bus, stops the
  // simulator. Idempotent.
  void stop();

  // Called once, on a thread of its own, when Fast DDS's event thread of this gateway's
  // participant has run no timer for `stalled_after` (dds/event_watchdog.hpp): the gateway then
  // hears and announces nothing any more, and stop() would wait forever. Set before start();
  // without one, the stall is only logged.
  void on_dds_stalled(std::function<void(Duration silent_for)> handler,
                      Duration stalled_after = std::chrono::seconds(30));

  // Stop to every online valve, if configured (as stop() does), once: a later call, or one
  // after stop() stopped them, returns 0 and touches nothing. Without touching DDS's entities
  // but the command statuses it writes; returns how many. Any thread.
  std::size_t stop_valves();

  const bridge::Bridge& bridge() const { return *bridge_; }
  const dds::GatewayPublisher& publisher() const { return *publisher_; }
  sim::Simulator* simulator() { return backend_.simulator.get(); }

 private:
  void read_bus(std::stop_token stop);
  void take_commands(std::stop_token stop);
  void commander_lost(const std::string& commander);
  void log_changes();
  Duration until(SteadyTime deadline) const;

  GatewayConfig config_;
  BusBackend backend_;
  const std::shared_ptr<const Clock> clock_;
  std::shared_ptr<dds::LostCommanders> lost_commanders_;
  std::unique_ptr<dds::Participant> participant_;
  std::function<void(Duration)> on_dds_stalled_;
  Duration dds_stalled_after_ = std::chrono::seconds(30);
  std::unique_ptr<dds::EventWatchdog> watchdog_;  // deleted just after participant_
  std::mutex valves_mutex_;                       // stop_valves() against bridge_'s reset
  bool valves_stopped_ = false;
  std::unique_ptr<dds::GatewayPublisher> publisher_;
  std::unique_ptr<dds::FramePublisher> frames_;        // with record_frames only
  can::ObservedBus* observed_bus_ = nullptr;           // backend_.bus while frames_ observes it
  std::unique_ptr<layout::LayoutStore> layout_store_;  // config_.layout_file's keeper
  std::unique_ptr<bridge::Bridge> bridge_;
  std::unique_ptr<dds::CommandSubscription> commands_;
  std::jthread reader_;
  std::jthread commander_;

  // What log_changes() said last; reader thread only.
  can::BusState logged_state_ = can::BusState::kErrorActive;
  std::uint64_t logged_decode_errors_ = 0;
  SteadyTime next_decode_report_{};
};

}  // namespace teejet::gateway
