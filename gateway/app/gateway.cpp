#include "gateway.hpp"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include "teejet/can/open_bus.hpp"
#include "teejet/can/virtual_bus.hpp"

namespace teejet::gateway {
namespace {

using namespace std::chrono_literals;

bridge::Timestamp now() {
  return std::chrono::duration_cast<bridge::Timestamp>(
      std::chrono::system_clock::now().time_since_epoch());
}

std::vector<sim::ValveConfig> simulated_valves(const GatewayConfig& config, int count) {
  std::vector<sim::ValveConfig> valves;
  for (int i = 0; i < count; ++i) {
    sim::ValveConfig valve;
    valve.serial = config.sim_first_serial + static_cast<std::uint32_t>(i);
    valve.degrees_per_second = config.sim_degrees_per_second;
    valve.closed_degrees = config.sim_closed_degrees;
    valve.opened_degrees = config.sim_opened_degrees;
    valves.push_back(valve);
  }
  return valves;
}

}  // namespace

Gateway::Gateway(GatewayConfig config) : config_(std::move(config)) {}

Gateway::~Gateway() { stop(); }

can::Status Gateway::start() {
  auto simulated = simulated_valve_count(config_.can);
  if (!simulated) return can::Status::failure(simulated.error().reason);
  if (*simulated) {
    // An in-process bus shared with simulated valves: the demo, and gateways without hardware.
    // Unique per gateway, so that two embedded simulations in one process never share a bus.
    static std::atomic<int> instances{0};
    const std::string bus_name =
        "teejet-sim-" + std::to_string(::getpid()) + "-" + std::to_string(++instances);
    simulator_ = std::make_unique<sim::Simulator>(
        std::make_unique<can::VirtualBus>(bus_name,
                                          can::VirtualBusOptions{can::valve_side_filters()}),
        sim::SimulatorOptions{.valves = simulated_valves(config_, **simulated)});
    if (auto started = simulator_->start(); !started) return started;
    bus_ = can::make_bus("virtual:" + bus_name, can::controller_side_filters());
  } else {
    bus_ = can::make_bus(config_.can, can::controller_side_filters());
  }
  if (auto opened = bus_->open(); !opened) return opened;
  config_.bridge.can_interface = config_.can;

  try {
    // Two signals for a dead commander: its writer's liveliness (2 s lease) and its
    // participant's lease. Fast DDS 2.9 misses the first once another command writer is alive
    // (docs/gateway.md), so the second backs it up.
    participant_ = std::make_unique<dds::Participant>(
        dds::ParticipantOptions{.domain = config_.domain,
                                .profile_file = config_.profile_file,
                                .name = config_.bridge.gateway_name,
                                .on_participant_dropped = [this](const std::string& prefix) {
                                  commander_lost("participant " + prefix + " dropped", prefix);
                                }});
    publisher_ = std::make_unique<dds::GatewayPublisher>(*participant_);
    bridge_ = std::make_unique<bridge::Bridge>(config_.bridge, *bus_, *publisher_);
    live_bridge_ = bridge_.get();
    commands_ = std::make_unique<dds::CommandSubscription>(
        *participant_,
        [this](const ValveCommand& command, const std::string& writer) {
          bridge_->on_command(command, now(), writer);
        },
        [this](const std::string& writer) {
          commander_lost("command writer " + writer + " lost liveliness", writer);
        });
  } catch (const dds::DdsError& error) {
    stop();
    return can::Status::failure(error.what());
  }

  running_ = true;
  reader_ = std::thread([this] { read_bus(); });
  clock_ = std::thread([this] { keep_time(); });
  spdlog::info("gateway '{}' on {} in DDS domain {}", config_.bridge.gateway_name, config_.can,
               config_.domain);
  return {};
}

void Gateway::stop() {
  running_ = false;
  if (reader_.joinable()) reader_.join();
  if (clock_.joinable()) clock_.join();
  if (bridge_ && config_.stop_valves_on_exit) {
    const auto stopped = bridge_->stop_all(now());
    spdlog::info("stopped {} valve(s) on exit", stopped);
  }
  live_bridge_ = nullptr;
  // Deleting the participant deletes the command reader, after which no callback can reach
  // the listener or the bridge; only then may they go.
  participant_.reset();
  commands_.reset();
  bridge_.reset();
  publisher_.reset();
  if (bus_) bus_->close();
  if (simulator_) simulator_->stop();
}

void Gateway::commander_lost(const std::string& what, const std::string& commander) {
  // Discovery runs on Fast DDS's threads, possibly before the bridge exists or while it goes.
  bridge::Bridge* bridge = live_bridge_;
  if (bridge == nullptr) return;
  if (config_.on_commander_lost != OnCommanderLost::kStopItsValves) {
    spdlog::info("{} (fail-safe off)", what);
    return;
  }
  const auto stopped = bridge->stop_commanded_by(commander, now());
  if (stopped > 0) spdlog::warn("{}: fail-safe stopped {} valve(s)", what, stopped);
}

void Gateway::read_bus() {
  while (running_) {
    if (auto frame = bus_->receive(100ms)) bridge_->on_frame(*frame);
  }
}

// Offline detection, command deadlines and the status topic need a clock that ticks even on a
// silent bus. Logs only what changed: a quiet bus makes no log lines.
void Gateway::keep_time() {
  auto last_state = can::BusState::kErrorActive;
  std::uint64_t last_decode_errors = 0;
  auto next_report = std::chrono::steady_clock::now();
  while (running_) {
    bridge_->tick(now());
    const auto state = bus_->statistics().state;
    if (state != last_state) {
      spdlog::warn("CAN bus {} is {}", config_.can, can::to_string(state));
      last_state = state;
    }
    if (std::chrono::steady_clock::now() >= next_report) {
      const auto counters = bridge_->counters();
      if (counters.decode_errors != last_decode_errors) {
        spdlog::warn("{} malformed frame(s) so far; last: {}", counters.decode_errors,
                     counters.last_decode_error);
        last_decode_errors = counters.decode_errors;
      }
      next_report += 10s;
    }
    std::this_thread::sleep_for(50ms);
  }
}

}  // namespace teejet::gateway
