#include "teejet/sim/isobus_neighbour.hpp"

#include <variant>

namespace teejet::sim {

IsobusNeighbour::IsobusNeighbour(std::unique_ptr<can::Bus> bus, isobus::Name name,
                                 std::uint8_t address)
    : bus_(std::move(bus)), name_(name), address_(address) {}

IsobusNeighbour::~IsobusNeighbour() { stop(); }

Status IsobusNeighbour::start() {
  if (auto opened = bus_->open(); !opened) return opened;
  thread_ = std::jthread([this](const std::stop_token& stop) { run(stop); });
  return {};
}

void IsobusNeighbour::stop() {
  if (!thread_.joinable()) return;
  thread_.request_stop();
  bus_->close();
  thread_.join();
}

Status IsobusNeighbour::claim() {
  {
    std::lock_guard lock(mutex_);
    holds_ = true;
  }
  return bus_->send(isobus::address_claimed(name_, address_));
}

Status IsobusNeighbour::give_up() {
  {
    std::lock_guard lock(mutex_);
    holds_ = false;
  }
  return bus_->send(isobus::cannot_claim_address(name_));
}

Status IsobusNeighbour::send(const codec::CanFrame& frame) { return bus_->send(frame); }

bool IsobusNeighbour::wait_for(const std::function<bool(const codec::CanFrame&)>& matches,
                               std::chrono::milliseconds timeout) const {
  std::unique_lock lock(mutex_);
  std::size_t looked = 0;
  return arrived_.wait_for(lock, timeout, [&] {
    for (; looked < heard_.size(); ++looked) {
      if (matches(heard_[looked].frame)) return true;
    }
    return false;
  });
}

void IsobusNeighbour::run(const std::stop_token& stop) {
  while (!stop.stop_requested()) {
    const auto received = bus_->receive(std::chrono::milliseconds(50));
    if (!received) continue;
    std::optional<codec::CanFrame> answer;
    {
      std::lock_guard lock(mutex_);
      heard_.push_back(*received);
      const auto meaning = isobus::classify(received->frame);
      if (const auto* request = std::get_if<isobus::ClaimRequest>(&meaning)) {
        if (request->destination == isobus::kGlobalAddress || request->destination == address_) {
          answer = holds_ ? isobus::address_claimed(name_, address_)
                          : isobus::cannot_claim_address(name_);
        }
      } else if (const auto* claimed = std::get_if<isobus::AddressClaim>(&meaning)) {
        if (holds_ && claimed->source == address_) {
          if (isobus::wins_over(name_, claimed->name)) {
            answer = isobus::address_claimed(name_, address_);  // defend it
          } else {
            holds_ = false;
            answer = isobus::cannot_claim_address(name_);
          }
        }
      }
    }
    arrived_.notify_all();
    if (answer) (void)bus_->send(*answer);
  }
}

}  // namespace teejet::sim
