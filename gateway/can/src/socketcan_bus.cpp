// Placeholder until the SocketCAN implementation lands: fails visibly, never pretends.
#include "teejet/can/socketcan_bus.hpp"

namespace teejet::can {

struct SocketCanBus::State {};

SocketCanBus::SocketCanBus(std::string interface_name, SocketCanOptions options)
    : interface_(std::move(interface_name)), options_(std::move(options)) {}
SocketCanBus::~SocketCanBus() = default;
Status SocketCanBus::open() { return Status::failure(interface_ + ": SocketCAN not implemented"); }
void SocketCanBus::close() {}
Status SocketCanBus::send(const codec::CanFrame&) { return Status::failure("not open"); }
std::optional<TimedFrame> SocketCanBus::receive(std::chrono::milliseconds) { return std::nullopt; }
BusStatistics SocketCanBus::statistics() const { return {}; }

}  // namespace teejet::can
