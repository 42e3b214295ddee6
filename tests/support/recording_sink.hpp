#pragma once

// What a Bridge publishes, as an ECU would see it on DDS, for suites that run a Bridge without
// DDS: every sample in order, with the steady time it arrived. The bridge may publish on another
// thread than the test reads on (a bus pump): every accessor locks and returns a copy.

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "teejet/bridge/bridge.hpp"

namespace teejet::testing {

class RecordingSink final : public bridge::Sink {
 public:
  using Clock = std::chrono::steady_clock;
  template <class Sample>
  struct Arrived {
    Sample sample;
    Clock::time_point at;
    std::uint64_t sequence = 0;  // the order of presences, samples and statuses, from 1
  };

  void presence(const ValvePresence& sample) override;
  void location(const ValveLocation& sample) override;
  void telemetry(const dds::TelemetrySample& sample) override;
  void error_cleared(std::uint32_t serial, ErrorKind kind) override;
  void command_status(const CommandStatus& status) override;
  void layout_change_status(const LayoutChangeStatus& status) override;
  void gateway_status(const GatewayStatus& status) override;

  std::vector<ValvePresence> presences() const;
  std::vector<ValveLocation> locations() const;
  // The newest sample of each location, by name.
  std::map<std::string, ValveLocation> latest_locations() const;
  std::vector<dds::TelemetrySample> samples() const;
  std::vector<std::pair<std::uint32_t, ErrorKind>> cleared() const;
  std::vector<CommandStatus> statuses() const;
  std::vector<LayoutChangeStatus> layout_statuses() const;
  std::vector<GatewayStatus> gateway_statuses() const;

  // The states command `command_id` went through, in order.
  std::vector<CommandState> states_of(std::uint32_t command_id) const;
  // How many statuses of any command are in `state`.
  std::size_t count(CommandState state) const;
  // The reason of the newest status; "" before the first.
  std::string last_reason() const;
  // The final status of command `command_id` (anything but ACCEPTED), once there is one.
  std::optional<Arrived<CommandStatus>> final_status(std::uint32_t command_id) const;
  std::optional<Arrived<ValvePresence>> last_presence(std::uint32_t serial) const;
  // The newest telemetry sample of `serial`, once there is one.
  std::optional<Arrived<dds::TelemetrySample>> last_sample(std::uint32_t serial) const;
  // Position samples of `serial` that arrived at `since` or later.
  std::size_t positions_since(std::uint32_t serial, Clock::time_point since) const;

 private:
  mutable std::mutex mutex_;
  std::uint64_t sequence_ = 0;
  std::vector<Arrived<ValvePresence>> presences_;
  std::vector<ValveLocation> locations_;
  std::vector<Arrived<dds::TelemetrySample>> samples_;
  std::vector<std::pair<std::uint32_t, ErrorKind>> cleared_;
  std::vector<Arrived<CommandStatus>> statuses_;
  std::vector<LayoutChangeStatus> layout_statuses_;
  std::vector<GatewayStatus> gateway_statuses_;
};

}  // namespace teejet::testing
