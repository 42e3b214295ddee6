#include "teejet/bridge/bridge.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>

#include "command_rate_limiter.hpp"
#include "command_tracker.hpp"
#include "teejet/codec/table.hpp"
#include "teejet/dds/conversions.hpp"

namespace teejet::bridge {
namespace {

using namespace std::chrono_literals;

// The first gateway status waits this long: one I'm Here period.
constexpr Duration kStatusPeriod = 1s;
// GatewayStatus.serials_online's bound (idl/teejet/valve.idl): two valves at each address.
constexpr std::size_t kMaxSerialsOnline = 64;
// Commands held during the 250 ms after an address claim; beyond, REJECTED with the reason.
constexpr std::size_t kMaxDeferredCommands = 256;
// The identifier bits that make a frame one from a valve to the controller (0x18EFD5xx, any
// priority): PGN 0xEF00 to 0xD5. Everything else the filters let in is the claimer's.
constexpr std::uint32_t kValveFrameMask = 0x03FFFF00;
constexpr std::uint32_t kValveFrameBits = codec::from_valve_id(0) & kValveFrameMask;

bool cut_off(can::BusState state) {
  return state == can::BusState::kBusOff || state == can::BusState::kDown;
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

std::string hex_address(std::uint8_t address) { return codec::format_address(address); }

std::string contest_reason(const directory::Contest& contest) {
  const auto [low, high] = std::minmax(contest.holder, contest.claimant);
  return "address " + hex_address(contest.address) + " is claimed by " + codec::format_serial(low) +
         " and " + codec::format_serial(high);
}

// Boot code identifies itself and keeps the bus settings but does not run the application
// (docs/valve-sim.md#power-off-power-on-and-the-churn): version and baud rate only. Stop is let
// through because it is harmless and a stop must never be refused when it can be sent.
bool runs_in_boot_code(const codec::ToValveMessage& message) {
  return std::holds_alternative<codec::RequestVersion>(message) ||
         std::holds_alternative<codec::BaudRate>(message) ||
         std::holds_alternative<codec::Stop>(message);
}

std::string boot_code_reason(std::uint32_t serial) {
  return "valve " + codec::format_serial(serial) + " is running boot code";
}

// How many times the quiet limit of a reply doubles while a valve keeps not sending it.
constexpr unsigned kMaxQuietBackoffShift = 5;

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

Bridge::Bridge(BridgeConfig config, can::Bus& bus, Sink& sink, std::shared_ptr<const Clock> clock,
               const OtherGateways* others, layout::LayoutStore* layout_store)
    : config_(std::move(config)),
      bus_(bus),
      sink_(sink),
      clock_(std::move(clock)),
      others_(others),
      layout_store_(layout_store),
      layout_(config_.layout),
      directory_(config_.offline_after),
      resent_polls_(resent_polls_of(config_.poll)),
      tracker_(std::make_unique<CommandTracker>(config_, layout_)),
      limiter_(std::make_unique<CommandRateLimiter>(config_.command_rate_per_valve,
                                                    config_.command_burst_per_valve)),
      next_status_(clock_->steady() + kStatusPeriod),
      claimer_(config_.isobus) {
  // Every place at once, so that an ECU resolves every name before the first valve announces.
  for (const auto& place : layout_.locations()) publish_location(place, false);
  const auto statistics = bus_.statistics();
  bus_state_seen_ = statistics.state;
  reopens_seen_ = statistics.reopens;
  outages_seen_ = statistics.outages;
  std::lock_guard lock(mutex_);
  apply(claimer_.claim(clock_->steady()));
}

Bridge::~Bridge() = default;

std::vector<can::Filter> frames_to_hear(const BridgeConfig& config) {
  auto filters = can::controller_side_filters();
  for (const auto& claiming : isobus::claiming_filters(config.isobus.address)) {
    filters.push_back({claiming.id, claiming.mask});
  }
  return filters;
}

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
  const codec::CanFrame& raw = frame.frame;
  if (!raw.extended || (raw.id & kValveFrameMask) != kValveFrameBits) {
    apply(claimer_.on_frame(raw, frame.received, clock_->steady()));
    return;
  }
  // Valves never claim: what an ECU that claimed this address sends is not a valve's.
  if (claimer_.claimed_by_neighbour(static_cast<std::uint8_t>(raw.id))) {
    ++counters_.neighbour_frames;
    apply(claimer_.on_frame(raw, frame.received, clock_->steady()));  // seen, not a valve
    return;
  }
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
  Outcome outcome;
  for (const auto& change : directory_.on_i_am_here(address, message, received, now)) {
    switch (change.kind) {
      case directory::ChangeKind::kDisplaced:
        // It still works on its command; only where to reach it is unknown until it announces.
        displaced_by_[change.valve.serial] = message.serial;
        publish_presence(change.valve);
        // Its offline expiry runs from its own last I'm Here, sooner than the cache allows for.
        next_deadline_.reset();
        break;
      case directory::ChangeKind::kAppeared:
      case directory::ChangeKind::kReaddressed:
      case directory::ChangeKind::kCameOnline:
        rearm = true;
        break;
      case directory::ChangeKind::kWentOffline:
        break;
      case directory::ChangeKind::kModeChanged:
        if (change.valve.boot_mode) {
          // Only a restart gets a valve into its boot code: what it was doing is gone.
          tracker_->lost(change.valve.serial,
                         "valve " + codec::format_serial(change.valve.serial) +
                             " restarted: it is running boot code",
                         outcome);
        } else {
          rearm = true;  // restarted into its application, which has no resends armed yet
        }
        break;
      case directory::ChangeKind::kAddressConflict: {
        const auto contest = directory_.contest_of(change.valve.serial);
        const auto reason = contest ? contest_reason(*contest) : "address contested";
        if (change.valve.serial == message.serial) {  // once per conflict, not per valve
          ++counters_.address_conflicts;
          spdlog::warn(
              "{}: neither valve can be told apart; telemetry from {} is dropped and "
              "commands to them are rejected until one moves away or goes silent",
              reason, hex_address(address));
        }
        tracker_->lost(change.valve.serial, reason, outcome);
        if (change.valve.serial != message.serial) publish_presence(change.valve);
        break;
      }
      case directory::ChangeKind::kConflictCleared:
        conflict_cleared(change);  // the other valve of the conflict, announcing elsewhere
        break;
    }
  }
  displaced_by_.erase(message.serial);
  if (next_deadline_) next_deadline_ = std::min(*next_deadline_, now + config_.offline_after);
  const auto valve = *directory_.find(message.serial);
  if (rearm) {
    arm_polling(valve);
  } else if (const auto quiet = quiet_polls(valve, now); !quiet.empty()) {
    // A power glitch short of offline_after at an address nobody took: the I'm Here looks like
    // any other, only the telemetry has stopped.
    poll_again(valve, quiet);
  }
  publish_presence(valve);
  settle(outcome);
}

void Bridge::conflict_cleared(const directory::Change& change) {
  spdlog::info("{}: address {} is no longer contested ({} moved away or went silent)",
               codec::format_serial(change.valve.serial), hex_address(change.valve.address),
               change.other ? codec::format_serial(*change.other) : "the other valve");
  // Both valves answered the polls at the contested address; the one left may have had its
  // resends replaced by the other's requests.
  arm_polling(change.valve);
  publish_presence(change.valve);
}

void Bridge::handle_telemetry(std::uint32_t serial, const codec::FromValveMessage& message,
                              Timestamp received) {
  if (const auto valve = awaited_.find(serial); valve != awaited_.end()) {
    if (const auto reply = valve->second.find(codec::message_id(message));
        reply != valve->second.end()) {
      reply->second = Awaited{clock_->steady()};
    }
  }
  // The sample goes out before the statuses it ends: a client that reads the position (or the
  // reply) on COMPLETED finds the one that completed the command, not the one before.
  if (auto sample = dds::to_sample(serial, message, received)) {
    if (const auto* error = std::get_if<ValveError>(&*sample)) {
      latched_errors_[serial].insert(error->kind());
    }
    sink_.telemetry(*sample);
  }
  Outcome outcome;
  tracker_->heard(serial, message, clock_->steady(), outcome);
  settle(outcome);
}

std::vector<Bridge::ResentPoll> Bridge::resent_polls_of(
    const std::vector<codec::ToValveMessage>& poll) {
  std::vector<ResentPoll> resent;
  for (const auto& request : poll) {
    const auto tenths = codec::field_value(request, "resend_tenths");
    const auto reply = codec::reply_id(request);
    if (!tenths || !reply || std::get<std::int64_t>(*tenths) == 0) continue;
    const Duration period = std::chrono::milliseconds(100) * std::get<std::int64_t>(*tenths);
    resent.push_back(
        ResentPoll{request, *reply, std::max(Duration{2 * kStatusPeriod}, 2 * period)});
  }
  return resent;
}

void Bridge::arm_polling(const directory::ValveRecord& valve) {
  if (!claimer_.may_send()) {
    polls_withheld_.insert(valve.serial);  // polled once the address is held
    return;
  }
  for (const auto& request : config_.poll) (void)send(valve.address, request);
  auto& awaited = awaited_[valve.serial];
  awaited.clear();
  for (const auto& poll : resent_polls_) awaited[poll.reply] = Awaited{clock_->steady()};
}

std::vector<const Bridge::ResentPoll*> Bridge::quiet_polls(const directory::ValveRecord& valve,
                                                           SteadyTime now) const {
  std::vector<const ResentPoll*> quiet;
  const auto awaited = awaited_.find(valve.serial);
  if (awaited == awaited_.end() || !valve.online || valve.boot_mode ||
      directory_.contest_of(valve.serial)) {
    return quiet;
  }
  for (const auto& poll : resent_polls_) {
    const auto reply = awaited->second.find(poll.reply);
    if (reply == awaited->second.end()) continue;
    const auto limit =
        poll.quiet_limit * (1u << std::min(reply->second.misses, kMaxQuietBackoffShift));
    if (now - reply->second.since > limit) quiet.push_back(&poll);
  }
  return quiet;
}

void Bridge::poll_again(const directory::ValveRecord& valve,
                        const std::vector<const ResentPoll*>& polls) {
  if (!claimer_.may_send()) return;
  std::string subjects;
  auto& awaited = awaited_[valve.serial];
  for (const auto* poll : polls) {
    (void)send(valve.address, poll->request);
    auto& reply = awaited[poll->reply];
    reply = Awaited{clock_->steady(), reply.misses + 1};
    if (!subjects.empty()) subjects += ", ";
    subjects += codec::subject(poll->request);
  }
  spdlog::info("{} sends no telemetry although polled (restarted?), none of: {}; polling it again",
               codec::format_serial(valve.serial), subjects);
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
  const auto* place = layout_.find_serial(valve.serial);
  sample.location(place ? place->name : "");
  sink_.presence(sample);
  if (place) {
    publish_location(*place, valve.online);
  } else if (!valve.online) {
    reported_unassigned_.erase(valve.serial);
  } else if (!layout_.empty() && reported_unassigned_.insert(valve.serial).second) {
    spdlog::warn(
        "{} is online at {} and sits in no location of this gateway's layout; assign "
        "it to its place (docs/layout.md)",
        codec::format_serial(valve.serial), hex_address(valve.address));
  }
}

ValveLocation Bridge::location_sample(const layout::Location& place, bool online) const {
  ValveLocation sample;
  sample.location(place.name);
  sample.gateway(config_.gateway_name);
  sample.order(static_cast<std::uint16_t>(place.order));
  switch (place.role) {
    case layout::Role::kSection:
      sample.role(ROLE_SECTION);
      break;
    case layout::Role::kMaster:
      sample.role(ROLE_MASTER);
      break;
    case layout::Role::kRate:
      sample.role(ROLE_RATE);
      break;
    case layout::Role::kOther:
      sample.role(ROLE_OTHER);
      break;
  }
  sample.assigned(place.serial.has_value());
  sample.serial(place.serial.value_or(0));
  sample.state(!place.serial ? LOCATION_EMPTY : online ? LOCATION_OK : LOCATION_MISSING);
  if (const auto mechanics = layout_.mechanics_of(place)) {
    sample.mechanics_known(true);
    sample.closed_degrees(static_cast<float>(mechanics->closed_degrees));
    sample.opened_degrees(static_cast<float>(mechanics->opened_degrees));
  }
  return sample;
}

void Bridge::publish_location(const layout::Location& place, bool online) {
  auto sample = location_sample(place, online);
  const auto [published, added] = published_locations_.try_emplace(place.name, sample);
  if (!added) {
    if (published->second == sample) return;
    published->second = sample;
  }
  sink_.location(sample);
}

// ---- Layout changes ---------------------------------------------------------------------

void Bridge::on_layout_change(const LayoutChange& change) {
  if (change.gateway().to_string() != config_.gateway_name) return;  // another gateway's layout
  std::lock_guard one_at_a_time(layout_change_mutex_);
  std::unique_lock lock(mutex_);
  auto changed = changed_layout(change);
  if (!changed) {
    publish_layout_change(change, LAYOUT_CHANGE_REJECTED, changed.error().reason);
    return;
  }
  auto& [next, what] = *changed;
  if (next == layout_) {  // nothing to save: it is so already
    publish_layout_change(change, LAYOUT_CHANGE_APPLIED, what);
    return;
  }
  // A save may wait for the disk: the bus reader must not wait with it.
  lock.unlock();
  const std::string gateway = "gateway " + config_.gateway_name;
  const Status saved = layout_store_ != nullptr
                           ? layout_store_->save(next)
                           : Status(Error{ErrorCode::kUnavailable,
                                          gateway + " has no layout file to keep it in (started "
                                                    "without layout_file: or --layout)"});
  lock.lock();
  if (!saved) {
    spdlog::warn("layout change for {} refused: {}", change.location().to_string(),
                 saved.error().reason);
    publish_layout_change(change, LAYOUT_CHANGE_REJECTED,
                          "nothing changed: " + saved.error().reason);
    return;
  }
  const layout::Layout before = std::exchange(layout_, std::move(next));
  publish_layout_moves(before);
  spdlog::info("layout: {} {}{}, asked by {}; saved", change.location().to_string(),
               change.kind() == LAYOUT_ASSIGN
                   ? "holds " + codec::format_serial(change.serial()) + " now"
                   : std::string("is empty now"),
               what.empty() ? "" : " (" + what + ")", change.origin().to_string());
  publish_layout_change(change, LAYOUT_CHANGE_APPLIED, what);
}

layout::Layout Bridge::current_layout() const {
  std::lock_guard lock(mutex_);
  return layout_;
}

Result<std::pair<layout::Layout, std::string>> Bridge::changed_layout(
    const LayoutChange& change) const {
  const std::string name = change.location().to_string();
  const std::string gateway = "gateway " + config_.gateway_name;
  if (layout_.find(name) == nullptr) {
    return Error{ErrorCode::kInvalidValue, gateway + "'s layout has no location '" + name + "'" +
                                               (layout_.empty() ? " (it has no layout)" : "")};
  }
  layout::Layout next = layout_;
  if (change.kind() == LAYOUT_UNASSIGN) {
    const auto left = next.unassign(name);
    if (!left) return left.error();
    return std::pair{std::move(next), *left ? codec::format_serial(**left) + " left it"
                                            : std::string("it was empty already")};
  }
  const std::uint32_t serial = change.serial();
  const std::string valve = codec::format_serial(serial);
  const auto record = directory_.find(serial);
  if (!record || !record->online) {
    const auto elsewhere =
        others_ != nullptr ? others_->reporting_online(serial) : std::vector<std::string>{};
    if (!elsewhere.empty()) {
      return Error{ErrorCode::kInvalidValue, valve + " is online on the bus of gateway " +
                                                 elsewhere.front() +
                                                 ", not of this one: assign it there"};
    }
    return Error{ErrorCode::kInvalidValue,
                 valve + " is not online on " + config_.can_interface + " (" + gateway +
                     "): a valve is assigned where it is fitted and announcing itself"};
  }
  const auto assigned = next.assign(name, serial, change.move());
  if (!assigned) {
    const Error& error = assigned.error();
    return Error{error.code, error.complaint.empty() ? error.reason : error.complaint};
  }
  std::string what;
  if (!assigned->changed) what = valve + " sat there already";
  if (assigned->displaced) what = codec::format_serial(*assigned->displaced) + " left it";
  if (assigned->moved_from) {
    what += (what.empty() ? "" : "; ") + valve + " left " + *assigned->moved_from;
  }
  return std::pair{std::move(next), what};
}

// Only what the change touched: the presence of each valve that came or went (which publishes
// its new place too), and the changed places no presence publishes (emptied, or holding a valve
// never heard).
void Bridge::publish_layout_moves(const layout::Layout& before) {
  std::set<std::uint32_t> moved;
  for (const auto& place : layout_.locations()) {
    const auto* was = before.find(place.name);
    if (was != nullptr && was->serial == place.serial) continue;
    if (was != nullptr && was->serial) moved.insert(*was->serial);
    if (place.serial) moved.insert(*place.serial);
    if (!place.serial || !directory_.find(*place.serial)) publish_location(place, false);
  }
  for (const std::uint32_t serial : moved) {
    reported_unassigned_.erase(serial);  // said again if it sits nowhere now
    if (const auto valve = directory_.find(serial)) publish_presence(*valve);
  }
}

void Bridge::publish_layout_change(const LayoutChange& change, LayoutChangeState state,
                                   std::string reason) {
  LayoutChangeStatus status;
  status.location(change.location());
  status.gateway(config_.gateway_name);
  status.change_id(change.change_id());
  status.origin(change.origin());
  status.kind(change.kind());
  const auto* place = layout_.find(change.location().to_string());
  status.serial(place != nullptr ? place->serial.value_or(0) : 0);
  status.state(state);
  status.reason(std::move(reason));
  status.stamp_ns(unix_nanoseconds(clock_->wall()));
  sink_.layout_change_status(status);
}

// ---- Commands -----------------------------------------------------------------------------

// A command on its way to the bus: what the checks of on_command() learn, one after the other.
struct Bridge::CommandUnderCheck {
  const ValveCommand& command;
  std::optional<directory::ValveRecord> valve;
  std::optional<codec::ToValveMessage> message;  // from translate()
  std::optional<codec::CanFrame> frame;          // from encode_frame()
};

void Bridge::on_command(const ValveCommand& command, const std::string& commander) {
  std::lock_guard lock(mutex_);
  take_command(command, commander);
}

void Bridge::take_command(const ValveCommand& command, const std::string& commander) {
  if (claimer_.state() == isobus::ClaimState::kClaiming &&
      deferred_.size() < kMaxDeferredCommands && directory_.find(command.serial())) {
    // Taken again when the wait after the claim ends (Bridge::apply): a quarter second at most.
    deferred_.push_back({command, commander});
    return;
  }
  // Stamped before it is sent: a reply can arrive before this function returns, and a client
  // tells a fresh reply from an old one by comparing it with the ACCEPTED stamp.
  const Timestamp taken = clock_->wall();
  CommandUnderCheck check{command, directory_.find(command.serial())};
  if (!check.valve && !config_.reject_unknown_serials) {
    ++counters_.commands_ignored;  // another gateway may own it
    return;
  }
  // In this order; the first reason ends the command REJECTED. Stop passes the boot-code check
  // and has a rate bucket of its own, so that a stop is never refused when it can be sent.
  static constexpr std::array kChecks{
      &Bridge::refuse_unknown_serial,
      &Bridge::refuse_without_address,
      &Bridge::refuse_offline,
      &Bridge::refuse_contested,
      &Bridge::refuse_online_elsewhere,
      &Bridge::refuse_baud_change,
      &Bridge::translate,
      &Bridge::refuse_in_boot_code,
      &Bridge::encode_frame,
      &Bridge::refuse_over_rate,
      &Bridge::send_frame,
  };
  for (const auto refusal_of : kChecks) {
    if (const auto reason = (this->*refusal_of)(check)) {
      ++counters_.commands_rejected;
      publish_status(command, COMMAND_REJECTED, *reason, taken);
      return;
    }
  }
  follow_sent(check, commander, taken);
}

std::optional<std::string> Bridge::refuse_unknown_serial(CommandUnderCheck& check) {
  if (check.valve) return std::nullopt;
  return "no valve " + codec::format_serial(check.command.serial()) + " on this gateway's bus (" +
         config_.can_interface + ")";
}

std::optional<std::string> Bridge::refuse_without_address(CommandUnderCheck& /*check*/) {
  return claimer_.refusal();
}

std::optional<std::string> Bridge::refuse_offline(CommandUnderCheck& check) {
  if (check.valve->online) return std::nullopt;
  return unreachable_reason(*check.valve);
}

std::optional<std::string> Bridge::refuse_contested(CommandUnderCheck& check) {
  // A frame to that address would reach both valves.
  if (const auto contest = directory_.contest_of(check.command.serial())) {
    return contest_reason(*contest);
  }
  return std::nullopt;
}

std::optional<std::string> Bridge::refuse_online_elsewhere(CommandUnderCheck& check) {
  // Two valves with one serial, or a replay: which one a command was meant for is unknown. A
  // Stop is safe for both, and each gateway stops its own.
  if (others_ == nullptr || check.command.kind() == COMMAND_STOP) return std::nullopt;
  const auto others = others_->reporting_online(check.command.serial());
  if (others.empty()) return std::nullopt;
  std::string names;
  for (const auto& name : others) names += (names.empty() ? "" : ", ") + name;
  return "valve " + codec::format_serial(check.command.serial()) + " is also online on gateway " +
         names +
         ": two valves carry this serial, or something replays it; commands to it but "
         "Stop are refused until only one gateway reports it";
}

std::optional<std::string> Bridge::refuse_baud_change(CommandUnderCheck& check) {
  if (check.command.kind() != COMMAND_SET_BAUD_RATE || config_.allow_baud_change) {
    return std::nullopt;
  }
  return "setting the baud rate is not allowed; start the gateway with --allow-baud-change";
}

std::optional<std::string> Bridge::translate(CommandUnderCheck& check) {
  auto message = dds::to_message(check.command);
  if (!message) return message.error().reason;
  check.message = std::move(*message);
  return std::nullopt;
}

std::optional<std::string> Bridge::refuse_in_boot_code(CommandUnderCheck& check) {
  if (!check.valve->boot_mode || runs_in_boot_code(*check.message)) return std::nullopt;
  return boot_code_reason(check.command.serial());
}

std::optional<std::string> Bridge::encode_frame(CommandUnderCheck& check) {
  const auto frame = codec::encode(check.valve->address, *check.message);
  if (!frame) return frame.error().reason;
  check.frame = *frame;
  return std::nullopt;
}

std::optional<std::string> Bridge::refuse_over_rate(CommandUnderCheck& check) {
  const bool stop = std::holds_alternative<codec::Stop>(*check.message);
  if (limiter_->admit(check.command.serial(), stop, clock_->steady())) return std::nullopt;
  ++counters_.commands_rate_limited;
  return rate_limit_reason(check.command.serial());
}

std::optional<std::string> Bridge::send_frame(CommandUnderCheck& check) {
  if (const auto sent = bus_.send(*check.frame); !sent) {
    return "CAN send failed: " + sent.error().reason;
  }
  return std::nullopt;
}

void Bridge::follow_sent(const CommandUnderCheck& check, const std::string& commander,
                         Timestamp taken) {
  const ValveCommand& command = check.command;
  publish_status(command, COMMAND_ACCEPTED, "", taken);
  if (std::holds_alternative<codec::ClearErrors>(*check.message)) {
    for (const ErrorKind kind : latched_errors_[command.serial()]) {
      sink_.error_cleared(command.serial(), kind);
    }
    latched_errors_.erase(command.serial());
  }
  Outcome outcome;
  tracker_->sent(command.serial(), *check.message, command, commander, clock_->steady(), outcome);
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

Status Bridge::send(std::uint8_t address, const codec::ToValveMessage& message,
                    bool even_while_claiming) {
  if (!claimer_.may_send() &&
      !(even_while_claiming && claimer_.state() == isobus::ClaimState::kClaiming)) {
    return Error{ErrorCode::kUnavailable, claimer_.refusal().value_or("")};
  }
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
  apply(claimer_.tick(now));
  Outcome outcome;
  for (const auto& change : directory_.expire(now)) {
    if (change.kind == directory::ChangeKind::kConflictCleared) {
      conflict_cleared(change);
      continue;
    }
    publish_presence(change.valve);
    tracker_->offline(change.valve.serial, outcome);
    displaced_by_.erase(change.valve.serial);
  }
  keep_command_deadlines(now, outcome);
}

void Bridge::tick_commands() {
  std::lock_guard lock(mutex_);
  Outcome outcome;
  keep_command_deadlines(clock_->steady(), outcome);
}

// Both threads come here at least once a second (the status), whichever keeps the deadlines.
void Bridge::keep_command_deadlines(SteadyTime now, Outcome& outcome) {
  reclaim_after_recovery(now);
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

SteadyTime Bridge::next_command_deadline() const {
  std::lock_guard lock(mutex_);
  return earliest_command_deadline();
}

SteadyTime Bridge::earliest_command_deadline() const {
  SteadyTime next = next_status_;
  if (const auto deadline = tracker_->next_deadline()) next = std::min(next, *deadline);
  return next;
}

SteadyTime Bridge::earliest_deadline() const {
  SteadyTime next = earliest_command_deadline();
  if (const auto claiming = claimer_.next_deadline()) next = std::min(next, *claiming);
  if (const auto expiry = directory_.next_expiry()) {
    // Expiry is "older than the timeout": the first instant it is due is one tick later.
    next = std::min(next, *expiry + Duration{1});
  }
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
  // One copy of the directory for both the count and the list.
  const auto valves = directory_.valves();
  std::vector<std::uint32_t> online;
  for (const auto& valve : valves) {
    if (valve.online) online.push_back(valve.serial);
  }
  status.valves_online(static_cast<std::uint32_t>(online.size()));
  status.valves_known(static_cast<std::uint32_t>(valves.size()));
  if (online.size() > kMaxSerialsOnline) online.resize(kMaxSerialsOnline);
  status.serials_online(std::move(online));
  status.locations_known(static_cast<std::uint32_t>(layout_.locations().size()));
  status.address_claim(dds::to_idl(claimer_.state()));
  status.source_address(config_.isobus.address);
  status.name(isobus::to_value(config_.isobus.name));
  status.address_holder(claimer_.holder() ? isobus::to_value(*claimer_.holder()) : 0);
  status.address_violations(claimer_.counters().address_violations);
  status.claims_in_valve_range(claimer_.counters().claims_in_valve_range);
  std::vector<BusNeighbour> neighbours;
  for (const auto& found : claimer_.neighbours()) {
    BusNeighbour neighbour;
    neighbour.address(found.address);
    neighbour.name(isobus::to_value(found.name));
    neighbour.last_seen_ns(unix_nanoseconds(found.last_seen));
    neighbours.push_back(neighbour);
  }
  status.neighbours(std::move(neighbours));
  status.stamp_ns(unix_nanoseconds(clock_->wall()));
  sink_.gateway_status(status);
}

// ---- Safe state ---------------------------------------------------------------------------

bool Bridge::stop_valve(std::uint32_t serial, const std::string& reason) {
  const auto record = directory_.find(serial);
  if (!record || !record->online || !send(record->address, codec::Stop{}, true)) return false;
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

// ---- Address claiming ---------------------------------------------------------------------

void Bridge::apply(const isobus::ClaimReaction& reaction) {
  for (const auto& frame : reaction.send) {
    if (const auto sent = bus_.send(frame); !sent) {
      spdlog::warn(
          "{}: address claiming frame 0x{:08X} not sent ({}); claimed again when the "
          "bus is back",
          config_.can_interface, frame.id, sent.error().reason);
    }
  }
  for (const auto& notice : reaction.notices) {
    if (notice.warning) {
      spdlog::warn("{}: {}", config_.can_interface, notice.text);
    } else {
      spdlog::info("{}: {}", config_.can_interface, notice.text);
    }
  }
  if (reaction.claim_sent) claimer_.wait_from(clock_->steady());
  next_deadline_.reset();
  if (!reaction.became_claimed) return;
  const auto withheld = std::exchange(polls_withheld_, {});
  for (const std::uint32_t serial : withheld) {
    if (const auto valve = directory_.find(serial); valve && valve->online) arm_polling(*valve);
  }
  for (const auto& deferred : std::exchange(deferred_, {})) {
    take_command(deferred.command, deferred.commander);
  }
}

void Bridge::reclaim_after_recovery(SteadyTime now) {
  const auto bus = bus_.statistics();
  const bool was_cut_off = cut_off(bus_state_seen_);
  bus_state_seen_ = bus.state;
  if (cut_off(bus.state)) return;  // claimed once it is back
  const bool recovered =
      was_cut_off || bus.outages != outages_seen_ || bus.reopens != reopens_seen_;
  outages_seen_ = bus.outages;
  reopens_seen_ = bus.reopens;
  if (!recovered || !config_.isobus.claim) return;
  spdlog::info("{}: the bus is back ({}): claiming the address again", config_.can_interface,
               can::to_string(bus.state));
  apply(claimer_.claim(now));
}

isobus::ClaimState Bridge::claim_state() const {
  std::lock_guard lock(mutex_);
  return claimer_.state();
}

std::vector<isobus::Neighbour> Bridge::neighbours() const {
  std::lock_guard lock(mutex_);
  return claimer_.neighbours();
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
