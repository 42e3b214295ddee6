#pragma once

// The valve simulator at run time: a ValveBank on a can::Bus (SocketCAN or virtual), driven by
// one thread. Embeddable: the gateway's `--can sim:N`, the demo and the tests run it in-process
// on a VirtualBus; the valve-sim tool runs it on a SocketCAN interface.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <random>
#include <stop_token>
#include <string>
#include <thread>
#include <vector>

#include "teejet/can/bus.hpp"
#include "teejet/codec/codec.hpp"
#include "teejet/sim/valve_bank.hpp"

namespace spdlog {
class logger;
}

namespace teejet::sim {

// Valves going off and coming back at random, for soak runs: every `period` one valve that is on,
// picked by a generator seeded with `seed` (the same seed picks the same valves), is powered off
// and powered on again `off_for` later, in application mode. Both re-rank the bank, so other
// valves are readdressed. At most one valve is off this way at a time: a period that ends while
// it is still off is skipped. period 0: off.
struct ChurnOptions {
  Duration period{0};
  Duration off_for{0};
  std::uint64_t seed = 0;
};

struct SimulatorOptions {
  std::vector<ValveConfig> valves;  // powered up by start()
  std::vector<SerialError> errors;  // latched at power-up
  std::shared_ptr<const Clock> clock = system_clock();
  // Log every frame received and sent, candump -L text plus the decoded message, at info level.
  bool verbose = false;
  std::shared_ptr<spdlog::logger> logger;  // default: spdlog's default logger
  // The thread waits for a frame until the next due event, but never longer than this, so
  // that stop(), add_valve() and inject_error() (and a ManualClock moved by a test) are seen
  // within this time even on a quiet bus.
  std::chrono::milliseconds max_wait{50};
  // Periodic messages (resends, I'm Here, latched errors) go out on this timer tick, as valve
  // firmware sends them from a timer interrupt: each keeps its own period and phase, and is sent
  // at the first tick at or after it is due. 32 valves whose resends were armed at scattered
  // moments otherwise wake the simulator, and the gateway reading it, ~230 times a second at
  // any poll rate; with 10 ms, 100 at most. Replies to requests are never delayed. 0: no tick.
  std::chrono::milliseconds timer_tick{10};
  codec::EncodeOptions encode_options{};
  ChurnOptions churn{};
};

// How long the simulator thread waits for a frame when the next event is due at `next_due`
// (nullopt: nothing scheduled): until the first multiple of `tick` (on the steady clock) at or
// after the event, rounded up to a whole millisecond so that it never wakes before the event is
// due; 0 when it is due already; never longer than `max_wait`.
std::chrono::milliseconds receive_timeout(std::optional<SteadyTime> next_due, SteadyTime now,
                                          std::chrono::milliseconds max_wait,
                                          std::chrono::milliseconds tick = {});

class Simulator {
 public:
  // The bus should listen to controller traffic only (can::valve_side_filters()); frames of
  // other kinds are ignored anyway. It is opened by start() unless already open.
  Simulator(std::unique_ptr<can::Bus> bus, SimulatorOptions options);
  ~Simulator();  // stop()
  Simulator(const Simulator&) = delete;
  Simulator& operator=(const Simulator&) = delete;

  // Validates the valves and errors, opens the bus, powers the bank up and starts the thread.
  // Fails, saying why, without starting anything.
  Status start();
  // Stops the thread (within max_wait) and closes the bus. Idempotent; start() may follow.
  void stop();
  bool started() const { return thread_.joinable(); }

  // Thread-safe; take effect at the current clock time. The resulting frames are sent by the
  // simulator thread within max_wait.
  Status add_valve(const ValveConfig& config, std::vector<AddressChange>* changes = nullptr);
  Status inject_error(std::uint32_t serial, const InjectedError& error);
  // ValveBank::power_off, power_on and force_address at the current clock time, logged.
  Status power_off(std::uint32_t serial, std::vector<AddressChange>* changes = nullptr);
  Status power_on(std::uint32_t serial, bool boot_mode = false,
                  std::vector<AddressChange>* changes = nullptr);
  Status force_address(std::uint32_t serial, std::uint8_t address);
  // A valve replaced on the machine: `old_serial` goes silent (powered off), a valve with its
  // settings and `new_serial` powers up and claims an address. Refused, changing nothing, for an
  // unknown old serial or a new one already in the bank.
  Status replace_valve(std::uint32_t old_serial, std::uint32_t new_serial,
                       std::vector<AddressChange>* changes = nullptr);
  // How many valves the churn has powered off so far.
  std::uint64_t churn_count() const { return churn_count_.load(); }

  std::vector<Assignment> assignments() const;
  // Calls fn(const ValveBank&) with the bank locked: inspection for tests and embedders.
  template <class Fn>
  auto inspect(Fn&& fn) const {
    std::lock_guard lock(mutex_);
    return fn(static_cast<const ValveBank&>(bank_));
  }

  // Frames taken off the bus and acted on (decoded or not), frames sent, sends that failed.
  std::uint64_t frames_handled() const { return frames_handled_.load(); }
  std::uint64_t frames_sent() const { return frames_sent_.load(); }
  std::uint64_t send_failures() const { return send_failures_.load(); }
  can::BusStatistics bus_statistics() const { return bus_->statistics(); }
  const std::string& bus_name() const { return bus_->name(); }
  const std::shared_ptr<const Clock>& clock() const { return options_.clock; }

 private:
  void run(const std::stop_token& stop);
  std::chrono::milliseconds wait_budget() const;
  void on_frame(const can::TimedFrame& received, std::vector<Outgoing>& out);
  // Encodes and sends a burst as one batch: the receiver wakes once for it.
  void send(const std::vector<Outgoing>& outgoing);
  void log_frame(const char* way, Timestamp at, const codec::CanFrame& frame) const;
  void log_changes(const std::vector<AddressChange>& changes) const;
  // Powers the churn's valve off or back on when due; mutex_ held.
  void churn(SteadyTime now);
  std::optional<SteadyTime> next_churn_event() const;  // mutex_ held

  std::unique_ptr<can::Bus> bus_;
  SimulatorOptions options_;
  std::shared_ptr<spdlog::logger> logger_;

  mutable std::mutex mutex_;  // guards bank_
  ValveBank bank_;

  // The churn, guarded by mutex_.
  std::mt19937_64 churn_random_;
  std::optional<SteadyTime> next_churn_;  // the next valve goes off then
  std::optional<std::uint32_t> churned_;  // the valve it holds off
  SteadyTime churned_back_at_{};
  std::atomic<std::uint64_t> churn_count_{0};

  std::jthread thread_;
  std::atomic<std::uint64_t> frames_handled_{0};
  std::atomic<std::uint64_t> frames_sent_{0};
  std::atomic<std::uint64_t> send_failures_{0};
  bool last_send_failed_ = false;        // simulator thread only
  std::vector<codec::CanFrame> frames_;  // simulator thread only: the burst being sent
};

// One line describing a frame as `-v` logs it: candump -L text, then the decoded message,
// e.g. "(1700000000.000123) vcan0 18EFD5D8#020384FFFFFFFFFF  position degrees=90.0", or the
// reason it does not decode.
std::string describe_frame(Timestamp at, const std::string& interface_name,
                           const codec::CanFrame& frame);

}  // namespace teejet::sim
