#include "support/recording_sink.hpp"

#include <algorithm>
#include <variant>

namespace teejet::testing {

namespace {

template <class Sample>
std::vector<Sample> without_times(const std::vector<RecordingSink::Arrived<Sample>>& arrived) {
  std::vector<Sample> out;
  out.reserve(arrived.size());
  for (const auto& a : arrived) out.push_back(a.sample);
  return out;
}

}  // namespace

void RecordingSink::presence(const ValvePresence& sample) {
  std::lock_guard lock(mutex_);
  presences_.push_back({sample, Clock::now(), ++sequence_});
}

void RecordingSink::location(const ValveLocation& sample) {
  std::lock_guard lock(mutex_);
  locations_.push_back(sample);
}

void RecordingSink::telemetry(const dds::TelemetrySample& sample) {
  std::lock_guard lock(mutex_);
  samples_.push_back({sample, Clock::now(), ++sequence_});
}

void RecordingSink::error_cleared(std::uint32_t serial, ErrorKind kind) {
  std::lock_guard lock(mutex_);
  cleared_.emplace_back(serial, kind);
}

void RecordingSink::command_status(const CommandStatus& status) {
  std::lock_guard lock(mutex_);
  statuses_.push_back({status, Clock::now(), ++sequence_});
}

void RecordingSink::layout_change_status(const LayoutChangeStatus& status) {
  std::lock_guard lock(mutex_);
  layout_statuses_.push_back(status);
}

void RecordingSink::gateway_status(const GatewayStatus& status) {
  std::lock_guard lock(mutex_);
  gateway_statuses_.push_back(status);
}

std::vector<ValvePresence> RecordingSink::presences() const {
  std::lock_guard lock(mutex_);
  return without_times(presences_);
}

std::vector<ValveLocation> RecordingSink::locations() const {
  std::lock_guard lock(mutex_);
  return locations_;
}

std::map<std::string, ValveLocation> RecordingSink::latest_locations() const {
  std::lock_guard lock(mutex_);
  std::map<std::string, ValveLocation> latest;
  for (const auto& sample : locations_)
    latest.insert_or_assign(sample.location().to_string(), sample);
  return latest;
}

std::vector<dds::TelemetrySample> RecordingSink::samples() const {
  std::lock_guard lock(mutex_);
  return without_times(samples_);
}

std::vector<std::pair<std::uint32_t, ErrorKind>> RecordingSink::cleared() const {
  std::lock_guard lock(mutex_);
  return cleared_;
}

std::vector<CommandStatus> RecordingSink::statuses() const {
  std::lock_guard lock(mutex_);
  return without_times(statuses_);
}

std::vector<LayoutChangeStatus> RecordingSink::layout_statuses() const {
  std::lock_guard lock(mutex_);
  return layout_statuses_;
}

std::vector<GatewayStatus> RecordingSink::gateway_statuses() const {
  std::lock_guard lock(mutex_);
  return gateway_statuses_;
}

std::vector<CommandState> RecordingSink::states_of(std::uint32_t command_id) const {
  std::lock_guard lock(mutex_);
  std::vector<CommandState> states;
  for (const auto& s : statuses_) {
    if (s.sample.command_id() == command_id) states.push_back(s.sample.state());
  }
  return states;
}

std::size_t RecordingSink::count(CommandState state) const {
  std::lock_guard lock(mutex_);
  return static_cast<std::size_t>(
      std::count_if(statuses_.begin(), statuses_.end(),
                    [&](const auto& s) { return s.sample.state() == state; }));
}

std::string RecordingSink::last_reason() const {
  std::lock_guard lock(mutex_);
  return statuses_.empty() ? std::string() : statuses_.back().sample.reason().to_string();
}

std::optional<RecordingSink::Arrived<CommandStatus>> RecordingSink::final_status(
    std::uint32_t command_id) const {
  std::lock_guard lock(mutex_);
  for (const auto& s : statuses_) {
    if (s.sample.command_id() == command_id && s.sample.state() != COMMAND_ACCEPTED) return s;
  }
  return std::nullopt;
}

std::optional<RecordingSink::Arrived<ValvePresence>> RecordingSink::last_presence(
    std::uint32_t serial) const {
  std::lock_guard lock(mutex_);
  for (auto it = presences_.rbegin(); it != presences_.rend(); ++it) {
    if (it->sample.serial() == serial) return *it;
  }
  return std::nullopt;
}

std::optional<RecordingSink::Arrived<dds::TelemetrySample>> RecordingSink::last_sample(
    std::uint32_t serial) const {
  std::lock_guard lock(mutex_);
  for (auto it = samples_.rbegin(); it != samples_.rend(); ++it) {
    if (std::visit([](const auto& sample) { return sample.serial(); }, it->sample) == serial) {
      return *it;
    }
  }
  return std::nullopt;
}

std::size_t RecordingSink::positions_since(std::uint32_t serial, Clock::time_point since) const {
  std::lock_guard lock(mutex_);
  return static_cast<std::size_t>(
      std::count_if(samples_.begin(), samples_.end(), [&](const auto& s) {
        const auto* position = std::get_if<ValvePosition>(&s.sample);
        return position != nullptr && position->serial() == serial && s.at >= since;
      }));
}

}  // namespace teejet::testing
