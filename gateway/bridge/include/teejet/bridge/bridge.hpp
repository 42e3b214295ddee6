#pragma once

// The gateway's translation engine, free of DDS entities and threads of its own: CAN frames in,
// samples out through a Sink; commands in, frames out through a Bus, each command followed to a
// final CommandStatus. The runtime calls on_frame, on_command and tick from any thread.

#include <chrono>
#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "teejet/bridge/conversions.hpp"
#include "teejet/can/bus.hpp"
#include "teejet/directory/valve_directory.hpp"

namespace teejet::bridge {

// Requests (re)sent to a valve whenever it appears, readdresses or comes back online, using the
// protocol's automatic resend. The default keeps the bus under 1 % per valve at 250 kbit/s.
std::vector<codec::ToValveMessage> default_poll_schedule();

// Per-valve mechanics the protocol cannot report (no message sets or reads them).
struct ValveLimits {
  double closed_degrees = 0.0;
  double opened_degrees = 90.0;  // 360 = a full-turn valve
  bool full_turn() const { return opened_degrees >= 360.0; }
};

struct BridgeConfig {
  std::string gateway_name = "teejet-gateway";
  std::string can_interface;
  std::chrono::nanoseconds offline_after = std::chrono::seconds(3);
  std::vector<codec::ToValveMessage> poll = default_poll_schedule();
  double completion_tolerance_degrees = 1.0;
  std::chrono::nanoseconds reply_timeout = std::chrono::seconds(2);  // requests, baud rate
  std::chrono::nanoseconds move_margin = std::chrono::seconds(3);    // added to a move's ETA
  unsigned assumed_dps = 90;  // until the valve reports its own degrees per second
  bool allow_baud_change = false;
  std::optional<ValveLimits> default_limits;    // nullopt: limits unknown, targets not clamped
  std::map<std::uint32_t, ValveLimits> limits;  // per serial, overrides default_limits
};

// Where the bridge publishes. The DDS adapter implements it; tests record.
class Sink {
 public:
  virtual ~Sink() = default;
  virtual void presence(const ValvePresence& sample) = 0;
  virtual void telemetry(const TelemetrySample& sample) = 0;
  virtual void error_cleared(std::uint32_t serial, ErrorKind kind) = 0;
  virtual void command_status(const CommandStatus& status) = 0;
  virtual void gateway_status(const GatewayStatus& status) = 0;
};

// Counters beyond what the bus itself counts.
struct BridgeCounters {
  std::uint64_t decode_errors = 0;  // frames of this PGN that did not decode
  std::uint64_t unattributed = 0;   // telemetry from an address no online valve announced
  std::uint64_t commands_rejected = 0;
  std::uint64_t commands_ignored = 0;  // for serials this gateway has never seen
  std::string last_decode_error;
};

class Bridge {
 public:
  Bridge(BridgeConfig config, can::Bus& bus, Sink& sink);

  void on_frame(const can::TimedFrame& frame);

  // `commander` identifies the writer that sent the command (for the fail-safe); empty if
  // unknown. Commands for serials this gateway has not seen are ignored: another gateway may
  // own them.
  void on_command(const ValveCommand& command, Timestamp now, const std::string& commander = {});

  // Offline detection, command timeouts and the once-a-second gateway status.
  void tick(Timestamp now);

  // Sends Stop to every online valve; returns how many were sent. For shutdown.
  std::size_t stop_all(Timestamp now);

  // Fail-safe: a commander was lost; stop the valves it drove last. `commander` is a writer id
  // ("prefix|entity"), or a participant's GUID prefix, which stands for all of its writers.
  std::size_t stop_commanded_by(const std::string& commander, Timestamp now);

  bool owns(std::uint32_t serial) const;
  BridgeCounters counters() const;
  std::vector<directory::ValveRecord> valves() const;

 private:
  struct TrackedCommand {
    ValveCommand command;
    std::string commander;
    std::optional<Timestamp> deadline;          // none for a manual drive: it has no observable end
    std::optional<double> target_degrees;       // moves: where the valve should end up
    std::optional<std::uint8_t> awaited_reply;  // requests: the message id that answers
    bool done_at_deadline = false;              // Milliseconds to Run: complete when its time is up
    // A one-shot request replaces the valve's automatic resend of that value (the sheet: "until
    // changed"); this is the poll request that puts the gateway's schedule back afterwards.
    std::optional<codec::ToValveMessage> restores;
  };
  struct ValveState {
    std::optional<double> position;
    unsigned dps = 0;                      // 0: not reported yet
    std::optional<TrackedCommand> motion;  // the run command the valve is working on
    std::vector<TrackedCommand> requests;  // awaiting their replies
    std::set<ErrorKind> latched_errors;
    std::string commander;  // who last drove this valve
  };

  void handle_i_am_here(std::uint8_t address, const codec::IAmHere& message, Timestamp received);
  void handle_telemetry(std::uint32_t serial, const codec::FromValveMessage& message,
                        Timestamp received);
  void arm_polling(const directory::ValveRecord& valve);
  std::optional<codec::ToValveMessage> schedule_entry_replaced_by(
      const codec::ToValveMessage& request) const;
  void end_request(std::uint32_t serial, const TrackedCommand& request, CommandState state,
                   const std::string& reason, Timestamp now);
  void publish_presence(const directory::ValveRecord& valve);
  void publish_status(const ValveCommand& command, CommandState state, const std::string& reason,
                      Timestamp now);
  void reject(const ValveCommand& command, const std::string& reason, Timestamp now);
  // Ends the valve's running command, if any, with a final state.
  void end_motion(ValveState& valve, CommandState state, const std::string& reason, Timestamp now);
  // Sends Stop to an online valve and supersedes its running command; false if not sent.
  bool stop_valve(std::uint32_t serial, const std::string& reason, Timestamp now);
  void finish(const TrackedCommand& tracked, CommandState state, const std::string& reason,
              Timestamp now);
  void track(std::uint32_t serial, const codec::ToValveMessage& message,
             const ValveCommand& command, const std::string& commander, Timestamp now);
  std::optional<double> target_of(const codec::ToValveMessage& message, const ValveState& valve,
                                  const ValveLimits* limits) const;
  double travel(const codec::ToValveMessage& message, const ValveState& valve,
                const ValveLimits* limits) const;  // degrees the move covers, worst case
  const ValveLimits* limits_for(std::uint32_t serial) const;
  can::Status send(std::uint8_t address, const codec::ToValveMessage& message);
  void publish_gateway_status(Timestamp now);

  const BridgeConfig config_;
  can::Bus& bus_;
  Sink& sink_;

  mutable std::mutex mutex_;
  directory::ValveDirectory directory_;
  std::map<std::uint32_t, ValveState> valves_;
  BridgeCounters counters_;
  // The first status waits one I'm Here period, so that its valve count means something to a
  // client that trusts it as the size of the directory.
  std::optional<Timestamp> next_status_;
};

}  // namespace teejet::bridge
