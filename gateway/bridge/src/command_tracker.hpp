#pragma once

// Follows every accepted command to its final CommandState: moves until the position arrives
// (or their time runs out), timed runs until their time is up, requests until their reply. Pure
// logic on the steady clock: what ends is handed back to the bridge, which publishes it.

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "teejet/bridge/bridge.hpp"

namespace teejet::bridge {

// A command that reached its final state.
struct Ended {
  ValveCommand command;
  CommandState state;
  std::string reason;
};

// What the tracker asks of the bridge after an event.
struct Outcome {
  std::vector<Ended> ended;
  // Poll requests to send again: a one-shot request replaced the valve's automatic resend of
  // that value (the sheet: "until changed"), so the gateway's schedule is put back.
  std::vector<std::pair<std::uint32_t, codec::ToValveMessage>> restore;
};

class CommandTracker {
 public:
  // `layout` (the bridge's, which changes) gives each valve's mechanics.
  CommandTracker(const BridgeConfig& config, const layout::Layout& layout)
      : config_(config), layout_(layout) {}

  // A command that was sent to the valve: completes at once (stop, clear errors, speed 0) or is
  // followed. A run command supersedes the one the valve was working on.
  void sent(std::uint32_t serial, const codec::ToValveMessage& message, const ValveCommand& command,
            const std::string& commander, SteadyTime now, Outcome& out);

  // Telemetry from the valve: positions complete moves, replies complete requests. A move whose
  // valve stopped short of the target (speed 0 reported, the position steady) ends at once.
  void heard(std::uint32_t serial, const codec::FromValveMessage& message, SteadyTime now,
             Outcome& out);

  // The gateway stopped the valve on its own account (shutdown, fail-safe): its command is
  // over and nobody drives it any more.
  void stopped(std::uint32_t serial, const std::string& reason, Outcome& out);

  // The valve went offline: nothing it was asked will be confirmed.
  void offline(std::uint32_t serial, Outcome& out);
  // Nothing the valve was asked will be confirmed any more (it restarted, or its address is
  // contested): every command followed for it ends TIMED_OUT with `reason`.
  void lost(std::uint32_t serial, const std::string& reason, Outcome& out);

  // The gateway is going away: every command still followed ends TIMED_OUT with `reason`, so
  // that no commander is left waiting for a status that nobody will send.
  void abandon_all(const std::string& reason, Outcome& out);

  // Ends what is due at `now`.
  void expire(SteadyTime now, Outcome& out);

  std::optional<SteadyTime> next_deadline() const;

  // The valves last driven by `commander`: a writer id ("prefix|entity"), or a participant's
  // GUID prefix, which stands for all of its writers.
  std::vector<std::uint32_t> driven_by(const std::string& commander) const;

 private:
  struct Tracked {
    ValveCommand command;
    std::optional<SteadyTime> deadline;         // none for a manual drive: it has no observable end
    std::optional<double> target_degrees;       // moves: where the valve should end up
    std::optional<std::uint8_t> awaited_reply;  // requests: the message id that answers
    bool done_at_deadline = false;              // Milliseconds to Run: complete when its time is up
    std::optional<codec::ToValveMessage> restores;
    // Moves: when sent, what was asked before the mechanics clamped it, and what the
    // completion says about that; where and since when the position has been steady.
    SteadyTime sent_at{};
    std::optional<double> asked_degrees;
    bool mechanics_known = false;
    std::string completion_note;
    std::optional<double> steady_degrees;
    SteadyTime steady_since{};
  };
  struct Valve {
    std::optional<double> position;
    unsigned dps = 0;               // 0: not reported yet
    std::optional<unsigned> speed;  // the speed it last reported, and when
    SteadyTime speed_heard_at{};
    std::optional<Tracked> motion;  // the run command the valve is working on
    std::vector<Tracked> requests;  // awaiting their replies
    std::string commander;          // who last drove this valve
  };

  // A move whose valve holds still short of its target: the reason to end it, or none yet.
  // Keeps where and since when the move's position has been steady.
  static std::optional<std::string> stopped_short(Tracked& move, const Valve& valve, double degrees,
                                                  SteadyTime now);
  void end_motion(Valve& valve, CommandState state, const std::string& reason, Outcome& out);
  void end_request(std::uint32_t serial, const Tracked& request, CommandState state,
                   const std::string& reason, Outcome& out);
  std::optional<codec::ToValveMessage> schedule_entry_replaced_by(
      const codec::ToValveMessage& request) const;
  std::optional<double> target_of(const codec::ToValveMessage& message, const Valve& valve,
                                  const std::optional<layout::Mechanics>& limits) const;
  double travel(const codec::ToValveMessage& message, const Valve& valve,
                const std::optional<layout::Mechanics>& limits) const;  // worst case, degrees

  const BridgeConfig& config_;
  const layout::Layout& layout_;
  std::map<std::uint32_t, Valve> valves_;
};

}  // namespace teejet::bridge
