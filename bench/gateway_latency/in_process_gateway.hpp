#pragma once

// A gateway with an embedded simulator, in this process, for latency under load on a host
// without CAN (tests/netns/isolated): N simulated valves and the bench valve share one virtual
// bus. DDS still goes between participants through the profile's transports: intraprocess
// delivery is switched off before any participant exists, so the ECU here is served as one in
// another process would be.

#include <memory>
#include <string>

#include "options.hpp"
#include "teejet/can/bus.hpp"
#include "teejet/gateway/gateway.hpp"

namespace teejet::bench {

class InProcessGateway {
 public:
  // With --load-valves: switches intraprocess delivery off (so call it before this process has
  // any other participant), then starts options.load_valves simulated valves (addresses from
  // 0xD8 up; the bench valve takes 0xF7) and a gateway on options.load_config's schedule, on
  // options.domain. Without: nullptr. Fails saying why.
  static Result<std::unique_ptr<InProcessGateway>> start_if_asked(const Options& options);
  ~InProcessGateway();

  // A new endpoint on the gateway's bus: only frames matching `filters` arrive.
  std::unique_ptr<can::Bus> endpoint(std::vector<can::Filter> filters) const;

 private:
  InProcessGateway() = default;
  std::string bus_name_;
  std::unique_ptr<gateway::Gateway> gateway_;
};

}  // namespace teejet::bench
