#pragma once

// The gateway's translation engine, free of DDS entities and threads of its own: CAN frames in,
// samples out through a Sink; commands in, frames out through a Bus, each command followed to a
// final CommandStatus. Thread-safe: the runtime calls it from its bus and command threads.
// Deadlines run on the clock's steady time; published stamps are its wall time.

#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <vector>

#include "teejet/can/bus.hpp"
#include "teejet/core/time.hpp"
#include "teejet/dds/conversions.hpp"
#include "teejet/directory/valve_directory.hpp"
#include "teejet/isobus/address_claimer.hpp"
#include "teejet/layout/layout.hpp"

namespace teejet::bridge {

class CommandTracker;
class CommandRateLimiter;
struct Outcome;

// Requests (re)sent to a valve whenever it appears, readdresses or comes back online, using the
// protocol's automatic resend: version once; position every 100 ms; temperature, voltage,
// current, degrees per second, speed and direction every second; run time and cycle counts
// every 5 s. 16.4 frames/s per valve with its I'm Here: under 1 % of a 250 kbit/s bus.
std::vector<codec::ToValveMessage> default_poll_schedule();

struct BridgeConfig {
  std::string gateway_name = "teejet-gateway";
  std::string can_interface;
  Duration offline_after = std::chrono::seconds(3);
  std::vector<codec::ToValveMessage> poll = default_poll_schedule();
  double completion_tolerance_degrees = 1.0;
  Duration reply_timeout = std::chrono::seconds(2);  // requests, baud rate
  Duration move_margin = std::chrono::seconds(3);    // added to a move's ETA
  unsigned assumed_dps = 90;  // until the valve reports its own degrees per second
  bool allow_baud_change = false;
  // Commands sent to one valve per second, as a token bucket holding `command_burst_per_valve`;
  // over it a command is REJECTED, never sent (Stop has a bucket of its own). 0: no limit.
  double command_rate_per_valve = 100.0;
  unsigned command_burst_per_valve = 20;
  // A command for a serial this gateway has never seen: REJECTED saying so, or (false, for
  // several gateways on one domain) ignored, since another gateway may own the valve.
  bool reject_unknown_serials = false;
  // Where each valve sits and each place's mechanics, which the protocol cannot report: a
  // valve whose mechanics are unknown gets its targets as sent, and relative moves wrap. The
  // layout at start: LayoutChanges change the bridge's copy.
  layout::Layout layout;
  // ISO 11783-5 address claiming of 0xD5 on a bus shared with other ECUs (docs/isobus.md): the
  // bridge claims when it is made and after the bus recovers, and sends nothing else until it
  // may. Commands meanwhile wait (the wait is 250 ms), at most kMaxDeferredCommands of them.
  isobus::ClaimConfig isobus;
};

// The frames a bridge of `config` must hear, as kernel filters: its valves' frames to the
// controller and what address claiming needs (isobus::claiming_filters). Every other ECU's
// traffic on a shared bus stays in the kernel.
std::vector<can::Filter> frames_to_hear(const BridgeConfig& config);

// Where the bridge publishes. The DDS adapter implements it; tests record.
class Sink {
 public:
  virtual ~Sink() = default;
  virtual void presence(const ValvePresence& sample) = 0;
  virtual void location(const ValveLocation& sample) = 0;
  virtual void telemetry(const dds::TelemetrySample& sample) = 0;
  virtual void error_cleared(std::uint32_t serial, ErrorKind kind) = 0;
  virtual void command_status(const CommandStatus& status) = 0;
  virtual void layout_change_status(const LayoutChangeStatus& status) = 0;
  virtual void gateway_status(const GatewayStatus& status) = 0;
};

// What the other gateways on the domain say of their buses. The DDS adapter implements it from
// their GatewayStatus; the bridge refuses commands to a serial another gateway reports online.
class OtherGateways {
 public:
  virtual ~OtherGateways() = default;
  // The names of the other gateways that report `serial` online on their bus; empty for none.
  virtual std::vector<std::string> reporting_online(std::uint32_t serial) const = 0;
};

// Counters beyond what the bus itself counts.
struct BridgeCounters {
  std::uint64_t decode_errors = 0;  // frames of this PGN that did not decode
  std::uint64_t unattributed = 0;   // telemetry from an address no online valve announced
  std::uint64_t commands_rejected = 0;
  std::uint64_t commands_ignored = 0;       // for serials this gateway has never seen
  std::uint64_t commands_rate_limited = 0;  // of commands_rejected: over the per-valve limit
  std::uint64_t address_conflicts = 0;      // two valves found announcing at one address
  std::uint64_t neighbour_frames = 0;       // valve frames from an address an ECU claimed: ignored
  std::string last_decode_error;
};

class Bridge {
 public:
  // `others` (may be null: none heard) and `layout_store` (may be null: layout changes are
  // refused) must outlive the bridge.
  Bridge(BridgeConfig config, can::Bus& bus, Sink& sink,
         std::shared_ptr<const Clock> clock = system_clock(), const OtherGateways* others = nullptr,
         layout::LayoutStore* layout_store = nullptr);
  ~Bridge();
  Bridge(const Bridge&) = delete;
  Bridge& operator=(const Bridge&) = delete;

