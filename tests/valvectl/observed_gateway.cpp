#include "observed_gateway.hpp"

#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <stdexcept>

#include "teejet/codec/codec.hpp"
#include "teejet/dds/gateway_publisher.hpp"
#include "teejet/dds/topics.hpp"
#include "teejet/valvePubSubTypes.h"

namespace teejet::testing {
namespace {

gateway::GatewayConfig config_for(const ObservedGatewayOptions& options) {
  gateway::GatewayConfig config;
  config.can = "sim:" + std::to_string(options.valves);
  config.domain = options.domain;
  config.bridge.gateway_name = options.name;
  return config;
}

template <class T>
T must(Result<T> result) {
  if (!result) throw std::runtime_error(result.error().reason);
  return std::move(result).value();
}

}  // namespace

ObservedGateway::ObservedGateway(const ObservedGatewayOptions& options) : name_(options.name) {
  const auto config = config_for(options);
  gateway_ = std::make_unique<gateway::Gateway>(config, must(gateway::make_bus_backend(config)));
  observer_ = std::make_unique<DdsPeer>(options.domain, "command-observer");
  // Subscribed before the gateway runs, so that no status of a test's command is missed.
  if (observer_->reader<CommandStatus>(dds::topics::status_reader_qos(), this) == nullptr) {
    throw std::runtime_error("cannot subscribe to command statuses");
  }
  if (const auto started = gateway_->start(); !started) {
    throw std::runtime_error(started.error().reason);
  }
  silent_bus_ = std::make_unique<can::VirtualBus>(
      simulator().bus_name(),
      can::VirtualBusOptions{.filters = can::valve_side_filters(), .queue_limit = 16});
  if (const auto opened = silent_bus_->open(); !opened) {
    throw std::runtime_error(opened.error().reason);
  }
}

ObservedGateway::~ObservedGateway() {
  gateway_->stop();
  observer_.reset();  // its reader goes before this listener does
}

void ObservedGateway::announce_silent_valve(std::uint32_t serial, std::uint8_t address) {
  const auto frame = codec::encode(address, codec::FromValveMessage{codec::IAmHere{0, serial}});
  if (!frame) throw std::runtime_error(frame.error().reason);
  if (const auto sent = silent_bus_->send(*frame); !sent) {
    throw std::runtime_error(sent.error().reason);
  }
}

void ObservedGateway::on_data_available(eprosima::fastdds::dds::DataReader* reader) {
  CommandStatus status;
  eprosima::fastdds::dds::SampleInfo info;
  while (reader->take_next_sample(&status, &info) ==
         eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK) {
    // ACCEPTED or REJECTED comes first for every command that reached the gateway.
    const bool first = status.state() == COMMAND_ACCEPTED || status.state() == COMMAND_REJECTED;
    if (!info.valid_data || !first) continue;
    std::lock_guard lock(mutex_);
    commands_.push_back(status);
  }
}

std::vector<CommandStatus> ObservedGateway::commands() const {
  std::lock_guard lock(mutex_);
  return commands_;
}

double ObservedGateway::position_of(std::uint32_t serial) {
  auto& sim = simulator();
  const auto now = sim.clock()->steady();
  return sim.inspect([&](const sim::ValveBank& bank) {
    const auto* valve = bank.valve_with_serial(serial);
    return valve == nullptr ? -1.0 : valve->position(now);
  });
}

}  // namespace teejet::testing
