#pragma once

#include <memory>
#include <string_view>

#include "teejet/can/bus.hpp"

namespace teejet::can {

// Makes the bus a user names on a command line: "virtual:NAME" is an in-process virtual bus
// (see VirtualBus), anything else is a SocketCAN interface name ("can0", "vcan0"). The bus is
// not opened yet. Filters apply to either kind; wait_for_interface to a SocketCAN interface
// only (SocketCanOptions::wait_for_interface).
struct BusOptions {
  std::vector<Filter> filters;
  bool wait_for_interface = false;
};
std::unique_ptr<Bus> make_bus(std::string_view spec, BusOptions options);
std::unique_ptr<Bus> make_bus(std::string_view spec, std::vector<Filter> filters);

}  // namespace teejet::can
