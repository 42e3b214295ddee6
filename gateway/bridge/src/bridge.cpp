#include "teejet/bridge/bridge.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace teejet::bridge {
namespace {

using namespace std::chrono_literals;

std::uint64_t nanoseconds(Timestamp t) { return static_cast<std::uint64_t>(t.count()); }

// The reply that answers a request: Request Position (0x11) is answered by Position (0x02), ...
std::optional<std::uint8_t> reply_id(const codec::ToValveMessage& message) {
  const std::uint8_t id = codec::message_id(message);
  if (id == 0x93) return 0x93;
  if (id >= 0x10 && id <= 0x18) return static_cast<std::uint8_t>(id - 0x0F);
  return std::nullopt;
}

bool is_run_command(const codec::ToValveMessage& message) {
  return codec::message_id(message) <= 0x05;
}

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

teejet::BusState to_idl(can::BusState state) {
  switch (state) {
    case can::BusState::kErrorActive:
      return BUS_ERROR_ACTIVE;
    case can::BusState::kErrorWarning:
      return BUS_ERROR_WARNING;
    case can::BusState::kErrorPassive:
      return BUS_ERROR_PASSIVE;
    case can::BusState::kBusOff:
      return BUS_OFF;
    case can::BusState::kDown:
      return BUS_DOWN;
  }
  return BUS_DOWN;
}

}  // namespace

std::vector<codec::ToValveMessage> default_poll_schedule() {
  return {codec::RequestVersion{},          codec::RequestPosition{1},
          codec::RequestTemperature{10},    codec::RequestVoltage{10},
          codec::RequestCurrent{10},        codec::RequestDegreesPerSecond{10},
          codec::RequestSpeedDirection{10}, codec::RequestRunTime{50},
          codec::RequestCycleCounts{50}};
}

Bridge::Bridge(BridgeConfig config, can::Bus& bus, Sink& sink)
    : config_(std::move(config)), bus_(bus), sink_(sink), directory_(config_.offline_after) {}

// ---- Frames from the bus ------------------------------------------------------------------

void Bridge::on_frame(const can::TimedFrame& frame) {
  const auto decoded = codec::decode(frame.frame);
  std::lock_guard lock(mutex_);
  if (!decoded) {
    ++counters_.decode_errors;
    counters_.last_decode_error = decoded.error().reason;
    return;
  }
  // Controller-to-valve frames on our bus come from another controller: not ours to translate.
  if (decoded->route.flow != codec::Flow::kFromValve) return;
  const auto& message = std::get<codec::FromValveMessage>(decoded->message);
  const std::uint8_t address = decoded->route.valve_address;
  if (const auto* here = std::get_if<codec::IAmHere>(&message)) {
    handle_i_am_here(address, *here, frame.received);
    return;
  }
  const auto serial = directory_.serial_at(address);
  if (!serial) {
    ++counters_.unattributed;
    return;
  }
  handle_telemetry(*serial, message, frame.received);
}

void Bridge::handle_i_am_here(std::uint8_t address, const codec::IAmHere& message,
                              Timestamp received) {
  const auto changes = directory_.on_i_am_here(address, message, received);
  const bool rearm = std::any_of(changes.begin(), changes.end(), [](const auto& change) {
    return change.kind == directory::ChangeKind::kAppeared ||
           change.kind == directory::ChangeKind::kReaddressed ||
           change.kind == directory::ChangeKind::kCameOnline;
  });
  const auto valve = *directory_.find(message.serial);
  valves_.try_emplace(message.serial);
  if (rearm) arm_polling(valve);
  publish_presence(valve);
}

