#pragma once

// One TeeJet CAN valve as a pure state machine: no threads, no I/O, no clock of its own. Time is
// passed in; motion is computed in closed form from the start of the running command, so the
// position at any instant is exact whatever the call pattern. See docs/valve-sim.md.

#include <chrono>
#include <cstdint>
#include <map>
#include <optional>
#include <string_view>
#include <vector>

#include "teejet/codec/messages.hpp"
#include "teejet/core/time.hpp"
#include "teejet/sim/valve_config.hpp"

namespace teejet::sim {

inline constexpr Duration kIAmHerePeriod = std::chrono::seconds(1);
inline constexpr Duration kErrorRepeatPeriod = std::chrono::seconds(1);
inline constexpr Duration kTenthOfSecond = std::chrono::milliseconds(100);

class SimulatedValve {
 public:
  // Throws std::invalid_argument when validate(config) fails.
  explicit SimulatedValve(ValveConfig config);

  // Acts on a controller message received at `now` and returns the immediate replies (none
  // for the motion commands, Stop and Clear Errors).
  std::vector<codec::FromValveMessage> handle(const codec::ToValveMessage& message, SteadyTime now);

  // Brings the valve to `now` and returns what falls due by then: I'm Here, latched errors,
  // automatic resends; each at most once per call, in order of their due times. Periods keep
  // their phase: a late call skips the missed instants instead of bursting.
  std::vector<codec::FromValveMessage> advance(SteadyTime now);

  // When advance() next has something to send; nullopt when nothing is scheduled.
  std::optional<SteadyTime> next_due() const;

  // I'm Here at `first`, then once a second. Called when the valve captures an address.
  void schedule_i_am_here(SteadyTime first);
  std::optional<SteadyTime> next_i_am_here() const { return next_i_am_here_; }

  // Latches the error: sent by the next advance() at or after `now`, then once a second until
  // Clear Errors. Injecting a kind again replaces its values. Throws std::invalid_argument when
  // validate(error) fails.
  void inject_error(const InjectedError& error, SteadyTime now);

  // Power gone at `now`: the motor stops where the valve got to (run time counted up to then),
  // and until power_on() the valve sends nothing and acts on nothing. What lives in RAM is lost:
  // automatic resends, latched errors, the I'm Here schedule, the direction of the last run
  // command, the "ran at 100 %" mark. What the firmware keeps in non-volatile memory stays: run
  // time, cycle counts, the stored bit rate. The position is where the shaft physically is.
  void power_off(SteadyTime now);
  // Power back: the valve runs its application code, or with `boot_mode` its boot code, which
  // announces itself (I'm Here byte 7 = 1) and answers Request Version and Baud Rate but does not
  // run the application: motion commands and telemetry requests are ignored (nothing moves,
  // nothing is counted, nothing is answered). The bank schedules its I'm Here.
  void power_on(bool boot_mode = false);
  bool powered() const { return powered_; }
  bool boot_mode() const { return boot_mode_; }

  // ---- Observation (for tests, logs and embedders); `now` must not precede earlier calls --
  const ValveConfig& config() const { return config_; }
  std::uint32_t serial() const { return config_.serial; }
  double position(SteadyTime now) const;  // degrees, not rounded
  bool running(SteadyTime now) const;
  unsigned speed_percent(SteadyTime now) const;              // 0 when stopped
  codec::Direction direction() const { return direction_; }  // of the last run command
  double run_time_seconds(SteadyTime now) const;             // not rounded
  std::uint32_t cycle_count() const { return cycle_count_; }
  std::uint32_t bit_rate() const { return bit_rate_; }
  bool error_latched(std::string_view kind) const;  // codec::error_kinds()'s words
  // Resend period of a request with automatic resend; nullopt when not resending.
  std::optional<Duration> resend_period(std::uint8_t request_id) const;

  // The message a request is answered with, as at `now`: the reply the codec's table names for
  // it, with this valve's values; nullopt for a message nothing answers.
  std::optional<codec::FromValveMessage> reply_to(const codec::ToValveMessage& request,
                                                  SteadyTime now) const;

 private:
  // A run command in progress. The valve turns from start_position at `rate` degrees per second
  // in direction `sign` for `duration` (nullopt: until told otherwise, a full-turn Manual run)
  // over `travel` degrees, and then rests at end_position.
  struct Motion {
    SteadyTime start{};
    double start_position = 0.0;
    int sign = 1;  // +1 opening (degrees increase), -1 closing
    double rate = 0.0;
    double travel = 0.0;
    std::optional<Duration> duration;
    double end_position = 0.0;
    unsigned speed_percent = 0;
  };
  struct Periodic {
    codec::ToValveMessage request;
    Duration period{};
    SteadyTime next{};
  };
  struct Latched {
    InjectedError error;
    SteadyTime next{};
  };

  double travelled(const Motion& motion, SteadyTime now) const;
  static Duration driven(const Motion& motion, SteadyTime now);
  Duration run_time(SteadyTime now) const;
  bool ran_at_full_speed(SteadyTime now) const;
  double normalized(double degrees) const;
  double distance_to_limit(codec::Direction direction) const;

  // Ends a motion that has finished by `now`.
  void settle(SteadyTime now);
  // Stops the running motion at `now`, keeping where it got to.
  void halt(SteadyTime now);
  // A run command: replaces the running one; speed 0 is Stop.
  void run(unsigned speed_percent, codec::Direction direction, double travel,
           std::optional<double> end_position, SteadyTime now);
  void run_target(const codec::TargetDegrees& command, SteadyTime now);
  void run_degrees(const codec::DegreesFromPosition& command, SteadyTime now);
  void run_manual(const codec::Manual& command, SteadyTime now);
  void run_milliseconds(const codec::MillisecondsToRun& command, SteadyTime now);
  // Set or Request CAN Baud Rate: a set changes the rate the valve reports (and keeps).
  void set_bit_rate(const codec::BaudRate& message);
  void request(const codec::ToValveMessage& request, SteadyTime now,
               std::vector<codec::FromValveMessage>& replies);
  // This valve's values in a reply, as at `now`; one per reply the simulator models.
  void report(codec::VersionInfo& reply, SteadyTime now) const;
  void report(codec::Position& reply, SteadyTime now) const;
  void report(codec::Temperature& reply, SteadyTime now) const;
  void report(codec::Voltage& reply, SteadyTime now) const;
  void report(codec::RunCurrent& reply, SteadyTime now) const;
  void report(codec::DegreesPerSecond& reply, SteadyTime now) const;
  void report(codec::SpeedDirection& reply, SteadyTime now) const;
  void report(codec::RunTime& reply, SteadyTime now) const;
  void report(codec::CycleCounts& reply, SteadyTime now) const;
  void report(codec::BaudRateReply& reply, SteadyTime now) const;

  ValveConfig config_;
  double position_ = 0.0;  // while stopped; normalized
  std::optional<Motion> motion_;
  codec::Direction direction_ = codec::Direction::kClose;
  Duration run_time_{0};  // of finished motions
  std::uint32_t cycle_count_ = 0;
  bool ran_at_full_speed_ = false;  // last running amps is 0 until then
  std::uint32_t bit_rate_ = codec::kBitRate250k;
  std::optional<SteadyTime> next_i_am_here_;
  std::map<std::uint8_t, Periodic> resends_;  // by request id
  std::map<std::uint8_t, Latched> errors_;    // by message id
  bool powered_ = true;
  bool boot_mode_ = false;
};

}  // namespace teejet::sim
