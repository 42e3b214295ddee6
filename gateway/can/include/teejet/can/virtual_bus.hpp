#pragma once

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <memory>
#include <mutex>

#include "teejet/can/bus.hpp"

namespace teejet::can {

// One endpoint on a named in-process bus. Every endpoint opened with the same name shares the
// medium: a frame sent by one is delivered to every other endpoint whose filters accept it, as
// SocketCAN delivers to other sockets but not back to the sender. No root, no kernel, no vcan:
// this is the bus of unit tests, the embedded simulator and the demo.
struct VirtualBusOptions {
  std::vector<Filter> filters;  // empty: receive everything
  std::shared_ptr<const Clock> clock = system_clock();
  std::size_t queue_limit = 4096;  // frames beyond this are dropped and counted, like the kernel
};

class VirtualBus final : public Bus {
 public:
  using Options = VirtualBusOptions;

  explicit VirtualBus(std::string bus_name, Options options = {});
  ~VirtualBus() override;
  VirtualBus(const VirtualBus&) = delete;
  VirtualBus& operator=(const VirtualBus&) = delete;

  const std::string& name() const override { return name_; }
  Status open() override;
  void close() override;
  Status send(const codec::CanFrame& frame) override;
  std::optional<TimedFrame> receive(std::chrono::milliseconds timeout) override;
  std::size_t receive_batch(std::vector<TimedFrame>& out, std::size_t max,
                            std::chrono::milliseconds timeout) override;
  BatchSent send_batch(std::span<const codec::CanFrame> frames) override;
  BusStatistics statistics() const override;

  // Delivers a frame to this endpoint only, as if it had come from the bus (filters apply).
  void inject(const codec::CanFrame& frame);

  // For tests and diagnostics: how many threads are blocked in receive() on this endpoint now,
  // waiting for a frame or close(). Once it counts a thread, a frame sent or a close() from then
  // on reaches that thread while it waits: tests act only then, instead of sleeping.
  std::size_t waiting_receivers() const;

  // Fault injection for every endpoint of a named bus: a link that is down refuses sends and
  // reports BusState::kDown; the controller state and error counters show in statistics().
  static void set_link_up(const std::string& bus_name, bool up);
  static void set_controller_state(const std::string& bus_name, BusState state,
                                   std::uint16_t tx_errors, std::uint16_t rx_errors);

 private:
  struct Medium;
  static std::shared_ptr<Medium> medium_named(const std::string& name);
  // Queues the frames this endpoint's filters accept, under one lock, with one wake-up.
  void deliver(std::span<const codec::CanFrame> frames);
  // Waits (counted in waiting_receivers()) until a frame is queued, the bus closes or `timeout`
  // passes; true when a frame is there to take. `lock` holds mutex_.
  bool wait_for_frames(std::unique_lock<std::mutex>& lock, std::chrono::milliseconds timeout);

  const std::string name_;
  const Options options_;
  std::shared_ptr<Medium> medium_;

  mutable std::mutex mutex_;
  std::condition_variable arrived_;
  std::deque<TimedFrame> queue_;
  BusStatistics statistics_;
  std::size_t waiting_ = 0;  // threads inside receive()'s wait
  bool open_ = false;
};

}  // namespace teejet::can