void Bridge::handle_telemetry(std::uint32_t serial, const codec::FromValveMessage& message,
                              Timestamp received) {
  ValveState& valve = valves_[serial];
  if (const auto* position = std::get_if<codec::Position>(&message)) {
    valve.position = position->degrees;
    if (valve.motion && valve.motion->target_degrees &&
        dial_distance(position->degrees, *valve.motion->target_degrees) <=
            config_.completion_tolerance_degrees) {
      end_motion(valve, COMMAND_COMPLETED, "", received);
    }
  } else if (const auto* dps = std::get_if<codec::DegreesPerSecond>(&message)) {
    valve.dps = dps->dps;
  }

  const std::uint8_t id = codec::message_id(message);
  std::erase_if(valve.requests, [&](TrackedCommand& request) {
    if (request.awaited_reply != id) return false;
    end_request(serial, request, COMMAND_COMPLETED, "", received);
    return true;
  });

  auto sample = to_sample(serial, message, received);
  if (!sample) return;
  if (const auto* error = std::get_if<ValveError>(&*sample)) {
    valve.latched_errors.insert(error->kind());
  }
  sink_.telemetry(*sample);
}

void Bridge::arm_polling(const directory::ValveRecord& valve) {
  for (const auto& request : config_.poll) (void)send(valve.address, request);
}

std::optional<codec::ToValveMessage> Bridge::schedule_entry_replaced_by(
    const codec::ToValveMessage& request) const {
  // Only a one-shot request disturbs the schedule by surprise; asking for another period is
  // the client's explicit choice and stands until the valve reappears.
  const bool one_shot = std::visit(
      [](const auto& m) {
        if constexpr (requires { m.resend_tenths; }) {
          return m.resend_tenths == 0;
        } else {
          return false;
        }
      },
      request);
  if (!one_shot) return std::nullopt;
  for (const auto& entry : config_.poll) {
    if (codec::message_id(entry) == codec::message_id(request) && entry != request) return entry;
  }
  return std::nullopt;
}

void Bridge::end_request(std::uint32_t serial, const TrackedCommand& request, CommandState state,
                         const std::string& reason, Timestamp now) {
  finish(request, state, reason, now);
  if (!request.restores) return;
  if (const auto valve = directory_.find(serial); valve && valve->online) {
    (void)send(valve->address, *request.restores);
  }
}

void Bridge::publish_presence(const directory::ValveRecord& valve) {
  ValvePresence sample;
  sample.serial(valve.serial);
  sample.address(valve.address);
  sample.online(valve.online);
  sample.part_number(valve.part_number);
  sample.boot_mode(valve.boot_mode);
  sample.last_seen_ns(nanoseconds(valve.last_seen));
  sample.gateway(config_.gateway_name);
  sink_.presence(sample);
}

// ---- Commands -----------------------------------------------------------------------------

void Bridge::on_command(const ValveCommand& command, Timestamp now, const std::string& commander) {
  std::lock_guard lock(mutex_);
  const auto valve = directory_.find(command.serial());
  if (!valve) {
    ++counters_.commands_ignored;
    return;
  }
  if (!valve->online) {
    reject(command, "valve " + codec::format_serial(command.serial()) + " is offline", now);
    return;
  }
  if (command.kind() == COMMAND_SET_BAUD_RATE && !config_.allow_baud_change) {
    reject(command,
           "setting the baud rate is not allowed; start the gateway with --allow-baud-change", now);
    return;
  }
  const auto message = to_message(command);
  if (!message) {
    reject(command, message.error().reason, now);
    return;
  }
  const auto frame = codec::encode(valve->address, *message);
  if (!frame) {
    reject(command, frame.error().reason, now);
    return;
  }
  if (const auto sent = bus_.send(*frame); !sent) {
    reject(command, "CAN send failed: " + sent.reason(), now);
    return;
  }
  publish_status(command, COMMAND_ACCEPTED, "", now);
  track(command.serial(), *message, command, commander, now);
}

