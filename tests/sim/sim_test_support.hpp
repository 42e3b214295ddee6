#pragma once

// Shared helpers of the simulator tests: times relative to a fixed power-up instant and typed
// access to replies.

#include <gtest/gtest.h>

#include <chrono>
#include <variant>
#include <vector>

#include "teejet/codec/messages.hpp"
#include "teejet/sim/simulated_valve.hpp"

namespace teejet::sim::testing {

using namespace std::chrono_literals;

// Power-up on the steady clock, which times everything. The wall clock, which only stamps frames,
// reads something else entirely at that instant, so that a mix-up of the two shows.
inline constexpr SteadyTime kT0{std::chrono::seconds(5'000)};
inline constexpr Timestamp kWallT0{std::chrono::seconds(1'700'000'000)};

// How long a test waits for the simulator's threads to do something.
inline constexpr auto kDeadline = std::chrono::seconds(5);

// kT0 + milliseconds.
constexpr SteadyTime at_ms(long long ms) { return kT0 + std::chrono::milliseconds(ms); }

// What the wall clock of a ManualClock(kWallT0, kT0) reads at steady time `t`, as long as only
// advance() has moved it.
constexpr Timestamp wall_at(SteadyTime t) { return kWallT0 + (t - kT0); }

// The only message of `messages`, which must be a T.
template <class T>
T only(const std::vector<codec::FromValveMessage>& messages) {
  EXPECT_EQ(messages.size(), 1u);
  if (messages.size() != 1 || !std::holds_alternative<T>(messages.front())) {
    ADD_FAILURE() << "expected exactly one message of the requested type";
    return T{};
  }
  return std::get<T>(messages.front());
}

// The position the valve reports, in degrees (tenths resolution), at `now`.
inline double reported_position(SimulatedValve& valve, SteadyTime now) {
  return only<codec::Position>(valve.handle(codec::RequestPosition{0}, now)).degrees;
}

// A default valve (limited, 0-90, 90 deg/s) with this serial, starting at `start` degrees.
inline ValveConfig valve_with(std::uint32_t serial, double start = 0.0) {
  ValveConfig config;
  config.serial = serial;
  config.start_degrees = start;
  return config;
}

inline ValveConfig limited_valve(double start = 0.0) {
  ValveConfig config;
  config.serial = 123456;
  config.start_degrees = start;
  return config;  // dps 90, closed 0, opened 90
}

inline ValveConfig full_turn_valve(double start = 0.0) {
  ValveConfig config = limited_valve(start);
  config.opened_degrees = 360.0;
  return config;
}

}  // namespace teejet::sim::testing
