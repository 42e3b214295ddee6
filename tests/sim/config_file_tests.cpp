// Reading valve-sim's config file: every key, and every mistake refused with the file, the line
// and the key. How the file composes with the command line: setup_tests.cpp.

#include <gtest/gtest.h>

#include <string>

#include "config_file.hpp"
#include "example_config.hpp"
#include "support/text.hpp"
#include "teejet/codec/codec.hpp"

namespace teejet::sim {
namespace {

using ::teejet::testing::contains;
using testing::kExample;

// Why `text`, named sim.yaml, is refused; empty (and a failure) when it is not.
std::string reason(const std::string& text) {
  const auto file = parse_config(text, "sim.yaml");
  EXPECT_FALSE(file) << text;
  return file ? std::string() : file.error().reason;
}

TEST(SimConfigFile, TheExampleFileParses) {
  const auto file = parse_config(kExample, "example.yaml");
  ASSERT_TRUE(file) << file.error().reason;
  EXPECT_EQ(file->defaults.degrees_per_second, 120.0);
  ASSERT_EQ(file->valves.size(), 2u);
  const auto& first = file->valves[0];
  EXPECT_EQ(first.serial, 123456u);
  EXPECT_EQ(first.start_degrees, 45.0);
  EXPECT_EQ(first.opening_direction, codec::Rotation::kCounterclockwise);
  EXPECT_EQ(first.part_number, 4711u);
  EXPECT_EQ(first.application_version, (codec::SoftwareVersion{1, 2, 'e'}));
  EXPECT_EQ(first.bootloader_version, (codec::SoftwareVersion{0, 9, 0}));
  EXPECT_EQ(first.volts, 12.6);
  EXPECT_EQ(first.valve_temperature_c, 31);
  EXPECT_EQ(first.sensor_temperature_c, -2);
  EXPECT_EQ(first.running_amps, 0.85);
  EXPECT_EQ(first.bit_rate, codec::kBitRate500k);
  EXPECT_EQ(first.errors, (std::vector<InjectedError>{codec::HighTemperatureError{95, 85}}));
  ASSERT_EQ(file->hotplug.size(), 1u);
  EXPECT_EQ(file->hotplug[0].serial, 100u);
  EXPECT_EQ(file->errors,
            (std::vector<SerialError>{
                {123457, codec::MinDegreesPerSecondError{20, 30, codec::Direction::kClose}}}));
}

TEST(SimConfigFile, AnEmptyFileIsNoSettings) {
  const auto file = parse_config("", "empty.yaml");
  ASSERT_TRUE(file);
  EXPECT_TRUE(file->valves.empty());
}

TEST(SimConfigFile, FileMistakesAreRefusedWithTheLine) {
  EXPECT_TRUE(contains(reason("valves:\n  - serial: 1\n    dsp: 90\n"),
                       "sim.yaml:3: valves[0]: unknown key 'dsp'"));
  EXPECT_TRUE(contains(reason("valve: []\n"), "unknown key 'valve'"));
  EXPECT_TRUE(contains(reason("valves:\n  - dps: 90\n"), "needs a serial"));
  EXPECT_TRUE(contains(reason("defaults:\n  dps: fast\n"), "'fast' is not a number"));
  EXPECT_TRUE(contains(reason("defaults:\n  opening_direction: left\n"), "neither clockwise"));
  EXPECT_TRUE(contains(reason("defaults:\n  bit_rate: 1M\n"), "neither 250000"));
  EXPECT_TRUE(contains(reason("defaults:\n  valve_temperature: 200\n"), "-127 to 127"));
  EXPECT_TRUE(contains(reason("errors:\n  - {kind: high-voltage, value: 1, limit: 2}\n"),
                       "needs a serial"));
  EXPECT_TRUE(contains(reason("errors:\n  - {serial: 1, kind: x, value: 1, limit: 2}\n"),
                       "unknown error kind 'x'"));
  EXPECT_TRUE(contains(reason("defaults: [1, 2]\n"), "expected a mapping"));
  EXPECT_TRUE(contains(reason("defaults: {dps: [1\n"), "sim.yaml"));  // YAML syntax error
  EXPECT_TRUE(
      contains(reason("defaults:\n  serial: 5\n"), "sim.yaml:2: defaults: unknown key 'serial'"));
  EXPECT_TRUE(contains(reason("valves:\n  - serial: 1\n    errors:\n      - {serial: 1, kind: "
                              "low-voltage, value: 9, limit: 10}\n"),
                       "sim.yaml:4: valves[0].errors[0]: unknown key 'serial'"));
  EXPECT_TRUE(contains(reason("valves:\n  - serial: 1\n    errors:\n      - {kind: "
                              "high-temperature, value: 300, limit: 85}\n"),
                       "sim.yaml:4: valves[0].errors[0]: high_temperature_error: temperature_c "
                       "300 is outside 0 to 127"));
  EXPECT_TRUE(contains(reason("errors: {serial: 1}\n"), "sim.yaml:1: errors: expected a list"));
}

TEST(SimConfigFile, KeysGivenTwiceAreRefusedWithTheLine) {
  EXPECT_TRUE(contains(reason("defaults:\n  dps: 100\n  dps: 120\n"),
                       "sim.yaml:3: defaults: 'dps' is given twice"));
  EXPECT_TRUE(contains(reason("valves:\n  - serial: 1\nvalves:\n  - serial: 2\n"),
                       "sim.yaml:3: top level: 'valves' is given twice"));
  EXPECT_TRUE(contains(reason("valves:\n  - serial: 1\n    serial: 2\n"),
                       "sim.yaml:3: valves[0]: 'serial' is given twice"));
  EXPECT_TRUE(contains(
      reason("errors:\n  - {serial: 1, kind: low-voltage, value: 9, limit: 10, value: 8}\n"),
      "sim.yaml:2: errors[0]: 'value' is given twice"));
}

TEST(SimConfigFile, MissingFileIsReported) {
  const auto file = load_config("/nonexistent/teejet-sim.yaml");
  ASSERT_FALSE(file);
  EXPECT_TRUE(contains(file.error().reason, "/nonexistent/teejet-sim.yaml"));
}

}  // namespace
}  // namespace teejet::sim
