#include "teejet/sim/simulated_valve.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <type_traits>

#include "teejet/codec/table.hpp"

namespace teejet::sim {
namespace {

// Distances below this are no movement: positions are doubles, commands come in tenths.
constexpr double kEpsilonDegrees = 1e-6;
constexpr double kInfinity = std::numeric_limits<double>::infinity();

double in_seconds(Duration duration) { return std::chrono::duration<double>(duration).count(); }

Duration duration_of(double travel, double rate) {
  return Duration{std::llround(travel / rate * 1e9)};
}

// x modulo 360 in [0, 360).
double wrap(double degrees) {
  double r = std::fmod(degrees, kFullTurnDegrees);
  if (r < 0.0) r += kFullTurnDegrees;
  if (r >= kFullTurnDegrees) r -= kFullTurnDegrees;
  return r;
}

int sign_of(codec::Direction direction) { return direction == codec::Direction::kOpen ? 1 : -1; }

template <class... Ts>
struct Overloaded : Ts... {
  using Ts::operator()...;
};
template <class... Ts>
Overloaded(Ts...) -> Overloaded<Ts...>;

}  // namespace

SimulatedValve::SimulatedValve(ValveConfig config) : config_(std::move(config)) {
  if (const auto valid = validate(config_); !valid)
    throw std::invalid_argument(valid.error().reason);
  position_ = normalized(config_.start_position());
  bit_rate_ = config_.bit_rate;
}

// ---- Motion -----------------------------------------------------------------------------------

double SimulatedValve::normalized(double degrees) const {
  if (config_.full_turn()) return wrap(degrees);
  return std::clamp(degrees, config_.closed_degrees, config_.opened_degrees);
}

double SimulatedValve::travelled(const Motion& motion, SteadyTime now) const {
  return std::min(motion.rate * std::max(0.0, in_seconds(now - motion.start)), motion.travel);
}

Duration SimulatedValve::driven(const Motion& motion, SteadyTime now) {
  Duration elapsed = std::max(Duration{0}, now - motion.start);
  if (motion.duration) elapsed = std::min(elapsed, *motion.duration);
  return elapsed;
}

double SimulatedValve::distance_to_limit(codec::Direction direction) const {
  if (config_.full_turn()) return kInfinity;
  return direction == codec::Direction::kOpen ? config_.opened_degrees - position_
                                              : position_ - config_.closed_degrees;
}

bool SimulatedValve::running(SteadyTime now) const {
  return motion_ && (!motion_->duration || now < motion_->start + *motion_->duration);
}

double SimulatedValve::position(SteadyTime now) const {
  if (!motion_) return position_;
  if (!running(now)) return motion_->end_position;
  return normalized(motion_->start_position + motion_->sign * travelled(*motion_, now));
}

unsigned SimulatedValve::speed_percent(SteadyTime now) const {
  return running(now) ? motion_->speed_percent : 0;
}

double SimulatedValve::run_time_seconds(SteadyTime now) const { return in_seconds(run_time(now)); }

Duration SimulatedValve::run_time(SteadyTime now) const {
  return run_time_ + (motion_ ? driven(*motion_, now) : Duration{0});
}

bool SimulatedValve::ran_at_full_speed(SteadyTime now) const {
  return ran_at_full_speed_ ||
         (motion_ && motion_->speed_percent == 100 && driven(*motion_, now) > Duration{0});
}

void SimulatedValve::halt(SteadyTime now) {
  if (!motion_) return;
  position_ = position(now);
  run_time_ += driven(*motion_, now);
  ran_at_full_speed_ = ran_at_full_speed(now);
  motion_.reset();
}

void SimulatedValve::settle(SteadyTime now) {
  if (motion_ && !running(now)) halt(now);
}

void SimulatedValve::run(unsigned speed_percent, codec::Direction direction, double travel,
                         std::optional<double> end_position, SteadyTime now) {
  halt(now);  // a new command replaces the running one
  speed_percent = std::min(speed_percent, 100u);
  if (speed_percent == 0) return;  // speed 0 = stop; not a run, not a cycle
  ++cycle_count_;
  direction_ = direction;
  if (!(travel > kEpsilonDegrees)) return;  // already there: counted, nothing to drive
  Motion motion;
  motion.start = now;
  motion.start_position = position_;
  motion.sign = sign_of(direction);
  motion.rate = config_.degrees_per_second * speed_percent / 100.0;
  motion.travel = travel;
  if (std::isfinite(travel)) motion.duration = duration_of(travel, motion.rate);
  motion.end_position = end_position ? *end_position : normalized(position_ + motion.sign * travel);
  motion.speed_percent = speed_percent;
  motion_ = motion;
}

void SimulatedValve::run_manual(const codec::Manual& command, SteadyTime now) {
  halt(now);
  const double limit = distance_to_limit(command.direction);
  std::optional<double> end;
  if (!config_.full_turn()) {
    end = command.direction == codec::Direction::kOpen ? config_.opened_degrees
                                                       : config_.closed_degrees;
  }
  run(command.speed_percent, command.direction, limit, end, now);
}

void SimulatedValve::run_target(const codec::TargetDegrees& command, SteadyTime now) {
  halt(now);
  if (!config_.full_turn()) {
    // The sheet: the target is clamped to the limits and the direction picked automatically.
    const double target =
        std::clamp(command.degrees, config_.closed_degrees, config_.opened_degrees);
    const auto direction = target > position_ ? codec::Direction::kOpen : codec::Direction::kClose;
    run(command.speed_percent, direction, std::abs(target - position_), target, now);
    return;
  }
  const double target = wrap(command.degrees);
  auto distance = [](double d) {
    return d < kEpsilonDegrees || d > kFullTurnDegrees - kEpsilonDegrees ? 0.0 : d;
  };
  const double opening = distance(wrap(target - position_));
  const double closing = distance(wrap(position_ - target));
  codec::Direction direction = codec::Direction::kOpen;
  switch (command.direction) {
    case codec::TargetDirection::kOpen:
      direction = codec::Direction::kOpen;
      break;
    case codec::TargetDirection::kClose:
      direction = codec::Direction::kClose;
      break;
    case codec::TargetDirection::kShortest:  // a tie opens
      direction = closing < opening ? codec::Direction::kClose : codec::Direction::kOpen;
      break;
  }
  run(command.speed_percent, direction, direction == codec::Direction::kOpen ? opening : closing,
      target, now);
}

void SimulatedValve::run_degrees(const codec::DegreesFromPosition& command, SteadyTime now) {
  halt(now);
  const int sign = sign_of(command.direction);
  if (config_.full_turn()) {  // without limit checking
    run(command.speed_percent, command.direction, command.degrees,
        wrap(position_ + sign * command.degrees), now);
    return;
  }
  const double target = normalized(position_ + sign * command.degrees);
  run(command.speed_percent, command.direction, std::abs(target - position_), target, now);
}

void SimulatedValve::run_milliseconds(const codec::MillisecondsToRun& command, SteadyTime now) {
  halt(now);
  const unsigned speed = std::min(command.speed_percent, 100u);
  const double rate = config_.degrees_per_second * speed / 100.0;
  const double wanted = rate * command.milliseconds / 1000.0;
  const double limit = distance_to_limit(command.direction);
  if (wanted >= limit) {  // stops at the limit first
    run(speed, command.direction, limit,
        command.direction == codec::Direction::kOpen ? config_.opened_degrees
                                                     : config_.closed_degrees,
        now);
    return;
  }
  run(speed, command.direction, wanted, std::nullopt, now);
  // Exactly the commanded time, not travel / rate recomputed in floating point.
  if (motion_) motion_->duration = std::chrono::milliseconds(command.milliseconds);
}

// ---- Messages ---------------------------------------------------------------------------------

void SimulatedValve::report(codec::VersionInfo& reply, SteadyTime) const {
  reply = {config_.application_version, config_.bootloader_version};
}

void SimulatedValve::report(codec::Position& reply, SteadyTime now) const {
  auto tenths = std::llround(position(now) * 10.0);
  tenths = config_.full_turn() ? (tenths % 3600 + 3600) % 3600 : std::clamp(tenths, 0LL, 3599LL);
  reply.degrees = static_cast<double>(tenths) / 10.0;
}

void SimulatedValve::report(codec::Temperature& reply, SteadyTime) const {
  reply = {config_.valve_temperature_c, config_.sensor_temperature_c};
}

void SimulatedValve::report(codec::Voltage& reply, SteadyTime) const {
  reply.volts = config_.volts;
}

void SimulatedValve::report(codec::RunCurrent& reply, SteadyTime now) const {
  reply = {config_.running_amps * speed_percent(now) / 100.0,
           ran_at_full_speed(now) ? config_.running_amps : 0.0};
}

void SimulatedValve::report(codec::DegreesPerSecond& reply, SteadyTime) const {
  reply = {static_cast<unsigned>(std::lround(config_.degrees_per_second)), direction_};
}

void SimulatedValve::report(codec::SpeedDirection& reply, SteadyTime now) const {
  reply = {speed_percent(now), direction_, config_.opening_direction};
}

void SimulatedValve::report(codec::RunTime& reply, SteadyTime now) const {
  const auto whole = std::chrono::duration_cast<std::chrono::seconds>(run_time(now)).count();
  reply.seconds = static_cast<std::uint32_t>(
      std::min<long long>(whole, std::numeric_limits<std::uint32_t>::max()));
}

void SimulatedValve::report(codec::CycleCounts& reply, SteadyTime) const {
  reply.count = cycle_count_;
}

void SimulatedValve::report(codec::BaudRateReply& reply, SteadyTime) const {
  reply.bit_rate = bit_rate_;
}

std::optional<codec::FromValveMessage> SimulatedValve::reply_to(
    const codec::ToValveMessage& request, SteadyTime now) const {
  auto reply = codec::reply_to(request);
  if (!reply) return std::nullopt;
  // A reply without a report() overload answers with every field zero.
  std::visit(
      [&](auto& message) {
        if constexpr (requires { report(message, now); }) report(message, now);
      },
      *reply);
  return reply;
}

void SimulatedValve::set_bit_rate(const codec::BaudRate& message) {
  if (message.action == codec::BaudAction::kSet) bit_rate_ = message.bit_rate;
}

void SimulatedValve::request(const codec::ToValveMessage& message, SteadyTime now,
                             std::vector<codec::FromValveMessage>& replies) {
  if (auto reply = reply_to(message, now)) replies.push_back(*std::move(reply));
  const auto resend = codec::field_value(message, "resend_tenths");
  if (!resend) return;  // sent once, by the sheet (Request Version)
  const auto tenths = std::get<std::int64_t>(*resend);
  const auto id = codec::message_id(message);
  if (tenths == 0) {
    resends_.erase(id);  // once, and a running resend of this kind ends
  } else {
    const Duration period = tenths * kTenthOfSecond;
    resends_.insert_or_assign(id, Periodic{message, period, now + period});
  }
}

void SimulatedValve::power_off(SteadyTime now) {
  halt(now);
  resends_.clear();
  errors_.clear();
  next_i_am_here_.reset();
  direction_ = codec::Direction::kClose;
  ran_at_full_speed_ = false;
  powered_ = false;
  boot_mode_ = false;
}

void SimulatedValve::power_on(bool boot_mode) {
  powered_ = true;
  boot_mode_ = boot_mode;
}

std::vector<codec::FromValveMessage> SimulatedValve::handle(const codec::ToValveMessage& message,
                                                            SteadyTime now) {
  if (!powered_) return {};
  settle(now);
  std::vector<codec::FromValveMessage> replies;
  if (boot_mode_) {
    // Boot code identifies itself and keeps the bus settings; the application (motion,
    // telemetry) does not run. Stop and Clear Errors have nothing to act on.
    if (const auto* baud = std::get_if<codec::BaudRate>(&message)) {
      set_bit_rate(*baud);
      request(message, now, replies);
    } else if (std::holds_alternative<codec::RequestVersion>(message)) {
      request(message, now, replies);
    }
    return replies;
  }
  std::visit(Overloaded{
                 [&](const codec::Stop&) { halt(now); },
                 [&](const codec::Manual& m) { run_manual(m, now); },
                 [&](const codec::TargetDegrees& m) { run_target(m, now); },
                 [&](const codec::DegreesFromPosition& m) { run_degrees(m, now); },
                 [&](const codec::ClearErrors&) {
                   errors_.clear();
                   halt(now);
                 },
                 [&](const codec::MillisecondsToRun& m) { run_milliseconds(m, now); },
                 [&](const codec::BaudRate& m) {
                   set_bit_rate(m);
                   request(message, now, replies);
                 },
                 // Requests, as the codec's table says who answers them.
                 [&](const auto&) { request(message, now, replies); },
             },
             message);
  return replies;
}

void SimulatedValve::schedule_i_am_here(SteadyTime first) { next_i_am_here_ = first; }

void SimulatedValve::inject_error(const InjectedError& error, SteadyTime now) {
  if (const auto valid = validate(error); !valid) throw std::invalid_argument(valid.error().reason);
  errors_.insert_or_assign(codec::message_id(error), Latched{error, now});
}

bool SimulatedValve::error_latched(std::string_view kind) const {
  const auto message = codec::error_message(kind);
  return message && errors_.contains(codec::message_id(*message));
}

std::optional<Duration> SimulatedValve::resend_period(std::uint8_t request_id) const {
  const auto resend = resends_.find(request_id);
  return resend == resends_.end() ? std::nullopt : std::optional(resend->second.period);
}

std::vector<codec::FromValveMessage> SimulatedValve::advance(SteadyTime now) {
  if (!powered_) return {};
  settle(now);
  struct Due {
    SteadyTime at;
    codec::FromValveMessage message;
  };
  std::vector<Due> due;
  // Fires a periodic event at most once and moves it past `now`, keeping its phase.
  auto fire = [&](SteadyTime& next, Duration period, auto&& make) {
    if (next > now) return;
    due.push_back({next, make()});
    next += period * ((now - next) / period + 1);
  };
  if (next_i_am_here_) {
    fire(*next_i_am_here_, kIAmHerePeriod, [&] {
      return codec::IAmHere{config_.part_number, config_.serial, boot_mode_};
    });
  }
  // Named, not structured bindings: clang before 16 cannot capture those.
  for (auto& entry : errors_) {
    Latched& latched = entry.second;
    fire(latched.next, kErrorRepeatPeriod, [&] { return latched.error; });
  }
  for (auto& entry : resends_) {
    Periodic& resend = entry.second;
    fire(resend.next, resend.period, [&] { return *reply_to(resend.request, now); });
  }
  std::stable_sort(due.begin(), due.end(), [](const Due& a, const Due& b) { return a.at < b.at; });
  std::vector<codec::FromValveMessage> messages;
  messages.reserve(due.size());
  for (auto& item : due) messages.push_back(std::move(item.message));
  return messages;
}

std::optional<SteadyTime> SimulatedValve::next_due() const {
  if (!powered_) return std::nullopt;
  std::optional<SteadyTime> earliest = next_i_am_here_;
  auto consider = [&](SteadyTime at) {
    if (!earliest || at < *earliest) earliest = at;
  };
  for (const auto& [id, latched] : errors_) consider(latched.next);
  for (const auto& [id, resend] : resends_) consider(resend.next);
  return earliest;
}

}  // namespace teejet::sim
