#pragma once

// Where each valve sits on the machine. The sheet asks the system to track a valve by the serial
// of its I'm Here, never by its address: a location names a place on the boom ("section-01"),
// its order on the machine, its role, the serial that sits there (or none yet) and that place's
// mechanics, which the protocol can neither set nor read. One layout per gateway (per bus).

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "teejet/core/result.hpp"

namespace teejet::layout {

enum class Role : std::uint8_t { kSection, kMaster, kRate, kOther };

std::string_view to_string(Role role);  // "section", "master", "rate", "other"
std::optional<Role> role_from(std::string_view name);
std::span<const std::string_view> role_names();

// Closed and Opened Degrees, which the valve is configured with (codec::check_valve_limits).
struct Mechanics {
  double closed_degrees = 0.0;
  double opened_degrees = 90.0;  // 360 = a full-turn valve
  bool full_turn() const;
  bool operator==(const Mechanics&) const = default;
};

// Lower-case letters, digits and '-', starting with a letter, at most this long, and never
// something that reads as a serial ("tjv000017"): a valve is named by either.
inline constexpr std::size_t kMaxNameLength = 32;
inline constexpr unsigned kMaxOrder = 9999;

// OK, or why not as a field_error about "name".
Status check_name(std::string_view name);

struct Location {
  std::string name;
  unsigned order = 0;  // 1..kMaxOrder, the machine's order (boom order, left to right)
  Role role = Role::kSection;
  std::optional<std::uint32_t> serial;  // nullopt: no valve assigned yet
  std::optional<Mechanics> mechanics;   // nullopt: the layout's default
  bool operator==(const Location&) const = default;
};

// What an accepted assignment changed: the serial that left `location` (if another was there)
// and the location that `serial` left (when it was moved from one).
struct Assignment {
  std::optional<std::uint32_t> displaced;
  std::optional<std::string> moved_from;
  bool changed = true;  // false: the serial sat there already
};

class Layout {
 public:
  Layout() = default;

  // Every rule checked: valid names and mechanics, no name, order or serial twice. The
  // locations are kept in machine order. Errors name the location and the field.
  // `failed`, when given, receives the index of the location an error is about.
  static Result<Layout> make(std::vector<Location> locations,
                             std::optional<Mechanics> default_mechanics = std::nullopt,
                             std::size_t* failed = nullptr);

  const std::vector<Location>& locations() const { return locations_; }
  const std::optional<Mechanics>& default_mechanics() const { return default_mechanics_; }
  bool empty() const { return locations_.empty(); }

  const Location* find(std::string_view name) const;
  const Location* find_serial(std::uint32_t serial) const;
  // The mechanics of a place: its own, else the layout's default; nullopt when neither is known.
  std::optional<Mechanics> mechanics_of(const Location& location) const;
  // The mechanics of the valve with this serial: its location's, else the default.
  std::optional<Mechanics> mechanics_of_serial(std::uint32_t serial) const;

  // Puts `serial` at the location `name`, replacing whatever serial sat there. A serial that
  // sits at another location is refused unless `move`, which empties the other location.
  Result<Assignment> assign(std::string_view name, std::uint32_t serial, bool move);
  // Empties the location `name`; returns the serial that sat there (nullopt: it was empty).
  Result<std::optional<std::uint32_t>> unassign(std::string_view name);

  bool operator==(const Layout&) const = default;

 private:
  Location* place_named(std::string_view name);
  Location* place_of(std::uint32_t serial);

  std::vector<Location> locations_;
  std::optional<Mechanics> default_mechanics_;
};

// Where a gateway keeps its layout when a person changes it (LayoutFileStore: its layout file).
class LayoutStore {
 public:
  virtual ~LayoutStore() = default;
  // Saves `layout` whole. An Error says why not; the change is then refused and not applied.
  virtual Status save(const Layout& layout) = 0;
};

}  // namespace teejet::layout