void Bridge::track(std::uint32_t serial, const codec::ToValveMessage& message,
                   const ValveCommand& command, const std::string& commander, Timestamp now) {
  ValveState& valve = valves_[serial];
  TrackedCommand tracked{command, commander, std::nullopt, std::nullopt, std::nullopt, false};

  if (!is_run_command(message)) {
    tracked.awaited_reply = reply_id(message);
    tracked.deadline = now + config_.reply_timeout;
    tracked.restores = schedule_entry_replaced_by(message);
    valve.requests.push_back(std::move(tracked));
    return;
  }

  // The valve works on the last command it received: whatever it was doing is replaced.
  end_motion(valve, COMMAND_SUPERSEDED,
             "replaced by command " + std::to_string(command.command_id()) +
                 (command.origin().size() == 0 ? "" : " from " + command.origin().to_string()),
             now);
  valve.commander = commander;

  const unsigned speed = speed_of(message);
  const bool stops = std::holds_alternative<codec::Stop>(message) ||
                     std::holds_alternative<codec::ClearErrors>(message) || speed == 0;
  if (std::holds_alternative<codec::ClearErrors>(message)) {
    for (const ErrorKind kind : valve.latched_errors) sink_.error_cleared(serial, kind);
    valve.latched_errors.clear();
  }
  if (stops) {
    finish(tracked, COMMAND_COMPLETED, "", now);
    return;
  }
  if (std::holds_alternative<codec::Manual>(message)) {
    // A manual drive has no end the gateway could observe; it stays accepted until replaced.
    valve.motion = std::move(tracked);
    return;
  }
  if (const auto* timed = std::get_if<codec::MillisecondsToRun>(&message)) {
    tracked.deadline = now + std::chrono::milliseconds(timed->milliseconds);
    tracked.done_at_deadline = true;
    valve.motion = std::move(tracked);
    return;
  }

  // Target Degrees or Degrees from Position: complete when the position arrives there.
  const ValveLimits* limits = limits_for(serial);
  tracked.target_degrees = target_of(message, valve, limits);
  const double dps = (valve.dps > 0 ? valve.dps : config_.assumed_dps) * speed / 100.0;
  const auto eta = std::chrono::duration_cast<std::chrono::nanoseconds>(
      std::chrono::duration<double>(travel(message, valve, limits) / dps));
  tracked.deadline = now + eta + config_.move_margin;
  if (tracked.target_degrees && valve.position &&
      dial_distance(*valve.position, *tracked.target_degrees) <=
          config_.completion_tolerance_degrees) {
    finish(tracked, COMMAND_COMPLETED, "", now);
    return;
  }
  valve.motion = std::move(tracked);
}

