#include "command_tracker.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace teejet::bridge {
namespace {

unsigned speed_of(const codec::ToValveMessage& message) {
  return std::visit(
      [](const auto& m) -> unsigned {
        if constexpr (requires { m.speed_percent; }) {
          return m.speed_percent;
        } else {
          return 0;
        }
      },
      message);
}

bool is_one_shot_request(const codec::ToValveMessage& message) {
  return std::visit(
      [](const auto& m) {
        if constexpr (requires { m.resend_tenths; }) {
          return m.resend_tenths == 0;
        } else {
          return false;
        }
      },
      message);
}

double wrap(double degrees) {
  const double wrapped = std::fmod(degrees, 360.0);
  return wrapped < 0 ? wrapped + 360.0 : wrapped;
}

// Degrees between two positions on the dial, whichever way is shorter.
double dial_distance(double a, double b) {
  const double d = std::fabs(wrap(a) - wrap(b));
  return std::min(d, 360.0 - d);
}

std::string format_degrees(double degrees) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f", degrees);
  return text;
}

// How still a valve must hold, and for how long, before a move that stopped short of its target
// ends: longer than the gap between two speed reports of the default poll (1 s).
constexpr double kSteadyDegrees = 0.2;
constexpr Duration kStoppedShortAfter = std::chrono::milliseconds(1500);

// `time + by`, held at the end of time instead of overflowing.
SteadyTime later(SteadyTime time, Duration by) {
  return by >= SteadyTime::max() - time ? SteadyTime::max() : time + by;
}

}  // namespace

void CommandTracker::sent(std::uint32_t serial, const codec::ToValveMessage& message,
                          const ValveCommand& command, const std::string& commander, SteadyTime now,
                          Outcome& out) {
  Valve& valve = valves_[serial];
  Tracked tracked{command, std::nullopt, std::nullopt, std::nullopt, false, std::nullopt};

  if (!codec::is_run_command(message)) {
    tracked.awaited_reply = codec::reply_id(message);
    tracked.deadline = later(now, config_.reply_timeout);
    tracked.restores = schedule_entry_replaced_by(message);
    valve.requests.push_back(std::move(tracked));
    return;
  }

  // The valve works on the last command it received: whatever it was doing is replaced.
  end_motion(valve, COMMAND_SUPERSEDED,
             "replaced by command " + std::to_string(command.command_id()) +
                 (command.origin().size() == 0 ? "" : " from " + command.origin().to_string()),
             out);
  valve.commander = commander;

  const unsigned speed = speed_of(message);
  const bool stops = std::holds_alternative<codec::Stop>(message) ||
                     std::holds_alternative<codec::ClearErrors>(message) || speed == 0;
  if (stops) {
    out.ended.push_back({command, COMMAND_COMPLETED, ""});
    return;
  }
  if (std::holds_alternative<codec::Manual>(message)) {
    // A manual drive has no end the gateway could observe; it stays accepted until replaced.
    valve.motion = std::move(tracked);
    return;
  }
  if (const auto* timed = std::get_if<codec::MillisecondsToRun>(&message)) {
    tracked.deadline = later(now, std::chrono::milliseconds(timed->milliseconds));
    tracked.done_at_deadline = true;
    valve.motion = std::move(tracked);
    return;
  }

  // Target Degrees or Degrees from Position: complete when the position arrives there.
  const auto limits = layout_.mechanics_of_serial(serial);
  tracked.target_degrees = target_of(message, valve, limits);
  tracked.asked_degrees = target_of(message, valve, std::nullopt);
  tracked.mechanics_known = limits.has_value();
  tracked.sent_at = now;
  if (tracked.target_degrees && tracked.asked_degrees &&
      dial_distance(*tracked.target_degrees, *tracked.asked_degrees) > 0.05) {
    const auto* place = layout_.find_serial(serial);
    const bool opened = *tracked.target_degrees == limits->opened_degrees;
    tracked.completion_note =
        "stopped at " + format_degrees(*tracked.target_degrees) + ", the " +
        (opened ? "Opened" : "Closed") + " Degrees of " +
        (place != nullptr ? place->name : std::string("this gateway's valves")) + " (asked " +
        format_degrees(*tracked.asked_degrees) + ")";
  }
  // The configuration keeps assumed_dps above 0; max() keeps a bad one from dividing by zero.
  const double full_speed_dps = std::max(1u, valve.dps > 0 ? valve.dps : config_.assumed_dps);
  const double dps = full_speed_dps * speed / 100.0;
  tracked.deadline =
      later(later(now, seconds(travel(message, valve, limits) / dps)), config_.move_margin);
  if (tracked.target_degrees && valve.position &&
      dial_distance(*valve.position, *tracked.target_degrees) <=
          config_.completion_tolerance_degrees) {
    out.ended.push_back({command, COMMAND_COMPLETED, tracked.completion_note});
    return;
  }
  valve.motion = std::move(tracked);
}

