#include "fake_gateway.hpp"

#include <spdlog/logger.h>
#include <unistd.h>

#include <stdexcept>

#include "teejet/codec/codec.hpp"

namespace teejet::testing {
namespace {

using namespace std::chrono_literals;

bridge::Timestamp wall_clock_now() {
  return std::chrono::duration_cast<bridge::Timestamp>(
      std::chrono::system_clock::now().time_since_epoch());
}

constexpr auto kTickPeriod = 50ms;

}  // namespace

FakeGateway::FakeGateway(const FakeGatewayOptions& options)
    : name_(options.name),
      bus_name_("valvectl-e2e-" + std::to_string(::getpid())),
      bus_(bus_name_, can::VirtualBusOptions{.filters = can::controller_side_filters()}),
      silent_bus_(bus_name_,
                  can::VirtualBusOptions{.filters = can::valve_side_filters(), .queue_limit = 16}),
      simulator_(std::make_unique<can::VirtualBus>(
                     bus_name_, can::VirtualBusOptions{.filters = can::valve_side_filters()}),
                 sim::SimulatorOptions{
                     .valves = options.valves,
                     // A logger without sinks: the test output stays readable.
                     .logger = std::make_shared<spdlog::logger>("valve-sim"),
                 }),
      participant_({.domain = options.domain, .name = options.name}),
      publisher_(participant_),
      bridge_(bridge::BridgeConfig{.gateway_name = options.name, .can_interface = bus_name_}, bus_,
              publisher_),
      subscription_(
          participant_,
          [this](const ValveCommand& command, const std::string& writer) {
            bridge_.on_command(command, wall_clock_now(), writer);
            std::lock_guard lock(mutex_);
            commands_.push_back(command);
          },
          // As teejet-gateway does: a commander that vanishes has its valves stopped.
          [this](const std::string& writer) {
            bridge_.stop_commanded_by(writer, wall_clock_now());
          }) {
  if (const auto opened = bus_.open(); !opened) throw std::runtime_error(opened.reason());
  if (const auto opened = silent_bus_.open(); !opened) throw std::runtime_error(opened.reason());
  if (const auto started = simulator_.start(); !started) {
    throw std::runtime_error(started.reason());
  }
  driver_ = std::thread([this] { drive(); });
}

FakeGateway::~FakeGateway() {
  stopping_ = true;
  driver_.join();
  // DDS first, while the bridge and this object's members still exist for late callbacks.
  participant_.get()->delete_contained_entities();
  simulator_.stop();
}

// The gateway's run loop in one thread: frames to the bridge as they come, a tick every 50 ms.
void FakeGateway::drive() {
  auto next_tick = std::chrono::steady_clock::now();
  while (!stopping_) {
    if (auto frame = bus_.receive(10ms)) bridge_.on_frame(*frame);
    if (std::chrono::steady_clock::now() >= next_tick) {
      bridge_.tick(wall_clock_now());
      next_tick += kTickPeriod;
    }
  }
}

void FakeGateway::announce_silent_valve(std::uint32_t serial, std::uint8_t address) {
  const auto frame = codec::encode(address, codec::FromValveMessage{codec::IAmHere{0, serial}});
  if (!frame) throw std::runtime_error(frame.error().reason);
  if (const auto sent = silent_bus_.send(*frame); !sent) throw std::runtime_error(sent.reason());
}

std::vector<ValveCommand> FakeGateway::commands() const {
  std::lock_guard lock(mutex_);
  return commands_;
}

double FakeGateway::position_of(std::uint32_t serial) const {
  const auto now = simulator_.clock()->now();
  return simulator_.inspect([&](const sim::ValveBank& bank) {
    const auto* valve = bank.valve_with_serial(serial);
    return valve == nullptr ? -1.0 : valve->position(now);
  });
}

}  // namespace teejet::testing
