#include "teejet/layout/layout.hpp"

#include <algorithm>
#include <array>
#include <map>
#include <utility>

#include "teejet/codec/codec.hpp"
#include "teejet/codec/table.hpp"

namespace teejet::layout {
namespace {

constexpr std::array<std::string_view, 4> kRoleNames{"section", "master", "rate", "other"};

bool name_character(char c) { return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '-'; }

Error location_error(const Location& location, std::string field, std::string complaint) {
  auto error = field_error(ErrorCode::kInvalidValue, std::move(field), std::move(complaint));
  return in_context(
      "location " + (location.name.empty() ? std::string("(unnamed)") : location.name),
      std::move(error));
}

}  // namespace

std::string_view to_string(Role role) { return kRoleNames.at(static_cast<std::size_t>(role)); }

std::optional<Role> role_from(std::string_view name) {
  for (std::size_t i = 0; i < kRoleNames.size(); ++i) {
    if (kRoleNames[i] == name) return static_cast<Role>(i);
  }
  return std::nullopt;
}

std::span<const std::string_view> role_names() { return kRoleNames; }

bool Mechanics::full_turn() const { return opened_degrees >= codec::kFullTurnOpenedDegrees; }

Status check_name(std::string_view name) {
  const auto bad = [](std::string complaint) {
    return field_error(ErrorCode::kInvalidValue, "name", std::move(complaint));
  };
  if (name.empty()) return bad("is empty");
  if (name.size() > kMaxNameLength) {
    return bad("'" + std::string(name) + "' is " + std::to_string(name.size()) +
               " characters long, more than " + std::to_string(kMaxNameLength));
  }
  if (!std::all_of(name.begin(), name.end(), name_character) || name.front() < 'a' ||
      name.front() > 'z') {
    return bad("'" + std::string(name) +
               "' is not lower-case letters, digits and '-' starting with a letter");
  }
  const auto rest = name.substr(std::min<std::size_t>(3, name.size()));
  if (name.starts_with("tjv") && !rest.empty() &&
      std::all_of(rest.begin(), rest.end(), [](char c) { return c >= '0' && c <= '9'; })) {
    return bad("'" + std::string(name) + "' reads as a serial, and a valve is named by either");
  }
  return {};
}

Result<Layout> Layout::make(std::vector<Location> locations,
                            std::optional<Mechanics> default_mechanics, std::size_t* failed) {
  if (default_mechanics) {
    if (auto valid = codec::check_valve_limits(default_mechanics->closed_degrees,
                                               default_mechanics->opened_degrees);
        !valid) {
      return in_context("default mechanics", valid.error());
    }
  }
  std::map<std::string_view, const Location*> names;
  std::map<unsigned, const Location*> orders;
  std::map<std::uint32_t, const Location*> serials;
  for (const auto& location : locations) {
    if (failed != nullptr) *failed = static_cast<std::size_t>(&location - locations.data());
    if (auto valid = check_name(location.name); !valid) {
      return in_context("location", valid.error());
    }
    if (location.order < 1 || location.order > kMaxOrder) {
      return location_error(
          location, "order",
          std::to_string(location.order) + " is outside 1 to " + std::to_string(kMaxOrder));
    }
    if (location.mechanics) {
      if (auto valid = codec::check_valve_limits(location.mechanics->closed_degrees,
                                                 location.mechanics->opened_degrees);
          !valid) {
        return location_error(location, valid.error().field, valid.error().complaint);
      }
    }
    if (const auto [at, added] = names.emplace(location.name, &location); !added) {
      return location_error(location, "name", "is given twice");
    }
    if (const auto [at, added] = orders.emplace(location.order, &location); !added) {
      return location_error(
          location, "order",
          std::to_string(location.order) + " is " + at->second->name + "'s order too");
    }
    if (location.serial) {
      if (const auto [at, added] = serials.emplace(*location.serial, &location); !added) {
        return location_error(
            location, "serial",
            codec::format_serial(*location.serial) + " sits at " + at->second->name + " already");
      }
    }
  }
  std::sort(locations.begin(), locations.end(),
            [](const Location& a, const Location& b) { return a.order < b.order; });
  Layout layout;
  layout.locations_ = std::move(locations);
  layout.default_mechanics_ = default_mechanics;
  return layout;
}

const Location* Layout::find(std::string_view name) const {
  const auto it = std::find_if(locations_.begin(), locations_.end(),
                               [&](const Location& location) { return location.name == name; });
  return it == locations_.end() ? nullptr : &*it;
}

const Location* Layout::find_serial(std::uint32_t serial) const {
  const auto it = std::find_if(locations_.begin(), locations_.end(),
                               [&](const Location& location) { return location.serial == serial; });
  return it == locations_.end() ? nullptr : &*it;
}

Location* Layout::place_named(std::string_view name) {
  return const_cast<Location*>(std::as_const(*this).find(name));
}

Location* Layout::place_of(std::uint32_t serial) {
  return const_cast<Location*>(std::as_const(*this).find_serial(serial));
}

std::optional<Mechanics> Layout::mechanics_of(const Location& location) const {
  return location.mechanics ? location.mechanics : default_mechanics_;
}

std::optional<Mechanics> Layout::mechanics_of_serial(std::uint32_t serial) const {
  const auto* location = find_serial(serial);
  return location ? mechanics_of(*location) : default_mechanics_;
}

Result<Assignment> Layout::assign(std::string_view name, std::uint32_t serial, bool move) {
  auto* target = place_named(name);
  if (target == nullptr) {
    return field_error(ErrorCode::kInvalidValue, "location",
                       "'" + std::string(name) + "' is not in this gateway's layout");
  }
  Assignment assignment;
  if (target->serial == serial) {
    assignment.changed = false;
    return assignment;
  }
  auto* previous = place_of(serial);
  if (previous != nullptr && !move) {
    return field_error(ErrorCode::kInvalidValue, "serial",
                       codec::format_serial(serial) + " sits at " + previous->name +
                           "; unassign it there first, or move it");
  }
  if (previous != nullptr) {
    previous->serial.reset();
    assignment.moved_from = previous->name;
  }
  assignment.displaced = target->serial;
  target->serial = serial;
  return assignment;
}

Result<std::optional<std::uint32_t>> Layout::unassign(std::string_view name) {
  auto* target = place_named(name);
  if (target == nullptr) {
    return field_error(ErrorCode::kInvalidValue, "location",
                       "'" + std::string(name) + "' is not in this gateway's layout");
  }
  const auto serial = target->serial;
  target->serial.reset();
  return serial;
}

}  // namespace teejet::layout
