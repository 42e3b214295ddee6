#include "valve_settings.hpp"

namespace teejet::sim {

void ValveSettings::apply_to(ValveConfig& config) const {
  if (serial) config.serial = *serial;
  if (part_number) config.part_number = *part_number;
  if (degrees_per_second) config.degrees_per_second = *degrees_per_second;
  if (closed_degrees) config.closed_degrees = *closed_degrees;
  if (opened_degrees) config.opened_degrees = *opened_degrees;
  if (start_degrees) config.start_degrees = *start_degrees;
  if (opening_direction) config.opening_direction = *opening_direction;
  if (application_version) config.application_version = *application_version;
  if (bootloader_version) config.bootloader_version = *bootloader_version;
  if (volts) config.volts = *volts;
  if (valve_temperature_c) config.valve_temperature_c = *valve_temperature_c;
  if (sensor_temperature_c) config.sensor_temperature_c = *sensor_temperature_c;
  if (running_amps) config.running_amps = *running_amps;
  if (bit_rate) config.bit_rate = *bit_rate;
}

}  // namespace teejet::sim
