#include "teejet/can/virtual_bus.hpp"

#include <algorithm>
#include <cerrno>
#include <map>

namespace teejet::can {

struct VirtualBus::Medium {
  std::mutex mutex;
  std::vector<VirtualBus*> endpoints;
  bool link_up = true;
  BusState state = BusState::kErrorActive;
  std::uint16_t tx_errors = 0;
  std::uint16_t rx_errors = 0;
};

// A medium lives as long as an endpoint refers to it; fault settings made while no endpoint is
// open are forgotten with it.
std::shared_ptr<VirtualBus::Medium> VirtualBus::medium_named(const std::string& name) {
  static std::mutex registry_mutex;
  static std::map<std::string, std::weak_ptr<Medium>, std::less<>> media;
  std::lock_guard lock(registry_mutex);
  auto& slot = media[name];
  auto medium = slot.lock();
  if (!medium) {
    medium = std::make_shared<Medium>();
    slot = medium;
  }
  return medium;
}

VirtualBus::VirtualBus(std::string bus_name, Options options)
    : name_(std::move(bus_name)), options_(std::move(options)) {}

VirtualBus::~VirtualBus() { close(); }

Status VirtualBus::open() {
  if (name_.empty()) return Error{ErrorCode::kInvalidValue, "a virtual bus needs a name"};
  auto medium = medium_named(name_);
  {
    std::lock_guard lock(medium->mutex);
    if (std::find(medium->endpoints.begin(), medium->endpoints.end(), this) ==
        medium->endpoints.end()) {
      medium->endpoints.push_back(this);
    }
  }
  std::lock_guard lock(mutex_);
  medium_ = std::move(medium);
  open_ = true;
  return {};
}

void VirtualBus::close() {
  std::shared_ptr<Medium> medium;
  {
    std::lock_guard lock(mutex_);
    if (!open_) return;
    open_ = false;
    medium = medium_;
  }
  {
    std::lock_guard lock(medium->mutex);
    std::erase(medium->endpoints, this);
  }
  arrived_.notify_all();
}

Status VirtualBus::send(const codec::CanFrame& frame) {
  std::shared_ptr<Medium> medium;
  {
    std::lock_guard lock(mutex_);
    if (!open_) return Error{ErrorCode::kUnavailable, name_ + ": bus is not open"};
    medium = medium_;
  }
  std::lock_guard medium_lock(medium->mutex);
  if (!medium->link_up) {
    std::lock_guard lock(mutex_);
    ++statistics_.tx_failed;
    return Error{ErrorCode::kUnavailable, name_ + ": link is down", ENETDOWN};
  }
  for (VirtualBus* endpoint : medium->endpoints) {
    if (endpoint != this) endpoint->deliver(frame);
  }
  std::lock_guard lock(mutex_);
  ++statistics_.frames_out;
  return {};
}

void VirtualBus::inject(const codec::CanFrame& frame) { deliver(frame); }

void VirtualBus::deliver(const codec::CanFrame& frame) {
  const auto& filters = options_.filters;
  if (!filters.empty() && std::none_of(filters.begin(), filters.end(),
                                       [&](const Filter& f) { return f.matches(frame); })) {
    return;
  }
  {
    std::lock_guard lock(mutex_);
    if (!open_) return;
    if (queue_.size() >= options_.queue_limit) {
      ++statistics_.rx_dropped;
      return;
    }
    queue_.push_back({frame, options_.clock->wall()});
  }
  arrived_.notify_one();
}

std::optional<TimedFrame> VirtualBus::receive(std::chrono::milliseconds timeout) {
  std::unique_lock lock(mutex_);
  ++waiting_;
  arrived_.wait_for(lock, timeout, [&] { return !queue_.empty() || !open_; });
  --waiting_;
  if (queue_.empty() || !open_) return std::nullopt;
  TimedFrame frame = queue_.front();
  queue_.pop_front();
  ++statistics_.frames_in;
  return frame;
}

std::size_t VirtualBus::waiting_receivers() const {
  std::lock_guard lock(mutex_);
  return waiting_;
}

BusStatistics VirtualBus::statistics() const {
  BusStatistics out;
  std::shared_ptr<Medium> medium;
  {
    std::lock_guard lock(mutex_);
    out = statistics_;
    medium = medium_;
  }
  if (medium) {
    std::lock_guard lock(medium->mutex);
    out.state = medium->link_up ? medium->state : BusState::kDown;
    out.tx_errors = medium->tx_errors;
    out.rx_errors = medium->rx_errors;
  }
  return out;
}

void VirtualBus::set_link_up(const std::string& bus_name, bool up) {
  auto medium = medium_named(bus_name);
  std::lock_guard lock(medium->mutex);
  medium->link_up = up;
}

void VirtualBus::set_controller_state(const std::string& bus_name, BusState state,
                                      std::uint16_t tx_errors, std::uint16_t rx_errors) {
  auto medium = medium_named(bus_name);
  std::lock_guard lock(medium->mutex);
  medium->state = state;
  medium->tx_errors = tx_errors;
  medium->rx_errors = rx_errors;
}

}  // namespace teejet::can
