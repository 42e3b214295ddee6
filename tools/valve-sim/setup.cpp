#include "setup.hpp"

#include <set>
#include <string>

#include "teejet/codec/codec.hpp"
#include "teejet/codec/table.hpp"
#include "teejet/sim/valve_bank.hpp"

namespace teejet::sim {
namespace {

Error setup_error(std::string reason) { return Error{ErrorCode::kInvalidValue, std::move(reason)}; }

}  // namespace

Result<Setup> compose_setup(const CommandLine& command_line, const ConfigFile& file) {
  if (command_line.valve_count && !command_line.serials.empty()) {
    return setup_error("--valves and --serials exclude each other");
  }
  ValveConfig base;
  file.defaults.apply_to(base);
  command_line.settings.apply_to(base);

  // Which valves make the bank.
  std::vector<std::uint32_t> serials;
  const bool from_command_line = command_line.valve_count || !command_line.serials.empty();
  if (command_line.valve_count) {
    const unsigned count = *command_line.valve_count;
    if (count < 1 || count > kMaxValves) {
      return setup_error("--valves " + std::to_string(count) + ": give 1 to " +
                         std::to_string(kMaxValves) + " (the addresses 0xD8-0xF7)");
    }
    for (unsigned i = 1; i <= count; ++i) serials.push_back(i);
  } else if (!command_line.serials.empty()) {
    serials = command_line.serials;
  } else {
    for (const auto& entry : file.valves) serials.push_back(*entry.serial);
  }
  if (serials.empty()) {
    return setup_error(
        "no valves to simulate: give --valves N, --serials LIST or a --config "
        "file with valves");
  }
  if (serials.size() > kMaxValves) {
    return setup_error(std::to_string(serials.size()) + " valves do not fit the " +
                       std::to_string(kMaxValves) + " addresses 0xD8-0xF7");
  }
  std::set<std::uint32_t> in_bank;
  for (const auto serial : serials) {
    if (!in_bank.insert(serial).second) {
      return setup_error("serial " + codec::format_serial(serial) + " is given twice");
    }
  }

  // The file's entries, by serial.
  std::set<std::uint32_t> seen;
  for (const auto& entry : file.valves) {
    if (!seen.insert(*entry.serial).second) {
      return setup_error("the config file lists " + codec::format_serial(*entry.serial) +
                         " twice under valves");
    }
    if (from_command_line && !in_bank.contains(*entry.serial)) {
      return setup_error("the config file has settings for " + codec::format_serial(*entry.serial) +
                         ", which is not one of the valves given by --valves/--serials");
    }
  }
  auto entry_for = [&](std::uint32_t serial) -> const ValveSettings* {
    for (const auto& entry : file.valves) {
      if (*entry.serial == serial) return &entry;
    }
    return nullptr;
  };

  Setup setup;
  setup.base = base;
  setup.base_errors = file.defaults.errors;
  for (const auto serial : serials) {
    ValveConfig config = base;
    config.serial = serial;
    const auto* entry = entry_for(serial);
    if (entry) entry->apply_to(config);
    if (const auto valid = validate(config); !valid) return setup_error(valid.error().reason);
    setup.valves.push_back(config);
    for (const auto& error : file.defaults.errors) setup.errors.push_back({serial, error});
    if (entry) {
      for (const auto& error : entry->errors) setup.errors.push_back({serial, error});
    }
  }

  std::set<std::uint32_t> hotplug_serials;
  for (const auto& entry : file.hotplug) {
    const auto serial = *entry.serial;
    if (in_bank.contains(serial) || !hotplug_serials.insert(serial).second) {
      return setup_error("hotplug valve " + codec::format_serial(serial) +
                         " is already in the bank or listed twice");
    }
    ValveConfig config = base;
    entry.apply_to(config);
    if (const auto valid = validate(config); !valid) {
      return setup_error("hotplug " + valid.error().reason);
    }
    setup.hotplug.push_back(config);
    for (const auto& error : file.defaults.errors) setup.hotplug_errors.push_back({serial, error});
    for (const auto& error : entry.errors) setup.hotplug_errors.push_back({serial, error});
  }

  for (const auto* errors : {&file.errors, &command_line.errors}) {
    for (const auto& serial_error : *errors) {
      if (in_bank.contains(serial_error.serial)) {
        setup.errors.push_back(serial_error);
      } else if (hotplug_serials.contains(serial_error.serial)) {
        setup.hotplug_errors.push_back(serial_error);
      } else {
        std::string reason = "error ";
        reason.append(codec::error_kind(serial_error.error))
            .append(" for ")
            .append(codec::format_serial(serial_error.serial))
            .append(", which is not a simulated valve");
        return setup_error(std::move(reason));
      }
    }
  }
  return setup;
}

}  // namespace teejet::sim
