#pragma once

// A config file that uses every key, shared by the tests of reading it and of composing it.

namespace teejet::sim::testing {

inline constexpr const char* kExample = R"(
defaults:
  dps: 120
  opened: 360
valves:
  - serial: TJV123456
    start: 45
    opening_direction: counterclockwise
    part_number: 4711
    application_version: "1.02e"
    bootloader_version: "0.09"
    volts: 12.6
    valve_temperature: 31
    sensor_temperature: -2
    running_amps: 0.85
    bit_rate: 500k
    errors:
      - {kind: high-temperature, value: 95, limit: 85}
  - serial: 123457
    opened: 90
hotplug:
  - serial: 100
    dps: 60
errors:
  - {serial: 123457, kind: min-dps, value: 20, limit: 30, direction: close}
)";

}  // namespace teejet::sim::testing