void CommandTracker::heard(std::uint32_t serial, const codec::FromValveMessage& message,
                           SteadyTime now, Outcome& out) {
  Valve& valve = valves_[serial];
  if (const auto* position = std::get_if<codec::Position>(&message)) {
    valve.position = position->degrees;
    if (valve.motion && valve.motion->target_degrees) {
      Tracked& move = *valve.motion;
      if (dial_distance(position->degrees, *move.target_degrees) <=
          config_.completion_tolerance_degrees) {
        end_motion(valve, COMMAND_COMPLETED, move.completion_note, out);
      } else if (const auto reason = stopped_short(move, valve, position->degrees, now)) {
        // Known mechanics put the target within reach: holding short of it is a fault, which
        // a move's deadline would only have reported later.
        end_motion(valve, move.mechanics_known ? COMMAND_TIMED_OUT : COMMAND_COMPLETED, *reason,
                   out);
      }
    }
  } else if (const auto* dps = std::get_if<codec::DegreesPerSecond>(&message)) {
    valve.dps = dps->dps;
  } else if (const auto* speed = std::get_if<codec::SpeedDirection>(&message)) {
    valve.speed = speed->speed_percent;
    valve.speed_heard_at = now;
  }
  const std::uint8_t id = codec::message_id(message);
  std::erase_if(valve.requests, [&](const Tracked& request) {
    if (request.awaited_reply != id) return false;
    end_request(serial, request, COMMAND_COMPLETED, "", out);
    return true;
  });
}

std::optional<std::string> CommandTracker::stopped_short(Tracked& move, const Valve& valve,
                                                         double degrees, SteadyTime now) {
  if (!move.steady_degrees || dial_distance(degrees, *move.steady_degrees) > kSteadyDegrees) {
    move.steady_degrees = degrees;
    move.steady_since = now;
    return std::nullopt;
  }
  const bool still = now - move.steady_since >= kStoppedShortAfter;
  const bool speed_zero = valve.speed == 0u && valve.speed_heard_at > move.sent_at;
  if (!still || !speed_zero) return std::nullopt;
  const std::string where = "stopped at " + format_degrees(degrees) + ", short of the " +
                            format_degrees(*move.target_degrees) + " asked, and holds there";
  if (move.mechanics_known) return where + " (speed 0): blocked, or its mechanics are not these";
  return where +
         ": presumably its own Opened or Closed Degrees, which the layout does not give "
         "for this valve (docs/layout.md)";
}

void CommandTracker::stopped(std::uint32_t serial, const std::string& reason, Outcome& out) {
  Valve& valve = valves_[serial];
  end_motion(valve, COMMAND_SUPERSEDED, reason, out);
  valve.commander.clear();
}

void CommandTracker::offline(std::uint32_t serial, Outcome& out) {
  lost(serial, "valve " + codec::format_serial(serial) + " went offline", out);
}

void CommandTracker::lost(std::uint32_t serial, const std::string& reason, Outcome& out) {
  Valve& valve = valves_[serial];
  end_motion(valve, COMMAND_TIMED_OUT, reason, out);
  for (const auto& request : valve.requests) {
    out.ended.push_back({request.command, COMMAND_TIMED_OUT, reason});
  }
  valve.requests.clear();
}

void CommandTracker::abandon_all(const std::string& reason, Outcome& out) {
  for (auto& [serial, valve] : valves_) {
    end_motion(valve, COMMAND_TIMED_OUT, reason, out);
    for (const auto& request : valve.requests) {
      out.ended.push_back({request.command, COMMAND_TIMED_OUT, reason});
    }
    valve.requests.clear();
  }
}

