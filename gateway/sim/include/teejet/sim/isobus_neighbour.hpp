#pragma once

// Another ECU on a shared ISOBUS, for tests and demos without a kernel: it claims an address
// with its NAME, answers Requests for Address Claimed (to everyone and to its address), gives
// its address up to a NAME of higher priority, and can send any frame of its own.
// A contender for the gateway's 0xD5 is a neighbour at 0xD5. Runs one thread on its own bus
// endpoint (a VirtualBus of the gateway's medium, or a SocketCAN interface) and records every
// frame it hears.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "teejet/can/bus.hpp"
#include "teejet/isobus/name.hpp"

namespace teejet::sim {

class IsobusNeighbour {
 public:
  // `bus` is opened by start(); it should hear everything (no filters).
  IsobusNeighbour(std::unique_ptr<can::Bus> bus, isobus::Name name, std::uint8_t address);
  ~IsobusNeighbour();  // stop()
  IsobusNeighbour(const IsobusNeighbour&) = delete;
  IsobusNeighbour& operator=(const IsobusNeighbour&) = delete;

  // Opens the bus and starts answering; claim() is separate, so that a test picks the moment.
  Status start();
  void stop();

  Status claim();    // Address Claimed from its address
  Status give_up();  // Cannot Claim Address: it leaves its address (and defends it no more)
  Status send(const codec::CanFrame& frame);
  // Waits up to `timeout` for a frame it heard (since start) that `matches`.
  bool wait_for(const std::function<bool(const codec::CanFrame&)>& matches,
                std::chrono::milliseconds timeout) const;

 private:
  void run(const std::stop_token& stop);

  std::unique_ptr<can::Bus> bus_;
  const isobus::Name name_;
  const std::uint8_t address_;
  mutable std::mutex mutex_;
  mutable std::condition_variable arrived_;
  std::vector<can::TimedFrame> heard_;
  bool holds_ = false;
  std::jthread thread_;
};

}  // namespace teejet::sim
