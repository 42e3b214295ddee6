#include "teejet/can/open_bus.hpp"

#include "teejet/can/socketcan_bus.hpp"
#include "teejet/can/virtual_bus.hpp"

namespace teejet::can {

std::unique_ptr<Bus> make_bus(std::string_view spec, BusOptions options) {
  constexpr std::string_view kVirtualPrefix = "virtual:";
  if (spec.starts_with(kVirtualPrefix)) {
    spec.remove_prefix(kVirtualPrefix.size());
    return std::make_unique<VirtualBus>(std::string(spec),
                                        VirtualBusOptions{.filters = std::move(options.filters)});
  }
  return std::make_unique<SocketCanBus>(
      std::string(spec), SocketCanOptions{.filters = std::move(options.filters),
                                          .wait_for_interface = options.wait_for_interface});
}

std::unique_ptr<Bus> make_bus(std::string_view spec, std::vector<Filter> filters) {
  return make_bus(spec, BusOptions{.filters = std::move(filters)});
}

}  // namespace teejet::can