void CommandTracker::expire(SteadyTime now, Outcome& out) {
  for (auto& [serial, valve] : valves_) {
    if (valve.motion && valve.motion->deadline && now >= *valve.motion->deadline) {
      const Tracked& motion = *valve.motion;
      if (motion.done_at_deadline) {
        end_motion(valve, COMMAND_COMPLETED, "", out);
      } else if (motion.target_degrees) {
        end_motion(valve, COMMAND_TIMED_OUT,
                   "position " + (valve.position ? format_degrees(*valve.position) : "unknown") +
                       " did not reach " + format_degrees(*motion.target_degrees) + " in time",
                   out);
      } else {
        end_motion(valve, COMMAND_TIMED_OUT, "position unknown: the move could not be confirmed",
                   out);
      }
    }
    // Captured by name: clang before 16 cannot capture a structured binding.
    std::erase_if(valve.requests, [&, valve_serial = serial](const Tracked& request) {
      if (now < *request.deadline) return false;
      end_request(valve_serial, request, COMMAND_TIMED_OUT,
                  "no reply within " +
                      std::to_string(std::chrono::duration_cast<std::chrono::milliseconds>(
                                         config_.reply_timeout)
                                         .count()) +
                      " ms",
                  out);
      return true;
    });
  }
}

std::optional<SteadyTime> CommandTracker::next_deadline() const {
  std::optional<SteadyTime> earliest;
  const auto consider = [&](const std::optional<SteadyTime>& due) {
    if (due && (!earliest || *due < *earliest)) earliest = due;
  };
  for (const auto& [serial, valve] : valves_) {
    if (valve.motion) consider(valve.motion->deadline);
    for (const auto& request : valve.requests) consider(request.deadline);
  }
  return earliest;
}

std::vector<std::uint32_t> CommandTracker::driven_by(const std::string& commander) const {
  std::vector<std::uint32_t> driven;
  if (commander.empty()) return driven;
  for (const auto& [serial, valve] : valves_) {
    if (valve.commander == commander || valve.commander.starts_with(commander + "|")) {
      driven.push_back(serial);
    }
  }
  return driven;
}

void CommandTracker::end_motion(Valve& valve, CommandState state, const std::string& reason,
                                Outcome& out) {
  if (!valve.motion) return;
  out.ended.push_back({valve.motion->command, state, reason});
  valve.motion.reset();
}

void CommandTracker::end_request(std::uint32_t serial, const Tracked& request, CommandState state,
                                 const std::string& reason, Outcome& out) {
  out.ended.push_back({request.command, state, reason});
  if (request.restores) out.restore.emplace_back(serial, *request.restores);
}

std::optional<codec::ToValveMessage> CommandTracker::schedule_entry_replaced_by(
    const codec::ToValveMessage& request) const {
  // Only a one-shot request disturbs the schedule by surprise; asking for another period is
  // the client's explicit choice and stands until the valve reappears.
  if (!is_one_shot_request(request)) return std::nullopt;
  for (const auto& entry : config_.poll) {
    if (codec::message_id(entry) == codec::message_id(request) && entry != request) return entry;
  }
  return std::nullopt;
}

std::optional<double> CommandTracker::target_of(
    const codec::ToValveMessage& message, const Valve& valve,
    const std::optional<layout::Mechanics>& limits) const {
  const bool limited = limits && !limits->full_turn();
  const auto clamp = [&](double degrees) {
    return limited ? std::clamp(degrees, limits->closed_degrees, limits->opened_degrees)
                   : wrap(degrees);
  };
  if (const auto* target = std::get_if<codec::TargetDegrees>(&message)) {
    return clamp(target->degrees);
  }
  if (const auto* relative = std::get_if<codec::DegreesFromPosition>(&message)) {
    if (!valve.position) return std::nullopt;
    const double sign = relative->direction == codec::Direction::kOpen ? 1.0 : -1.0;
    return clamp(*valve.position + sign * relative->degrees);
  }
  return std::nullopt;
}

double CommandTracker::travel(const codec::ToValveMessage& message, const Valve& valve,
                              const std::optional<layout::Mechanics>& limits) const {
  if (const auto* relative = std::get_if<codec::DegreesFromPosition>(&message)) {
    return relative->degrees;
  }
  const auto* target = std::get_if<codec::TargetDegrees>(&message);
  if (target == nullptr || !valve.position) return 360.0;
  const double from = *valve.position;
  if (limits && !limits->full_turn()) {
    return std::fabs(std::clamp(target->degrees, limits->closed_degrees, limits->opened_degrees) -
                     from);
  }
  // A full-turn valve, or one whose limits are unknown: the direction decides the way round.
  switch (target->direction) {
    case codec::TargetDirection::kOpen:
      return wrap(target->degrees - from);
    case codec::TargetDirection::kClose:
      return wrap(from - target->degrees);
    case codec::TargetDirection::kShortest:
      return dial_distance(from, target->degrees);
  }
  return 360.0;
}

}  // namespace teejet::bridge