std::optional<double> Bridge::target_of(const codec::ToValveMessage& message,
                                        const ValveState& valve, const ValveLimits* limits) const {
  const bool limited = limits != nullptr && !limits->full_turn();
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

double Bridge::travel(const codec::ToValveMessage& message, const ValveState& valve,
                      const ValveLimits* limits) const {
  if (const auto* relative = std::get_if<codec::DegreesFromPosition>(&message)) {
    return relative->degrees;
  }
  const auto* target = std::get_if<codec::TargetDegrees>(&message);
  if (target == nullptr || !valve.position) return 360.0;
  const double from = *valve.position;
  if (limits != nullptr && !limits->full_turn()) {
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

const ValveLimits* Bridge::limits_for(std::uint32_t serial) const {
  if (auto it = config_.limits.find(serial); it != config_.limits.end()) return &it->second;
  return config_.default_limits ? &*config_.default_limits : nullptr;
}

can::Status Bridge::send(std::uint8_t address, const codec::ToValveMessage& message) {
  const auto frame = codec::encode(address, message);
  if (!frame) return can::Status::failure(frame.error().reason);
  return bus_.send(*frame);
}

void Bridge::publish_status(const ValveCommand& command, CommandState state,
                            const std::string& reason, Timestamp now) {
  CommandStatus status;
  status.serial(command.serial());
  status.command_id(command.command_id());
  status.origin(command.origin());
  status.kind(command.kind());
  status.state(state);
  status.reason(reason);
  status.stamp_ns(nanoseconds(now));
  sink_.command_status(status);
}

void Bridge::reject(const ValveCommand& command, const std::string& reason, Timestamp now) {
  ++counters_.commands_rejected;
  publish_status(command, COMMAND_REJECTED, reason, now);
}

void Bridge::finish(const TrackedCommand& tracked, CommandState state, const std::string& reason,
                    Timestamp now) {
  publish_status(tracked.command, state, reason, now);
}

// ---- Time ---------------------------------------------------------------------------------

void Bridge::tick(Timestamp now) {
  std::lock_guard lock(mutex_);
  for (const auto& change : directory_.expire(now)) {
    publish_presence(change.valve);
    ValveState& valve = valves_[change.valve.serial];
    end_motion(valve, COMMAND_TIMED_OUT, "valve went offline", now);
    for (auto& request : valve.requests)
      finish(request, COMMAND_TIMED_OUT, "valve went offline", now);
    valve.requests.clear();
  }

  for (auto& [serial, valve] : valves_) {
    if (valve.motion && valve.motion->deadline && now >= *valve.motion->deadline) {
      const TrackedCommand& motion = *valve.motion;
      if (motion.done_at_deadline) {
        end_motion(valve, COMMAND_COMPLETED, "", now);
      } else if (motion.target_degrees) {
        end_motion(valve, COMMAND_TIMED_OUT,
                   "position " + (valve.position ? format_degrees(*valve.position) : "unknown") +
                       " did not reach " + format_degrees(*motion.target_degrees) + " in time",
                   now);
      } else {
        end_motion(valve, COMMAND_TIMED_OUT, "position unknown: the move could not be confirmed",
                   now);
      }
    }
    std::erase_if(valve.requests, [&](TrackedCommand& request) {
      if (now < *request.deadline) return false;
      end_request(serial, request, COMMAND_TIMED_OUT,
                  "no reply within " +
                      std::to_string(std::chrono::duration_cast<std::chrono::milliseconds>(
                                         config_.reply_timeout)
                                         .count()) +
                      " ms",
                  now);
      return true;
    });
  }

  if (!next_status_) next_status_ = now + 1s;
  if (now >= *next_status_) {
    publish_gateway_status(now);
    next_status_ = now + 1s;
  }
}

void Bridge::publish_gateway_status(Timestamp now) {
  const auto bus = bus_.statistics();
  GatewayStatus status;
  status.gateway(config_.gateway_name);
  status.can_interface(config_.can_interface);
  status.bus_state(to_idl(bus.state));
  status.tx_errors(bus.tx_errors);
  status.rx_errors(bus.rx_errors);
  status.frames_in(bus.frames_in);
  status.frames_out(bus.frames_out);
  status.decode_errors(counters_.decode_errors);
  status.rx_dropped(bus.rx_dropped);
  status.valves_online(static_cast<std::uint32_t>(directory_.online_count()));
  status.valves_known(static_cast<std::uint32_t>(directory_.valves().size()));
  status.stamp_ns(nanoseconds(now));
  sink_.gateway_status(status);
}

// ---- Safe state ---------------------------------------------------------------------------

void Bridge::end_motion(ValveState& valve, CommandState state, const std::string& reason,
                        Timestamp now) {
  if (!valve.motion) return;
  finish(*valve.motion, state, reason, now);
  valve.motion.reset();
}

bool Bridge::stop_valve(std::uint32_t serial, const std::string& reason, Timestamp now) {
  const auto record = directory_.find(serial);
  if (!record || !record->online || !send(record->address, codec::Stop{})) return false;
  end_motion(valves_[serial], COMMAND_SUPERSEDED, reason, now);
  return true;
}

std::size_t Bridge::stop_all(Timestamp now) {
  std::lock_guard lock(mutex_);
  std::size_t stopped = 0;
  for (const auto& record : directory_.valves()) {
    if (stop_valve(record.serial, "gateway stopped the valve", now)) ++stopped;
  }
  return stopped;
}

std::size_t Bridge::stop_commanded_by(const std::string& commander, Timestamp now) {
  std::lock_guard lock(mutex_);
  std::size_t stopped = 0;
  for (auto& [serial, valve] : valves_) {
    const bool drove_it =
        valve.commander == commander || valve.commander.starts_with(commander + "|");
    if (commander.empty() || !drove_it) continue;
    if (!stop_valve(serial, "fail-safe: the commanding writer was lost", now)) continue;
    ++stopped;
    valve.commander.clear();
  }
  return stopped;
}

bool Bridge::owns(std::uint32_t serial) const {
  std::lock_guard lock(mutex_);
  return directory_.find(serial).has_value();
}

BridgeCounters Bridge::counters() const {
  std::lock_guard lock(mutex_);
  return counters_;
}

std::vector<directory::ValveRecord> Bridge::valves() const {
  std::lock_guard lock(mutex_);
  return directory_.valves();
}

}  // namespace teejet::bridge
