// Configuration: validation, the --inject-error syntax and how the command line and the config
// file compose into a bank. Reading the file itself: config_file_tests.cpp.

#include <gtest/gtest.h>

#include "example_config.hpp"
#include "setup.hpp"
#include "support/text.hpp"
#include "teejet/codec/codec.hpp"
#include "teejet/codec/table.hpp"

namespace teejet::sim {
namespace {

using ::teejet::testing::contains;
using testing::kExample;

// ---- ValveConfig ---------------------------------------------------------------------------

TEST(SimSetup, DefaultConfigurationIsValid) {
  EXPECT_TRUE(validate(ValveConfig{}));
  ValveConfig full_turn;
  full_turn.opened_degrees = 360;
  full_turn.start_degrees = 359.9;
  EXPECT_TRUE(validate(full_turn));
}

TEST(SimSetup, InvalidConfigurationsNameTheValveAndTheField) {
  const auto refused = [](auto change, const std::string& expected) {
    ValveConfig config;
    config.serial = 42;
    change(config);
    const auto status = validate(config);
    EXPECT_FALSE(status) << expected;
    EXPECT_TRUE(contains(status.error().reason, expected)) << status.error().reason;
    if (config.serial <= kMaxSerial) {
      EXPECT_TRUE(contains(status.error().reason, "TJV000042")) << status.error().reason;
    }
  };
  // The ranges are the codec's, named by the field of the message that reports the value.
  refused([](ValveConfig& c) { c.opened_degrees = 341; },
          "opened_degrees 341 is neither 360 (full turn) nor at most 340");
  refused([](ValveConfig& c) { c.opened_degrees = 400; }, "neither 360");
  refused([](ValveConfig& c) { c.closed_degrees = 90; },
          "closed_degrees 90 must be at least 0 and below opened_degrees 90");
  refused([](ValveConfig& c) { c.closed_degrees = -1; }, "at least 0");
  refused([](ValveConfig& c) { c.degrees_per_second = 0; }, "degrees per second 0 must be above 0");
  refused([](ValveConfig& c) { c.degrees_per_second = 360; }, "dps 360 is outside 0 to 359");
  refused([](ValveConfig& c) { c.start_degrees = 91; }, "start position");
  refused([](ValveConfig& c) { c.volts = 17; }, "volts 17 is outside 0 to 16.5");
  refused([](ValveConfig& c) { c.valve_temperature_c = 128; },
          "valve_c 128 is outside -127 to 127");
  refused([](ValveConfig& c) { c.running_amps = -1; }, "amps -1 is outside 0 to 655.35");
  refused([](ValveConfig& c) { c.bit_rate = 125000; }, "bit_rate 125000 is neither");
  refused([](ValveConfig& c) { c.part_number = 0x1000000; }, "part_number 16777216 is outside");
  refused([](ValveConfig& c) { c.application_version.minor = 256; }, "application");
  refused([](ValveConfig& c) { c.serial = 0x1000000; }, "24 bits");
}

// ---- --inject-error ------------------------------------------------------------------------

TEST(SimSetup, ErrorSpecsParse) {
  const auto high_voltage = parse_error_spec("TJV000001:high-voltage:16.2:15.5");
  ASSERT_TRUE(high_voltage) << high_voltage.error().reason;
  EXPECT_EQ(*high_voltage, (SerialError{1, codec::HighVoltageError{16.2, 15.5}}));
  const auto min_dps = parse_error_spec("123456:min_dps:20:30:close");
  ASSERT_TRUE(min_dps) << min_dps.error().reason;
  EXPECT_EQ(
      *min_dps,
      (SerialError{123456, codec::MinDegreesPerSecondError{20, 30, codec::Direction::kClose}}));
  // The codec's words, and the older ones with '-' and min-dps.
  for (const std::string_view kind : codec::error_kinds()) {
    const auto parsed = parse_error_spec("7:" + std::string(kind) + ":1:2");
    ASSERT_TRUE(parsed) << kind;
    EXPECT_EQ(codec::error_kind(parsed->error), kind);
  }
  for (const auto* older : {"high-voltage", "low-voltage", "high-current", "low-current",
                            "high-temperature", "min-dps"}) {
    EXPECT_TRUE(parse_error_spec(std::string("7:") + older + ":1:2")) << older;
  }
}

TEST(SimSetup, BadErrorSpecsSayWhatIsWrong) {
  const auto reason = [](std::string_view spec) {
    const auto parsed = parse_error_spec(spec);
    EXPECT_FALSE(parsed) << spec;
    return parsed ? std::string() : parsed.error().reason;
  };
  EXPECT_TRUE(contains(reason("1:high-voltage:16"), "SERIAL:KIND:VALUE:LIMIT"));
  EXPECT_TRUE(contains(reason("x:high-voltage:16:15"), "serial 'x'"));
  EXPECT_TRUE(contains(reason("1:sparks:16:15"), "unknown error kind 'sparks'"));
  EXPECT_TRUE(contains(reason("1:high-voltage:hot:15"), "must be numbers"));
  EXPECT_TRUE(contains(reason("1:high-voltage:16:15:open"), "high_voltage takes no DIRECTION"));
  EXPECT_TRUE(contains(reason("1:min-dps:16:15:up"), "\"up\" is not one of close, open"));
  EXPECT_TRUE(
      contains(reason("1:high-temperature:130:100"), "temperature_c 130 is outside 0 to 127"));
  EXPECT_TRUE(contains(reason("1:high-temperature:90.5:100"), "90.5 is not a whole number"));
  EXPECT_TRUE(contains(reason("1:low-current:-1:1"), "amps -1 is outside 0 to 655.35"));
}

TEST(SimSetup, VersionsAndRotationsParse) {
  EXPECT_EQ(*codec::parse_version("1.02e"), (codec::SoftwareVersion{1, 2, 'e'}));
  EXPECT_EQ(*codec::parse_version("2.10"), (codec::SoftwareVersion{2, 10, 0}));
  EXPECT_FALSE(codec::parse_version("1"));
  EXPECT_FALSE(codec::parse_version("1.2ee"));
  EXPECT_FALSE(codec::parse_version("256.1"));
  EXPECT_EQ(parse_rotation("counterclockwise"), codec::Rotation::kCounterclockwise);
  EXPECT_EQ(parse_rotation("cw"), codec::Rotation::kClockwise);
  EXPECT_FALSE(parse_rotation("left"));
}

// ---- Composition ---------------------------------------------------------------------------

TEST(SimSetup, ValvesFlagGivesSerialsOneToN) {
  CommandLine command_line;
  command_line.valve_count = 3;
  const auto setup = compose_setup(command_line, {});
  ASSERT_TRUE(setup) << setup.error().reason;
  ASSERT_EQ(setup->valves.size(), 3u);
  EXPECT_EQ(setup->valves[0].serial, 1u);
  EXPECT_EQ(setup->valves[2].serial, 3u);
  EXPECT_EQ(setup->valves[2].degrees_per_second, 90.0);
}

TEST(SimSetup, PrecedenceIsDefaultsThenFileDefaultsThenFlagsThenTheValvesEntry) {
  const auto file = parse_config(kExample, "example.yaml");
  ASSERT_TRUE(file);
  CommandLine command_line;
  command_line.serials = {123456, 123457, 5};
  command_line.settings.degrees_per_second = 150;  // beats the file's defaults (120)
  command_line.settings.volts = 13.0;              // loses to the file's entry for 123456
  const auto setup = compose_setup(command_line, *file);
  ASSERT_TRUE(setup) << setup.error().reason;
  ASSERT_EQ(setup->valves.size(), 3u);
  const auto& a = setup->valves[0];
  EXPECT_EQ(a.serial, 123456u);
  EXPECT_EQ(a.degrees_per_second, 150.0);
  EXPECT_EQ(a.volts, 12.6);
  EXPECT_TRUE(a.full_turn());
  const auto& b = setup->valves[1];
  EXPECT_EQ(b.opened_degrees, 90.0);
  EXPECT_EQ(b.volts, 13.0);
  const auto& c = setup->valves[2];
  EXPECT_EQ(c.serial, 5u);
  EXPECT_TRUE(c.full_turn());
  EXPECT_EQ(setup->errors.size(), 2u);
  ASSERT_EQ(setup->hotplug.size(), 1u);
  EXPECT_EQ(setup->hotplug[0].serial, 100u);
  EXPECT_EQ(setup->hotplug[0].degrees_per_second, 60.0);
  EXPECT_EQ(setup->base.degrees_per_second, 150.0);
}

TEST(SimSetup, TheFileAloneCanDefineTheBank) {
  const auto file = parse_config(kExample, "example.yaml");
  ASSERT_TRUE(file);
  const auto setup = compose_setup({}, *file);
  ASSERT_TRUE(setup) << setup.error().reason;
  EXPECT_EQ(setup->valves.size(), 2u);
}

TEST(SimSetup, CompositionMistakesAreRefused) {
  const auto reason = [](const CommandLine& command_line, const std::string& yaml) {
    const auto file = parse_config(yaml, "sim.yaml");
    EXPECT_TRUE(file);
    const auto setup = compose_setup(command_line, *file);
    EXPECT_FALSE(setup);
    return setup ? std::string() : setup.error().reason;
  };
  EXPECT_TRUE(contains(reason({}, ""), "no valves"));
  CommandLine too_many;
  too_many.valve_count = 33;
  EXPECT_TRUE(contains(reason(too_many, ""), "1 to 32"));
  CommandLine twice;
  twice.serials = {4, 4};
  EXPECT_TRUE(contains(reason(twice, ""), "TJV000004 is given twice"));
  CommandLine two;
  two.valve_count = 2;
  EXPECT_TRUE(contains(reason(two, "valves:\n  - serial: 9\n"), "TJV000009, which is not"));
  auto with_error = two;
  with_error.errors.push_back({9, codec::HighVoltageError{16, 15}});
  EXPECT_TRUE(contains(reason(with_error, ""), "not a simulated valve"));
  auto bad_flags = two;
  bad_flags.settings.opened_degrees = 350;
  EXPECT_TRUE(contains(reason(bad_flags, ""), "at most 340"));
  EXPECT_TRUE(contains(reason(two, "hotplug:\n  - serial: 2\n"), "already in the bank"));
}

}  // namespace
}  // namespace teejet::sim
