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
  std::uint64_t outages = 0;  // link downs and bus-offs
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
  auto sent = send_batch(std::span(&frame, 1));
  return sent.status;
}

VirtualBus::BatchSent VirtualBus::send_batch(std::span<const codec::CanFrame> frames) {
  std::shared_ptr<Medium> medium;
  {
    std::lock_guard lock(mutex_);
    if (!open_) return {0, Error{ErrorCode::kUnavailable, name_ + ": bus is not open"}};
    medium = medium_;
  }
  std::lock_guard medium_lock(medium->mutex);
  if (!medium->link_up) {
    std::lock_guard lock(mutex_);
    ++statistics_.tx_failed;
    return {0, Error{ErrorCode::kUnavailable, name_ + ": link is down", ENETDOWN}};
  }
  for (VirtualBus* endpoint : medium->endpoints) {
    if (endpoint != this) endpoint->deliver(frames);
  }
  std::lock_guard lock(mutex_);
  statistics_.frames_out += frames.size();
  return {frames.size(), {}};
}

void VirtualBus::inject(const codec::CanFrame& frame) { deliver(std::span(&frame, 1)); }

void VirtualBus::deliver(std::span<const codec::CanFrame> frames) {
  const auto& filters = options_.filters;
  const auto accepted = [&](const codec::CanFrame& frame) {
    return filters.empty() || std::any_of(filters.begin(), filters.end(),
                                          [&](const Filter& f) { return f.matches(frame); });
  };
  bool queued = false;
  {
    std::lock_guard lock(mutex_);
    if (!open_) return;
    const Timestamp now = options_.clock->wall();
    for (const auto& frame : frames) {
      if (!accepted(frame)) continue;
      if (queue_.size() >= options_.queue_limit) {
        ++statistics_.rx_dropped;
        continue;
      }
      queue_.push_back({frame, now});
      queued = true;
    }
  }
  if (queued) arrived_.notify_one();
}

bool VirtualBus::wait_for_frames(std::unique_lock<std::mutex>& lock,
                                 std::chrono::milliseconds timeout) {
  ++waiting_;
  arrived_.wait_for(lock, timeout, [&] { return !queue_.empty() || !open_; });
  --waiting_;
  return open_ && !queue_.empty();
}

std::optional<TimedFrame> VirtualBus::receive(std::chrono::milliseconds timeout) {
  std::unique_lock lock(mutex_);
  if (!wait_for_frames(lock, timeout)) return std::nullopt;
  TimedFrame frame = queue_.front();
  queue_.pop_front();
  ++statistics_.frames_in;
  return frame;
}

std::size_t VirtualBus::receive_batch(std::vector<TimedFrame>& out, std::size_t max,
                                      std::chrono::milliseconds timeout) {
  if (max == 0) return 0;
  std::unique_lock lock(mutex_);
  if (!wait_for_frames(lock, timeout)) return 0;
  const std::size_t taken = std::min(max, queue_.size());
  const auto end = queue_.begin() + static_cast<std::ptrdiff_t>(taken);
  out.insert(out.end(), queue_.begin(), end);
  queue_.erase(queue_.begin(), end);
  statistics_.frames_in += taken;
  return taken;
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
    out.outages = medium->outages;
    out.tx_errors = medium->tx_errors;
    out.rx_errors = medium->rx_errors;
  }
  return out;
}

void VirtualBus::set_link_up(const std::string& bus_name, bool up) {
  auto medium = medium_named(bus_name);
  std::lock_guard lock(medium->mutex);
  if (medium->link_up && !up) ++medium->outages;
  medium->link_up = up;
}

void VirtualBus::set_controller_state(const std::string& bus_name, BusState state,
                                      std::uint16_t tx_errors, std::uint16_t rx_errors) {
  auto medium = medium_named(bus_name);
  std::lock_guard lock(medium->mutex);
  if (state == BusState::kBusOff && medium->state != BusState::kBusOff) ++medium->outages;
  medium->state = state;
  medium->tx_errors = tx_errors;
  medium->rx_errors = rx_errors;
}

}  // namespace teejet::can
