#include "teejet/can/open_bus.hpp"

#include "teejet/can/socketcan_bus.hpp"
#include "teejet/can/virtual_bus.hpp"

namespace teejet::can {

std::unique_ptr<Bus> make_bus(std::string_view spec, std::vector<Filter> filters) {
  constexpr std::string_view kVirtualPrefix = "virtual:";
  if (spec.starts_with(kVirtualPrefix)) {
    spec.remove_prefix(kVirtualPrefix.size());
    return std::make_unique<VirtualBus>(std::string(spec),
                                        VirtualBusOptions{.filters = std::move(filters)});
  }
  return std::make_unique<SocketCanBus>(std::string(spec),
                                        SocketCanOptions{.filters = std::move(filters)});
}

}  // namespace teejet::can