  void on_frame(const can::TimedFrame& frame) { on_frames(std::span(&frame, 1)); }
  // A burst from the bus, in order.
  void on_frames(std::span<const can::TimedFrame> frames);

  // `commander` identifies the writer that sent the command (for the fail-safe); empty if
  // unknown. Commands for serials this gateway has not seen are ignored (another gateway may
  // own them) unless reject_unknown_serials is set.
  void on_command(const ValveCommand& command, const std::string& commander = {});

  // A person's change of where a valve sits. One addressed to another gateway is ignored; any
  // other ends in one LayoutChangeStatus: REJECTED with the reason and nothing changed, or
  // APPLIED once the layout store saved it, its locations and presences published first.
  // Saving happens outside the lock that the bus reader takes. Changes run one at a time.
  void on_layout_change(const LayoutChange& change);
  layout::Layout current_layout() const;

  // Offline detection, command deadlines and the once-a-second gateway status: whatever is due.
  // For the thread that reads the bus, right after it took what the bus holds: a starved reader
  // must not call a valve offline whose I'm Here waits unread.
  void tick();

  // The same but offline detection: for any other thread (the one that takes commands).
  void tick_commands();

  // When tick() next has something to do (at most a second away: the gateway status), or
  // earlier, never later: a valve's I'm Here pushes its offline deadline back without a new
  // look at every valve, and a tick that finds nothing due takes that look.
  SteadyTime next_deadline() const;

  // When tick_commands() next has something to do.
  SteadyTime next_command_deadline() const;

  // Sends Stop to every online valve; returns how many were sent. For shutdown.
  std::size_t stop_all();

  // Shutdown, last: every command still followed (a move of a valve left running, a request
  // awaiting its reply) ends TIMED_OUT, saying the gateway stopped. Returns how many.
  std::size_t end_all_commands();

  // Fail-safe: a commander was lost; stop the valves it drove last. `commander` is a writer id
  // ("prefix|entity"), or a participant's GUID prefix, which stands for all of its writers.
  std::size_t stop_commanded_by(const std::string& commander);

  bool owns(std::uint32_t serial) const;
  isobus::ClaimState claim_state() const;
  std::vector<isobus::Neighbour> neighbours() const;
  BridgeCounters counters() const;
  std::vector<directory::ValveRecord> valves() const;

 private:
  void handle_frame(const can::TimedFrame& frame);  // mutex_ held
  // Sends what address claiming asks, logs its notices, and once the address is held sends
  // what waited for it. mutex_ held.
  void apply(const isobus::ClaimReaction& reaction);
  // Claims again when the bus came back (link up, bus-off restart, interface re-created),
  // however short the outage was (BusStatistics::outages). mutex_ held.
  void reclaim_after_recovery(SteadyTime now);
  void take_command(const ValveCommand& command, const std::string& commander);  // mutex_ held
  void handle_i_am_here(std::uint8_t address, const codec::IAmHere& message, Timestamp received,
                        SteadyTime now);
  void handle_telemetry(std::uint32_t serial, const codec::FromValveMessage& message,
                        Timestamp received);
  void arm_polling(const directory::ValveRecord& valve);
  void conflict_cleared(const directory::Change& change);
  struct ResentPoll;
  // The resent polls of an online valve whose replies stopped for longer than their quiet limit:
  // its resends are gone (a restart), or the request never reached it.
  std::vector<const ResentPoll*> quiet_polls(const directory::ValveRecord& valve,
                                             SteadyTime now) const;
  void poll_again(const directory::ValveRecord& valve, const std::vector<const ResentPoll*>& polls);
  // The valve's presence, and the state of the location it sits at (or, when it sits nowhere
  // and the layout has places, a log line naming it).
  void publish_presence(const directory::ValveRecord& valve);
  ValveLocation location_sample(const layout::Location& place, bool online) const;
  void publish_location(const layout::Location& place, bool online);  // when it changed
  void publish_status(const ValveCommand& command, CommandState state, const std::string& reason,
                      Timestamp stamp);
  void publish_layout_change(const LayoutChange& change, LayoutChangeState state,
                             std::string reason);
  // The layout `change` makes, or why it is refused. mutex_ held.
  Result<std::pair<layout::Layout, std::string>> changed_layout(const LayoutChange& change) const;
  // Publishes what moved between `before` and layout_: places, and the presence of the valves
  // that came or went. mutex_ held.
  void publish_layout_moves(const layout::Layout& before);
  std::string unreachable_reason(const directory::ValveRecord& valve) const;
  std::string rate_limit_reason(std::uint32_t serial) const;

