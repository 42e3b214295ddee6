#include "in_process_gateway.hpp"

#include <fastrtps/attributes/LibrarySettingsAttributes.h>
#include <fastrtps/xmlparser/XMLProfileManager.h>
#include <unistd.h>

#include "teejet/can/virtual_bus.hpp"
#include "teejet/sim/simulator.hpp"

namespace teejet::bench {

namespace {

// Fast DDS reads the setting when a participant is created: before the first one.
void switch_off_intraprocess_delivery() {
  eprosima::fastrtps::LibrarySettingsAttributes settings;
  settings.intraprocess_delivery = eprosima::fastrtps::INTRAPROCESS_OFF;
  eprosima::fastrtps::xmlparser::XMLProfileManager::library_settings(settings);
}

}  // namespace

Result<std::unique_ptr<InProcessGateway>> InProcessGateway::start_if_asked(const Options& options) {
  if (options.load_valves <= 0) return std::unique_ptr<InProcessGateway>{};
  switch_off_intraprocess_delivery();
  gateway::GatewayConfig config;
  if (!options.load_config.empty()) {
    auto read = gateway::load_config_file(options.load_config, config);
    if (!read) return read.error();
    config = std::move(*read);
  }
  config.domain = options.domain;
  config.profile_file = options.profile;
  config.bridge.gateway_name = "latency-bench-gateway";
  std::unique_ptr<InProcessGateway> self(new InProcessGateway);
  self->bus_name_ = "latency-bench-" + std::to_string(::getpid());
  config.can = "virtual:" + self->bus_name_;

  std::vector<sim::ValveConfig> valves;
  for (int i = 0; i < options.load_valves; ++i) {
    sim::ValveConfig valve;
    valve.serial = 1 + static_cast<std::uint32_t>(i);
    valves.push_back(valve);
  }
  gateway::BusBackend backend;
  backend.simulator = std::make_unique<sim::Simulator>(
      std::make_unique<can::VirtualBus>(self->bus_name_,
                                        can::VirtualBusOptions{can::valve_side_filters()}),
      sim::SimulatorOptions{.valves = std::move(valves)});
  backend.bus = self->endpoint(can::controller_side_filters());
  self->gateway_ = std::make_unique<gateway::Gateway>(config, std::move(backend));
  if (auto started = self->gateway_->start(); !started) return started.error();
  return self;
}

InProcessGateway::~InProcessGateway() = default;

std::unique_ptr<can::Bus> InProcessGateway::endpoint(std::vector<can::Filter> filters) const {
  return std::make_unique<can::VirtualBus>(bus_name_,
                                           can::VirtualBusOptions{.filters = std::move(filters)});
}

}  // namespace teejet::bench
