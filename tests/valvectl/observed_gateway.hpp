#pragma once

// The real gateway runtime with simulated valves (teejet-gateway --can sim:N, in the test's
// process), plus what the valvectl tests observe around it: the commands that reached it, seen
// through the command statuses it publishes, and a valve that announces itself once and falls
// silent.

#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "support/dds_peer.hpp"
#include "teejet/can/virtual_bus.hpp"
#include "teejet/dds/gateway_publisher.hpp"
#include "teejet/gateway/gateway.hpp"

namespace teejet::testing {

struct ObservedGatewayOptions {
  int domain = 0;
  std::string name = "observed-gateway";
  int valves = 1;  // TJV000001.., dps 90, closed 0, opened 90, 12.0 V, 25 °C
};

class ObservedGateway : eprosima::fastdds::dds::DataReaderListener {
 public:
  explicit ObservedGateway(const ObservedGatewayOptions& options);  // throws when it cannot start
  ~ObservedGateway() override;
  ObservedGateway(const ObservedGateway&) = delete;
  ObservedGateway& operator=(const ObservedGateway&) = delete;

  // Sends one I'm Here for `serial` from `address`, as a valve that then falls silent: the
  // gateway shows it online at once and offline after its offline timeout.
  void announce_silent_valve(std::uint32_t serial, std::uint8_t address);

  const bridge::Bridge& bridge() const { return gateway_->bridge(); }
  sim::Simulator& simulator() { return *gateway_->simulator(); }
  const std::string& name() const { return name_; }

  // The commands the gateway accepted or rejected, in order (one per command id). Commands for
  // serials it does not know leave no status: bridge().counters().commands_ignored counts them.
  std::vector<CommandStatus> commands() const;
  // The readers the gateway sends Sample's topic to (every client following it).
  template <class Sample>
  int readers_of() const {
    eprosima::fastdds::dds::PublicationMatchedStatus matched;
    gateway_->publisher().writer_of<Sample>()->get_publication_matched_status(matched);
    return matched.current_count;
  }
  // A simulated valve's exact position now.
  double position_of(std::uint32_t serial);

 private:
  void on_data_available(eprosima::fastdds::dds::DataReader* reader) override;

  const std::string name_;
  std::unique_ptr<gateway::Gateway> gateway_;
  // On the simulator's bus, for valves that announce themselves and fall silent.
  std::unique_ptr<can::VirtualBus> silent_bus_;
  std::unique_ptr<DdsPeer> observer_;

  mutable std::mutex mutex_;
  std::vector<CommandStatus> commands_;
};

}  // namespace teejet::testing
