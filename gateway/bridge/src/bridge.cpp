#include "teejet/bridge/bridge.hpp"

#include <algorithm>

#include "command_rate_limiter.hpp"
#include "command_tracker.hpp"

namespace teejet::bridge {
namespace {

using namespace std::chrono_literals;

// The first gateway status waits this long: one I'm Here period.
constexpr Duration kStatusPeriod = 1s;

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

std::string hex_address(std::uint8_t address) {
  char text[8];
  std::snprintf(text, sizeof text, "0x%02X", address);
  return text;
}

// 100, 0.5: as a person would write the configured value.
std::string number_text(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  return text;
}

}  // namespace

std::vector<codec::ToValveMessage> default_poll_schedule() {
  return {codec::RequestVersion{},          codec::RequestPosition{1},
          codec::RequestTemperature{10},    codec::RequestVoltage{10},
          codec::RequestCurrent{10},        codec::RequestDegreesPerSecond{10},
          codec::RequestSpeedDirection{10}, codec::RequestRunTime{50},
          codec::RequestCycleCounts{50}};
}

Bridge::Bridge(BridgeConfig config, can::Bus& bus, Sink& sink, std::shared_ptr<const Clock> clock)
    : config_(std::move(config)),
      bus_(bus),
      sink_(sink),
      clock_(std::move(clock)),
      directory_(config_.offline_after),
      tracker_(std::make_unique<CommandTracker>(config_)),
      limiter_(std::make_unique<CommandRateLimiter>(config_.command_rate_per_valve,
                                                    config_.command_burst_per_valve)),
      next_status_(clock_->steady() + kStatusPeriod) {}

Bridge::~Bridge() = default;

// ---- Frames from the bus ------------------------------------------------------------------

// The lock is taken per frame, not per burst: a command arriving meanwhile waits for one frame's
// DDS write at most, never for a whole burst (measured in UML with an ECU reading: a burst-long
// lock made command->frame p50 9.6 ms instead of 0.5 ms). An uncontended lock costs ~20 ns.
void Bridge::on_frames(std::span<const can::TimedFrame> frames) {
  for (const auto& frame : frames) {
    std::lock_guard lock(mutex_);
    handle_frame(frame);
  }
}

void Bridge::handle_frame(const can::TimedFrame& frame) {
  const auto decoded = codec::decode(frame.frame);
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
    handle_i_am_here(address, *here, frame.received, clock_->steady());
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
                              Timestamp received, SteadyTime now) {
  bool rearm = false;
  for (const auto& change : directory_.on_i_am_here(address, message, received, now)) {
    switch (change.kind) {
      case directory::ChangeKind::kDisplaced:
        // It still works on its command; only where to reach it is unknown until it announces.
        displaced_by_[change.valve.serial] = message.serial;
        publish_presence(change.valve);
        break;
      case directory::ChangeKind::kAppeared:
      case directory::ChangeKind::kReaddressed:
      case directory::ChangeKind::kCameOnline:
        rearm = true;
        break;
      case directory::ChangeKind::kWentOffline:
      case directory::ChangeKind::kModeChanged:
        break;
    }
  }
  displaced_by_.erase(message.serial);
  if (next_deadline_) next_deadline_ = std::min(*next_deadline_, now + config_.offline_after);
  const auto valve = *directory_.find(message.serial);
  if (rearm) arm_polling(valve);
  publish_presence(valve);
}

void Bridge::handle_telemetry(std::uint32_t serial, const codec::FromValveMessage& message,
                              Timestamp received) {
  Outcome outcome;
  tracker_->heard(serial, message, outcome);
  settle(outcome);
  auto sample = dds::to_sample(serial, message, received);
  if (!sample) return;
  if (const auto* error = std::get_if<ValveError>(&*sample)) {
    latched_errors_[serial].insert(error->kind());
  }
  sink_.telemetry(*sample);
}

void Bridge::arm_polling(const directory::ValveRecord& valve) {
  for (const auto& request : config_.poll) (void)send(valve.address, request);
}

void Bridge::publish_presence(const directory::ValveRecord& valve) {
  ValvePresence sample;
  sample.serial(valve.serial);
  sample.address(valve.address);
  sample.online(valve.online);
  sample.part_number(valve.part_number);
  sample.boot_mode(valve.boot_mode);
  sample.last_seen_ns(unix_nanoseconds(valve.last_seen));
  sample.gateway(config_.gateway_name);
  sink_.presence(sample);
}

// ---- Commands -----------------------------------------------------------------------------

void Bridge::on_command(const ValveCommand& command, const std::string& commander) {
  std::lock_guard lock(mutex_);
  // Stamped before it is sent: a reply can arrive before this function returns, and a client
  // tells a fresh reply from an old one by comparing it with the ACCEPTED stamp.
  const Timestamp taken = clock_->wall();
  const auto valve = directory_.find(command.serial());
  const auto reject = [&](const std::string& reason) {
    ++counters_.commands_rejected;
    publish_status(command, COMMAND_REJECTED, reason, taken);
  };
  if (!valve) {
    if (config_.reject_unknown_serials) {
      reject("no valve " + codec::format_serial(command.serial()) + " on this gateway's bus (" +
             config_.can_interface + ")");
      return;
    }
    ++counters_.commands_ignored;
    return;
  }
  if (!valve->online) {
    reject(unreachable_reason(*valve));
    return;
  }
  if (command.kind() == COMMAND_SET_BAUD_RATE && !config_.allow_baud_change) {
    reject("setting the baud rate is not allowed; start the gateway with --allow-baud-change");
    return;
  }
  const auto message = dds::to_message(command);
  if (!message) {
    reject(message.error().reason);
    return;
  }
  const auto frame = codec::encode(valve->address, *message);
  if (!frame) {
    reject(frame.error().reason);
    return;
  }
  if (!limiter_->admit(command.serial(), std::holds_alternative<codec::Stop>(*message),
                       clock_->steady())) {
    ++counters_.commands_rate_limited;
    reject(rate_limit_reason(command.serial()));
    return;
  }
  if (const auto sent = bus_.send(*frame); !sent) {
    reject("CAN send failed: " + sent.error().reason);
    return;
  }
  publish_status(command, COMMAND_ACCEPTED, "", taken);
  if (std::holds_alternative<codec::ClearErrors>(*message)) {
    for (const ErrorKind kind : latched_errors_[command.serial()]) {
      sink_.error_cleared(command.serial(), kind);
    }
    latched_errors_.erase(command.serial());
  }
  Outcome outcome;
  tracker_->sent(command.serial(), *message, command, commander, clock_->steady(), outcome);
  next_deadline_.reset();
  settle(outcome);
}

std::string Bridge::rate_limit_reason(std::uint32_t serial) const {
  return "not sent: over the limit of " + number_text(config_.command_rate_per_valve) +
         " commands/s (burst " + std::to_string(config_.command_burst_per_valve) + ") to valve " +
         codec::format_serial(serial) + " (commands.rate_per_valve, commands.burst_per_valve)";
}

std::string Bridge::unreachable_reason(const directory::ValveRecord& valve) const {
  const std::string serial = codec::format_serial(valve.serial);
  if (auto it = displaced_by_.find(valve.serial); it != displaced_by_.end()) {
    return "valve " + serial + " is offline: " + codec::format_serial(it->second) +
           " took its address " + hex_address(valve.address) +
           " and it has not announced its new one yet";
  }
  return "valve " + serial + " is offline";
}

Status Bridge::send(std::uint8_t address, const codec::ToValveMessage& message) {
  const auto frame = codec::encode(address, message);
  if (!frame) return frame.error();
  return bus_.send(*frame);
}

void Bridge::publish_status(const ValveCommand& command, CommandState state,
                            const std::string& reason, Timestamp stamp) {
  CommandStatus status;
  status.serial(command.serial());
  status.command_id(command.command_id());
  status.origin(command.origin());
  status.kind(command.kind());
  status.state(state);
  status.reason(reason);
  status.stamp_ns(unix_nanoseconds(stamp));
  sink_.command_status(status);
}

void Bridge::settle(const Outcome& outcome) {
  const Timestamp now = clock_->wall();
  for (const auto& ended : outcome.ended) {
    publish_status(ended.command, ended.state, ended.reason, now);
  }
  for (const auto& [serial, request] : outcome.restore) {
    if (const auto valve = directory_.find(serial); valve && valve->online) {
      (void)send(valve->address, request);
    }
  }
}

// ---- Time ---------------------------------------------------------------------------------

void Bridge::tick() {
  std::lock_guard lock(mutex_);
  const SteadyTime now = clock_->steady();
  Outcome outcome;
  for (const auto& change : directory_.expire(now)) {
    publish_presence(change.valve);
    tracker_->offline(change.valve.serial, outcome);
  }
  tracker_->expire(now, outcome);
  settle(outcome);
  if (now >= next_status_) {
    publish_gateway_status();
    next_status_ = now + kStatusPeriod;
  }
  next_deadline_.reset();
}

SteadyTime Bridge::next_deadline() const {
  std::lock_guard lock(mutex_);
  if (!next_deadline_) next_deadline_ = earliest_deadline();
  return *next_deadline_;
}

SteadyTime Bridge::earliest_deadline() const {
  SteadyTime next = next_status_;
  if (const auto expiry = directory_.next_expiry()) {
    // Expiry is "older than the timeout": the first instant it is due is one tick later.
    next = std::min(next, *expiry + Duration{1});
  }
  if (const auto deadline = tracker_->next_deadline()) next = std::min(next, *deadline);
  return next;
}

void Bridge::publish_gateway_status() {
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
  status.stamp_ns(unix_nanoseconds(clock_->wall()));
  sink_.gateway_status(status);
}

// ---- Safe state ---------------------------------------------------------------------------

bool Bridge::stop_valve(std::uint32_t serial, const std::string& reason) {
  const auto record = directory_.find(serial);
  if (!record || !record->online || !send(record->address, codec::Stop{})) return false;
  Outcome outcome;
  tracker_->stopped(serial, reason, outcome);
  settle(outcome);
  return true;
}

std::size_t Bridge::stop_all() {
  std::lock_guard lock(mutex_);
  std::size_t stopped = 0;
  for (const auto& record : directory_.valves()) {
    if (stop_valve(record.serial, "gateway stopped the valve")) ++stopped;
  }
  return stopped;
}

std::size_t Bridge::end_all_commands() {
  std::lock_guard lock(mutex_);
  Outcome outcome;
  tracker_->abandon_all("the gateway stopped before the command finished", outcome);
  const std::size_t ended = outcome.ended.size();
  outcome.restore.clear();  // nobody is left to poll for
  settle(outcome);
  next_deadline_.reset();
  return ended;
}

std::size_t Bridge::stop_commanded_by(const std::string& commander) {
  std::lock_guard lock(mutex_);
  std::size_t stopped = 0;
  for (const std::uint32_t serial : tracker_->driven_by(commander)) {
    if (stop_valve(serial, "fail-safe: the commanding writer was lost")) ++stopped;
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
