#pragma once

// Valve settings as a user gives them, on the command line or in the config file: each one may
// or may not be given. Composed over the built-in defaults by compose_setup() (setup.hpp).

#include <cstdint>
#include <optional>
#include <vector>

#include "teejet/sim/valve_config.hpp"

namespace teejet::sim {

struct ValveSettings {
  std::optional<std::uint32_t> serial;
  std::optional<std::uint32_t> part_number;
  std::optional<double> degrees_per_second;
  std::optional<double> closed_degrees;
  std::optional<double> opened_degrees;
  std::optional<double> start_degrees;
  std::optional<codec::Rotation> opening_direction;
  std::optional<codec::SoftwareVersion> application_version;
  std::optional<codec::SoftwareVersion> bootloader_version;
  std::optional<double> volts;
  std::optional<int> valve_temperature_c;
  std::optional<int> sensor_temperature_c;
  std::optional<double> running_amps;
  std::optional<std::uint32_t> bit_rate;
  std::vector<InjectedError> errors;  // latched at power-up (or when added)

  // Overwrites only the settings that are given; the errors are not part of a ValveConfig.
  void apply_to(ValveConfig& config) const;
};

}  // namespace teejet::sim