  // on_command()'s checks, in its order. Each returns the reason the command is refused, or
  // nothing; translate() and encode_frame() also keep what they made for the checks after them.
  struct CommandUnderCheck;
  std::optional<std::string> refuse_unknown_serial(CommandUnderCheck& check);
  std::optional<std::string> refuse_without_address(CommandUnderCheck& check);
  std::optional<std::string> refuse_offline(CommandUnderCheck& check);
  std::optional<std::string> refuse_contested(CommandUnderCheck& check);
  std::optional<std::string> refuse_online_elsewhere(CommandUnderCheck& check);
  std::optional<std::string> refuse_baud_change(CommandUnderCheck& check);
  std::optional<std::string> translate(CommandUnderCheck& check);
  std::optional<std::string> refuse_in_boot_code(CommandUnderCheck& check);
  std::optional<std::string> encode_frame(CommandUnderCheck& check);
  std::optional<std::string> refuse_over_rate(CommandUnderCheck& check);  // takes a token
  std::optional<std::string> send_frame(CommandUnderCheck& check);
  // A command whose frame went out: ACCEPTED, latched errors cleared, followed by the tracker.
  void follow_sent(const CommandUnderCheck& check, const std::string& commander, Timestamp taken);

  // Publishes what the tracker ended and sends what it asked to restore.
  void settle(const Outcome& outcome);
  // Sends Stop to an online valve and ends its running command; false if not sent.
  bool stop_valve(std::uint32_t serial, const std::string& reason);
  // Refused while the address is not held; a Stop goes out during the wait after a claim too
  // (`even_while_claiming`), never once the address was given up.
  Status send(std::uint8_t address, const codec::ToValveMessage& message,
              bool even_while_claiming = false);
  void publish_gateway_status();
  SteadyTime earliest_deadline() const;          // mutex_ held; walks every valve
  SteadyTime earliest_command_deadline() const;  // mutex_ held: commands and the status
  // Ends the commands past their deadline into `outcome`, settles it, publishes the status when
  // due. mutex_ held.
  void keep_command_deadlines(SteadyTime now, Outcome& outcome);

  const BridgeConfig config_;
  can::Bus& bus_;
  Sink& sink_;
  const std::shared_ptr<const Clock> clock_;
  const OtherGateways* const others_;
  layout::LayoutStore* const layout_store_;

  std::mutex layout_change_mutex_;  // one layout change at a time, held while it is saved
  mutable std::mutex mutex_;
  layout::Layout layout_;  // config_.layout as changed since; the tracker reads it
  directory::ValveDirectory directory_;
  // The poll schedule's requests that a valve resends by itself, each with how long its replies
  // may stop before the gateway asks again: two I'm Here periods, or two of its resend periods
  // if that is longer.
  struct ResentPoll {
    codec::ToValveMessage request;
    std::uint8_t reply = 0;
    Duration quiet_limit{};
  };
  static std::vector<ResentPoll> resent_polls_of(const std::vector<codec::ToValveMessage>& poll);
  const std::vector<ResentPoll> resent_polls_;
  std::unique_ptr<CommandTracker> tracker_;
  std::unique_ptr<CommandRateLimiter> limiter_;
  std::map<std::uint32_t, std::set<ErrorKind>> latched_errors_;
  std::map<std::string, ValveLocation> published_locations_;  // by location name
  std::set<std::uint32_t> reported_unassigned_;  // online valves in no location, logged once
  // Valves displaced from their address, and by whom: commands wait for their next I'm Here.
  std::map<std::uint32_t, std::uint32_t> displaced_by_;
  // Per valve and resent reply: since when it is awaited (polled, or last heard) and how many
  // times in a row it was asked for again in vain. Kept per reply, not per valve: a glitch in the
  // middle of a poll burst leaves some resends armed and others not, and the ones still flowing
  // must not hide the ones that stopped. A valve that never answers a request is asked again
  // ever more rarely (its limit doubles per miss, up to 32 times).
  struct Awaited {
    SteadyTime since;
    unsigned misses = 0;
  };
  std::map<std::uint32_t, std::map<std::uint8_t, Awaited>> awaited_;
  BridgeCounters counters_;
  // The first status waits one I'm Here period, so that its valve count means something to a
  // client that trusts it as the size of the directory.
  SteadyTime next_status_;
  // next_deadline()'s answer, kept between batches of frames: walking every valve's deadlines
  // once per batch was 8 % of the bus reader's time at a full bus. Only a command adds a
  // deadline; telemetry only ends them and an I'm Here moves one later or adds one no sooner
  // than offline_after from now. nullopt: walk again.
  mutable std::optional<SteadyTime> next_deadline_;

  isobus::AddressClaimer claimer_;
  std::set<std::uint32_t> polls_withheld_;  // valves that appeared before the address was held
  struct DeferredCommand {
    ValveCommand command;
    std::string commander;
  };
  std::vector<DeferredCommand> deferred_;  // taken during the wait after a claim
  can::BusState bus_state_seen_ = can::BusState::kErrorActive;
  std::uint64_t reopens_seen_ = 0;
  std::uint64_t outages_seen_ = 0;
};

}  // namespace teejet::bridge
