#include "teejet/sim/simulator.hpp"

#include <pthread.h>
#include <spdlog/spdlog.h>

#include <array>
#include <cstdio>
#include <type_traits>
#include <variant>

#include "teejet/candump/log_line.hpp"

namespace teejet::sim {
namespace {

std::string field_text(const codec::FieldValue& value) {
  return std::visit(
      [](const auto& v) -> std::string {
        using T = std::decay_t<decltype(v)>;
        if constexpr (std::is_same_v<T, std::string>) {
          return v;
        } else if constexpr (std::is_same_v<T, bool>) {
          return v ? "true" : "false";
        } else if constexpr (std::is_same_v<T, double>) {
          std::array<char, 32> text{};
          std::snprintf(text.data(), text.size(), "%.2f", v);
          std::string s = text.data();
          // Trim to the fewest decimals, keeping one: 90.00 -> 90.0, 0.25 -> 0.25.
          while (s.size() > 1 && s.back() == '0' && s[s.size() - 2] != '.') s.pop_back();
          return s;
        } else {
          return std::to_string(v);
        }
      },
      value);
}

template <class Message>
std::string message_text(const Message& message) {
  std::string text(codec::message_name(message));
  codec::for_each_field(message, [&](std::string_view name, const codec::FieldValue& value) {
    text += ' ';
    text += name;
    text += '=';
    text += field_text(value);
  });
  return text;
}

std::string address_text(std::uint8_t address) { return codec::format_address(address); }

}  // namespace

std::string describe_frame(Timestamp at, const std::string& interface_name,
                           const codec::CanFrame& frame) {
  const auto micros =
      std::chrono::duration_cast<std::chrono::microseconds>(at.time_since_epoch()).count();
  const auto seconds = static_cast<std::uint64_t>(micros < 0 ? 0 : micros / 1'000'000);
  const auto fraction = static_cast<std::uint32_t>(micros < 0 ? 0 : micros % 1'000'000);
  std::string text = candump::format_log_line(seconds, fraction, interface_name, frame) + "  ";
  const auto decoded = codec::decode(frame);
  if (!decoded) return text + "(" + decoded.error().reason + ")";
  text += address_text(decoded->route.valve_address) + ' ';
  std::visit([&](const auto& message) { text += message_text(message); }, decoded->message);
  return text;
}

Simulator::Simulator(std::unique_ptr<can::Bus> bus, SimulatorOptions options)
    : bus_(std::move(bus)), options_(std::move(options)) {
  logger_ = options_.logger ? options_.logger : spdlog::default_logger();
  if (!options_.clock) options_.clock = system_clock();
}

Simulator::~Simulator() { stop(); }

Status Simulator::start() {
  if (started()) return Error{ErrorCode::kUnavailable, "the simulator is already running"};
  // The valves power up when the bus is open; a trial power-up first refuses a bad bank without
  // touching the bus.
  const auto power_up = [this](ValveBank& bank) -> Status {
    const SteadyTime now = options_.clock->steady();
    if (const auto powered = bank.power_up(options_.valves, now); !powered) return powered;
    for (const auto& [serial, error] : options_.errors) {
      if (const auto injected = bank.inject_error(serial, error, now); !injected) return injected;
    }
    return {};
  };
  ValveBank trial;
  if (const auto valid = power_up(trial); !valid) return valid;
  if (options_.churn.period < Duration{0} ||
      (options_.churn.period > Duration{0} && options_.churn.off_for <= Duration{0})) {
    return Error{ErrorCode::kInvalidValue,
                 "churn: the period must be 0 (off) or positive, with a positive off time"};
  }
  if (const auto opened = bus_->open(); !opened) {
    return Error{opened.error().code, "cannot open " + bus_->name() + ": " + opened.error().reason,
                 opened.error().os_error};
  }
  {
    std::lock_guard lock(mutex_);
    bank_ = ValveBank{};
    if (const auto powered = power_up(bank_); !powered) return powered;  // as the trial did
    churn_random_.seed(options_.churn.seed);
    churned_.reset();
    next_churn_.reset();
    if (options_.churn.period > Duration{0}) {
      next_churn_ = options_.clock->steady() + options_.churn.period;
    }
  }
  for (const auto& [serial, address] : assignments()) {
    logger_->info("{} at address {} on {}", codec::format_serial(serial), address_text(address),
                  bus_->name());
  }
  thread_ = std::jthread([this](const std::stop_token& stop) { run(stop); });
  pthread_setname_np(thread_.native_handle(), "tj-simulator");
  return {};
}

void Simulator::stop() {
  if (thread_.joinable()) {
    thread_.request_stop();
    thread_.join();
    bus_->close();
  }
}

Status Simulator::add_valve(const ValveConfig& config, std::vector<AddressChange>* changes) {
  std::vector<AddressChange> local;
  auto* out = changes ? changes : &local;
  {
    std::lock_guard lock(mutex_);
    if (const auto added = bank_.add_valve(config, options_.clock->steady(), out); !added) {
      return added;
    }
  }
  log_changes(*out);
  return {};
}

void Simulator::log_changes(const std::vector<AddressChange>& changes) const {
  for (const auto& change : changes) {
    if (change.from) {
      logger_->info("{} moves from {} to {}", codec::format_serial(change.serial),
                    address_text(*change.from), address_text(change.to));
    } else {
      logger_->info("{} added at {}", codec::format_serial(change.serial), address_text(change.to));
    }
  }
}

Status Simulator::replace_valve(std::uint32_t old_serial, std::uint32_t new_serial,
                                std::vector<AddressChange>* changes) {
  ValveConfig config;
  {
    std::lock_guard lock(mutex_);
    const auto* old_valve = bank_.valve_with_serial(old_serial);
    if (old_valve == nullptr) {
      return Error{ErrorCode::kInvalidValue,
                   "no simulated valve " + codec::format_serial(old_serial) + " to replace"};
    }
    if (bank_.valve_with_serial(new_serial) != nullptr) {
      return Error{ErrorCode::kInvalidValue,
                   "a simulated valve " + codec::format_serial(new_serial) +
                       " exists already; a replacement needs a new serial"};
    }
    config = old_valve->config();
  }
  config.serial = new_serial;
  logger_->info("{} replaced by {}", codec::format_serial(old_serial),
                codec::format_serial(new_serial));
  if (auto off = power_off(old_serial, changes); !off) return off;
  return add_valve(config, changes);
}

Status Simulator::power_off(std::uint32_t serial, std::vector<AddressChange>* changes) {
  std::vector<AddressChange> local;
  auto* out = changes ? changes : &local;
  {
    std::lock_guard lock(mutex_);
    if (const auto off = bank_.power_off(serial, options_.clock->steady(), out); !off) return off;
  }
  logger_->info("{} powered off", codec::format_serial(serial));
  log_changes(*out);
  return {};
}

Status Simulator::power_on(std::uint32_t serial, bool boot_mode,
                           std::vector<AddressChange>* changes) {
  std::vector<AddressChange> local;
  auto* out = changes ? changes : &local;
  {
    std::lock_guard lock(mutex_);
    if (const auto on = bank_.power_on(serial, boot_mode, options_.clock->steady(), out); !on) {
      return on;
    }
  }
  logger_->info("{} powered on{}", codec::format_serial(serial),
                boot_mode ? ", running boot code" : "");
  log_changes(*out);
  return {};
}

Status Simulator::force_address(std::uint32_t serial, std::uint8_t address) {
  {
    std::lock_guard lock(mutex_);
    if (const auto forced = bank_.force_address(serial, address, options_.clock->steady());
        !forced) {
      return forced;
    }
  }
  logger_->warn("{} forced to claim {}", codec::format_serial(serial), address_text(address));
  return {};
}

void Simulator::churn(SteadyTime now) {
  std::vector<AddressChange> changes;
  if (churned_ && now >= churned_back_at_) {
    const auto serial = *churned_;
    churned_.reset();
    // A test may have powered it on itself meanwhile: nothing to do then.
    if (bank_.power_on(serial, false, now, &changes)) {
      logger_->info("churn: {} powered on", codec::format_serial(serial));
      log_changes(changes);
    }
  }
  if (!next_churn_ || now < *next_churn_) return;
  const auto period = options_.churn.period;
  *next_churn_ += period * ((now - *next_churn_) / period + 1);
  if (churned_) return;  // still off from the last period
  const auto on = bank_.assignments();
  if (on.empty()) return;
  // Not std::uniform_int_distribution: its results differ between standard libraries, and the
  // same seed must pick the same valves everywhere.
  const auto serial = on[churn_random_() % on.size()].serial;
  if (!bank_.power_off(serial, now, &changes)) return;
  churned_ = serial;
  churned_back_at_ = now + options_.churn.off_for;
  ++churn_count_;
  logger_->info(
      "churn: {} powered off for {} ms", codec::format_serial(serial),
      std::chrono::duration_cast<std::chrono::milliseconds>(options_.churn.off_for).count());
  log_changes(changes);
}

std::optional<SteadyTime> Simulator::next_churn_event() const {
  std::optional<SteadyTime> due = next_churn_;
  if (churned_ && (!due || churned_back_at_ < *due)) due = churned_back_at_;
  return due;
}

Status Simulator::inject_error(std::uint32_t serial, const InjectedError& error) {
  {
    std::lock_guard lock(mutex_);
    if (const auto injected = bank_.inject_error(serial, error, options_.clock->steady());
        !injected) {
      return injected;
    }
  }
  std::string values;
  codec::for_each_field(error, [&](std::string_view field, const codec::FieldValue& value) {
    values += ' ';
    values.append(field).append("=").append(std::visit(
        [](const auto& v) {
          if constexpr (std::is_same_v<std::decay_t<decltype(v)>, std::string>)
            return v;
          else
            return fmt::format("{}", v);
        },
        value));
  });
  logger_->info("{}: {} error latched ({})", codec::format_serial(serial), codec::error_kind(error),
                values.substr(1));
  return {};
}

std::vector<Assignment> Simulator::assignments() const {
  std::lock_guard lock(mutex_);
  return bank_.assignments();
}

std::chrono::milliseconds receive_timeout(std::optional<SteadyTime> next_due, SteadyTime now,
                                          std::chrono::milliseconds max_wait,
                                          std::chrono::milliseconds tick) {
  if (!next_due) return max_wait;
  SteadyTime wake = *next_due;
  if (tick > Duration{0}) {
    const Duration since_epoch = wake.time_since_epoch();
    const Duration tick_length = tick;
    const auto ticks = since_epoch / tick_length + (since_epoch % tick_length > Duration{0});
    wake = SteadyTime(ticks * tick_length);
  }
  const Duration left = wake - now;
  if (left <= Duration{0}) return std::chrono::milliseconds{0};
  if (left >= max_wait) return max_wait;
  // Rounded up: waking before the event would only lead to a second, empty wait.
  return std::chrono::ceil<std::chrono::milliseconds>(left);
}

std::chrono::milliseconds Simulator::wait_budget() const {
  std::optional<SteadyTime> due;
  {
    std::lock_guard lock(mutex_);
    due = bank_.next_due();
    if (const auto churn_due = next_churn_event(); churn_due && (!due || *churn_due < *due)) {
      due = churn_due;
    }
  }
  return receive_timeout(due, options_.clock->steady(), options_.max_wait, options_.timer_tick);
}

void Simulator::on_frame(const can::TimedFrame& received, std::vector<Outgoing>& out) {
  if (options_.verbose) log_frame("rx", received.received, received.frame);
  const auto decoded = codec::decode(received.frame);
  const auto* message = decoded && decoded->route.flow == codec::Flow::kToValve
                            ? std::get_if<codec::ToValveMessage>(&decoded->message)
                            : nullptr;
  if (message != nullptr) {
    const SteadyTime now = options_.clock->steady();
    std::lock_guard lock(mutex_);
    auto replies = bank_.handle(decoded->route.valve_address, *message, now);
    for (auto& reply : replies) out.push_back(std::move(reply));
  }
  ++frames_handled_;  // after acting on it: a test may move the clock once it sees the count
}

void Simulator::send(const std::vector<Outgoing>& outgoing) {
  frames_.clear();
  for (const auto& message : outgoing) {
    auto frame = codec::encode(message.address, message.message, options_.encode_options);
    if (!frame) {  // a bug: the valves only produce values in the sheet's ranges
      logger_->error("cannot encode {} from {}: {}", codec::message_name(message.message),
                     address_text(message.address), frame.error().reason);
      continue;
    }
    frames_.push_back(*frame);
  }
  if (frames_.empty()) return;
  const auto sent = bus_->send_batch(frames_);
  frames_sent_ += sent.sent;
  if (!sent.status) {
    send_failures_ += frames_.size() - sent.sent;
    // Once per outage, not once per frame: a link that is down would flood the log.
    if (!last_send_failed_) {
      logger_->warn("{}: send failed: {}", bus_->name(), sent.status.error().reason);
    }
    last_send_failed_ = true;
  } else {
    if (last_send_failed_) logger_->info("{}: sending again", bus_->name());
    last_send_failed_ = false;
  }
  if (options_.verbose) {
    const Timestamp now = options_.clock->wall();
    for (std::size_t i = 0; i < sent.sent; ++i) log_frame("tx", now, frames_[i]);
  }
}

void Simulator::log_frame(const char* way, Timestamp at, const codec::CanFrame& frame) const {
  logger_->info("{} {}", way, describe_frame(at, bus_->name(), frame));
}

void Simulator::run(const std::stop_token& stop) {
  std::vector<Outgoing> out;
  while (!stop.stop_requested()) {
    const auto received = bus_->receive(wait_budget());
    out.clear();
    if (received) on_frame(*received, out);
    {
      std::lock_guard lock(mutex_);
      churn(options_.clock->steady());
      auto due = bank_.advance(options_.clock->steady());
      for (auto& message : due) out.push_back(std::move(message));
    }
    send(out);
  }
}

}  // namespace teejet::sim
