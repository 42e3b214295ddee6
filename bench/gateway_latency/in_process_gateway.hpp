#pragma once

// A gateway with an embedded simulator, in this process, for latency under load on a host
// without CAN (tests/netns/isolated): N simulated valves and the bench valve share one virtual
// bus. DDS still goes between participants through the profile's transports: intraprocess
// delivery is switched off before any participant exists, so the ECU here is served as one in
// another process would be.

#include <memory>
#include <string>

#include "gateway.hpp"
#include "teejet/can/bus.hpp"

namespace teejet::bench {

struct InProcessLoad {
  int valves = 31;          // simulated, from address 0xD8 up; the bench valve takes 0xF7
  std::string config_file;  // the gateway's YAML (its poll schedule), e.g. bench/full-poll.yaml
  int domain = 0;
  std::string profile;
};

// Call before the first participant of the process: afterwards Fast DDS has read the setting.
void switch_off_intraprocess_delivery();

class InProcessGateway {
 public:
  // Starts the simulator, the gateway and its DDS participant; fails saying why.
  static Result<std::unique_ptr<InProcessGateway>> start(const InProcessLoad& load);
  ~InProcessGateway();

  // A new endpoint on the gateway's bus, as a valve would be: only frames to `filters` arrive.
  std::unique_ptr<can::Bus> valve_endpoint(std::vector<can::Filter> filters) const;

 private:
  InProcessGateway() = default;
  std::string bus_name_;
  std::unique_ptr<gateway::Gateway> gateway_;
};

}  // namespace teejet::bench
