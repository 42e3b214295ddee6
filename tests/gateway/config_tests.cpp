#include <gtest/gtest.h>

#include <fstream>

#include "support/eventually.hpp"
#include "support/scratch_dir.hpp"
#include "teejet/gateway/bus_backend.hpp"
#include "teejet/gateway/config.hpp"

namespace teejet::gateway {
namespace {

using namespace std::chrono_literals;

GatewayConfig parse(const std::string& yaml) {
  auto config = parse_config(yaml, "test.yaml", GatewayConfig{});
  EXPECT_TRUE(config) << (config ? "" : config.error().reason);
  return config ? *config : GatewayConfig{};
}

std::string error_of(const std::string& yaml) {
  auto config = parse_config(yaml, "test.yaml", GatewayConfig{});
  EXPECT_FALSE(config);
  return config ? "" : config.error().reason;
}

TEST(GatewayConfig, EmptyFileKeepsTheDefaults) {
  const auto config = parse("");
  EXPECT_EQ(config.bridge.offline_after, 3s);
  EXPECT_TRUE(config.stop_valves_on_exit);
  EXPECT_FALSE(config.bridge.allow_baud_change);
  EXPECT_EQ(config.receive_coalesce, 4ms);
  EXPECT_EQ(config.receive_coalesce_above, 3000u);  // a full 500 kbit/s bus only
  EXPECT_EQ(config.bridge.poll.size(), 9u);
}

TEST(GatewayConfig, TheShippedExampleParsesAndMatchesTheDefaults) {
  std::ifstream file(EXAMPLE_CONFIG);
  std::stringstream text;
  text << file.rdbuf();
  const auto config = parse(text.str());
  const GatewayConfig defaults;
  EXPECT_EQ(config.can, "can0");
  EXPECT_EQ(config.bridge.offline_after, defaults.bridge.offline_after);
  EXPECT_EQ(config.bridge.poll, bridge::default_poll_schedule());
  EXPECT_EQ(config.bridge.reply_timeout, defaults.bridge.reply_timeout);
  EXPECT_EQ(config.receive_coalesce, defaults.receive_coalesce);
  EXPECT_EQ(config.receive_coalesce_above, defaults.receive_coalesce_above);
  const auto& layout = config.bridge.layout;
  EXPECT_EQ(layout.default_mechanics(), (layout::Mechanics{0, 90}));
  ASSERT_TRUE(layout.find("left-master"));
  EXPECT_TRUE(layout.mechanics_of_serial(3)->full_turn());
  EXPECT_EQ(config.layout_file, "");
  EXPECT_EQ(config.bridge.isobus.claim, defaults.bridge.isobus.claim);
  EXPECT_EQ(config.bridge.isobus.name, defaults.bridge.isobus.name);
}

TEST(GatewayConfig, TheIsobusNameIsGivenFieldByFieldWithinEachFieldsRange) {
  EXPECT_TRUE(parse("").bridge.isobus.claim) << "claiming is on unless turned off";
  EXPECT_EQ(isobus::to_value(parse("").bridge.isobus.name), 0x2008800000000000ULL);
  const auto config = parse(R"(
isobus:
  claim: false
  identity_number: 2097151
  manufacturer_code: 2047
  ecu_instance: 7
  function_instance: 31
  function: 129
  device_class: 127
  device_class_instance: 15
  industry_group: 7
)");
  EXPECT_FALSE(config.bridge.isobus.claim);
  EXPECT_EQ(isobus::to_value(config.bridge.isobus.name), 0x7FFE81FFFFFFFFFFULL);
  EXPECT_EQ(error_of("isobus:\n  identity_number: 2097152\n"),
            "test.yaml:2: isobus.identity_number: 2097152 is not a whole number from 0 to 2097151");
  EXPECT_EQ(error_of("isobus:\n  industry_group: -1\n"),
            "test.yaml:2: isobus.industry_group: -1 is not a whole number from 0 to 7");
  EXPECT_EQ(error_of("isobus:\n  arbitrary_address_capable: 1\n"),
            "test.yaml:2: isobus.arbitrary_address_capable: the gateway's address is the sheet's "
            "0xD5, never another: its NAME is not arbitrary-address capable");
  EXPECT_EQ(error_of("isobus:\n  claim: maybe\n"),
            "test.yaml:2: isobus.claim: 'maybe' is neither true nor false");
}

TEST(GatewayConfig, ALayoutFileIsReadFromBesideTheConfigurationThatNamesIt) {
  teejet::testing::ScratchDir dir;
  std::ofstream(dir / "boom.yaml") << "locations:\n  - {name: section-01, order: 1, serial: 7}\n";
  auto config =
      parse_config("layout_file: boom.yaml\n", (dir / "gateway.yaml").string(), GatewayConfig{});
  ASSERT_TRUE(config) << config.error().reason;
  EXPECT_EQ(config->layout_file, (dir / "boom.yaml").string());
  ASSERT_TRUE(read_layout_file(*config));
  ASSERT_NE(config->bridge.layout.find_serial(7), nullptr);
  EXPECT_EQ(config->bridge.layout.find_serial(7)->name, "section-01");
}

TEST(GatewayConfig, AMistakeInTheLayoutFileNamesThatFileAndLine) {
  teejet::testing::ScratchDir dir;
  const auto path = (dir / "boom.yaml").string();
  std::ofstream(path) << "locations:\n  - {name: section-01, order: 1}\n  - {name: section-01, "
                         "order: 2}\n";
  GatewayConfig config;
  config.layout_file = path;
  const auto read = read_layout_file(config);
  ASSERT_FALSE(read);
  EXPECT_EQ(read.error().reason, path + ":3: layout.section-01.name: is given twice");
  config.layout_file = (dir / "missing.yaml").string();
  EXPECT_EQ(read_layout_file(config).error().reason,
            "cannot read config file '" + config.layout_file + "'");
}

TEST(GatewayConfig, ALayoutInTheConfigurationAndInAFileIsRefused) {
  auto config = parse("layout: {locations: [{name: section-01, order: 1}]}\n");
  EXPECT_TRUE(config.layout_in_config);
  config.layout_file = "boom.yaml";  // --layout boom.yaml
  EXPECT_EQ(read_layout_file(config).error().reason,
            "the layout is given twice: in the configuration (layout:) and as boom.yaml; give one "
            "or the other");
}

TEST(GatewayConfig, EveryKeyIsRead) {
  const auto config = parse(R"(
gateway: {name: boom-left, can: vcan0, domain: 7, offline_after_s: 1.5, stop_valves_on_exit: false,
          on_commander_lost: ignore, allow_baud_change: true, receive_coalesce_us: 2000,
          receive_coalesce_above_fps: 0}
commands: {completion_tolerance_deg: 0.5, reply_timeout_s: 1, move_margin_s: 2, assumed_dps: 45}
simulator: {first_serial: TJV000101, dps: 30, closed_deg: 10, opened_deg: 80}
)");
  EXPECT_EQ(config.bridge.gateway_name, "boom-left");
  EXPECT_EQ(config.can, "vcan0");
  EXPECT_EQ(config.domain, 7);
  EXPECT_EQ(config.bridge.offline_after, 1500ms);
  EXPECT_FALSE(config.stop_valves_on_exit);
  EXPECT_EQ(config.on_commander_lost, OnCommanderLost::kIgnore);
  EXPECT_TRUE(config.bridge.allow_baud_change);
  EXPECT_EQ(config.receive_coalesce, 2ms);
  EXPECT_EQ(config.receive_coalesce_above, 0u);
  EXPECT_EQ(config.bridge.completion_tolerance_degrees, 0.5);
  EXPECT_EQ(config.bridge.reply_timeout, 1s);
  EXPECT_EQ(config.bridge.move_margin, 2s);
  EXPECT_EQ(config.bridge.assumed_dps, 45u);
  EXPECT_EQ(config.sim_first_serial, 101u);
  EXPECT_EQ(config.sim_degrees_per_second, 30.0);
  EXPECT_EQ(config.sim_opened_degrees, 80.0);
}

TEST(GatewayConfig, PollEntriesChangeOnlyWhatTheyName) {
  const auto config = parse("poll: {position: 5, run_time: off, version: off}");
  const std::vector<codec::ToValveMessage> expected{
      codec::RequestPosition{5},          codec::RequestTemperature{10},
      codec::RequestVoltage{10},          codec::RequestCurrent{10},
      codec::RequestDegreesPerSecond{10}, codec::RequestSpeedDirection{10},
      codec::RequestCycleCounts{50}};
  EXPECT_EQ(config.bridge.poll, expected);
  EXPECT_EQ(parse("poll: {temperature: once}").bridge.poll.at(2),
            codec::ToValveMessage{codec::RequestTemperature{0}});
}

// Found by fuzz_gateway_config: these became durations of 0 ns, so every request timed out at
// once and every valve was offline as soon as it was seen.
TEST(GatewayConfig, DurationsShorterThanOneNanosecondAreRefused) {
  EXPECT_EQ(error_of("gateway: {offline_after_s: 1e-10}"),
            "test.yaml:1: gateway.offline_after_s: 1e-10 s is shorter than 1 ns");
  EXPECT_EQ(error_of("commands:\n  reply_timeout_s: 0.0000000001\n"),
            "test.yaml:2: commands.reply_timeout_s: 0.0000000001 s is shorter than 1 ns");
  EXPECT_EQ(parse("commands: {move_margin_s: 1e-9}").bridge.move_margin, 1ns);
}

TEST(GatewayConfig, MistakesAreNamedWithTheirLineAndKey) {
  EXPECT_EQ(
      error_of("gateway:\n  nmae: x\n"),
      "test.yaml:2: gateway: unknown key 'nmae' (name, can, domain, profile, "
      "offline_after_s, stop_valves_on_exit, on_commander_lost, allow_baud_change, "
      "receive_coalesce_us, receive_coalesce_above_fps, reject_unknown_serials, record_frames)");
  EXPECT_EQ(error_of("polling: {}\n"),
            "test.yaml:1: the file: unknown key 'polling' (gateway, commands, poll, layout, "
            "layout_file, simulator, isobus)");
  EXPECT_EQ(error_of("poll:\n  position: 300\n"),
            "test.yaml:2: poll.position: 300 is not a whole number from 0 to 255");
  EXPECT_EQ(error_of("gateway: {on_commander_lost: panic}"),
            "test.yaml:1: gateway.on_commander_lost: 'panic' is not 'stop' or 'ignore'");
  EXPECT_EQ(error_of("gateway: {receive_coalesce_us: 20000}"),
            "test.yaml:1: gateway.receive_coalesce_us: 20000 is not a whole number from 0 to "
            "10000");
  EXPECT_EQ(error_of("gateway: {receive_coalesce_above_fps: -1}"),
            "test.yaml:1: gateway.receive_coalesce_above_fps: -1 is not a whole number from 0 to "
            "10000");
  EXPECT_EQ(error_of("gateway: {offline_after_s: 0}"),
            "test.yaml:1: gateway.offline_after_s: 0 s is outside the allowed range: more than 0, "
            "at most 3600 s");
  EXPECT_EQ(error_of("layout: {locations: [{name: a, order: 1, serial: TJV12x}]}"),
            "test.yaml:1: layout.a.serial: serial 'TJV12x' is not TJV followed by digits, nor "
            "digits alone");
  EXPECT_EQ(error_of("layout: {default: {opened_deg: 350}}"),
            "test.yaml:1: layout.default.opened_deg: 350 is neither 360 (full turn) nor at most "
            "340 (the sheet)");
  EXPECT_EQ(error_of("layout: {default: {closed_deg: 90}}"),
            "test.yaml:1: layout.default.closed_deg: 90 must be at least 0 and below "
            "opened_degrees 90");
  EXPECT_EQ(error_of("valves: {default: {opened_deg: 90}}"),
            "test.yaml:1: valves: the mechanics of each valve are part of layout: now "
            "(docs/layout.md): valves.default is layout.default, and a valve's go with its "
            "location");
  EXPECT_EQ(error_of("layout: {}\nlayout_file: boom.yaml\n"),
            "test.yaml:2: layout_file: the layout is in this file already (layout:); give one or "
            "the other");
  EXPECT_EQ(error_of("gateway: {domain: 1}\ngateway: {domain: 2}\n"),
            "test.yaml:2: the file: 'gateway' is given twice");
  EXPECT_NE(error_of("gateway: [unclosed").find("test.yaml: "), std::string::npos);
}

// Values that parsed before and then broke the gateway at run time (issue 7, bug 3): a zero
// assumed speed divided by zero when a move's deadline was computed, a negative tolerance made
// every move time out. Every number now has its range.
TEST(GatewayConfig, EveryNumberHasItsRange) {
  EXPECT_EQ(error_of("commands: {assumed_dps: 0}"),
            "test.yaml:1: commands.assumed_dps: 0 is not a whole number from 1 to 359");
  EXPECT_EQ(error_of("commands: {completion_tolerance_deg: -1}"),
            "test.yaml:1: commands.completion_tolerance_deg: -1 is outside 0 to 45");
  EXPECT_EQ(error_of("commands: {completion_tolerance_deg: .nan}"),
            "test.yaml:1: commands.completion_tolerance_deg: '.nan' is not a number");
  EXPECT_EQ(
      error_of("commands: {move_margin_s: 1e30}"),
      "test.yaml:1: commands.move_margin_s: 1e30 s is outside the allowed range: more than 0, "
      "at most 3600 s");
  EXPECT_EQ(error_of("commands: {reply_timeout_s: -2}"),
            "test.yaml:1: commands.reply_timeout_s: -2 s is outside the allowed range: more than "
            "0, at most 3600 s");
  EXPECT_EQ(error_of("gateway: {offline_after_s: .inf}"),
            "test.yaml:1: gateway.offline_after_s: '.inf' is not a number");
  EXPECT_EQ(error_of("gateway: {domain: -1}"),
            "test.yaml:1: gateway.domain: -1 is not a whole number from 0 to 232");
  EXPECT_EQ(error_of("simulator: {dps: 0}"), "test.yaml:1: simulator.dps: 0 is outside 1 to 359");
  EXPECT_EQ(error_of("layout: {default: {closed_deg: -10}}"),
            "test.yaml:1: layout.default.closed_deg: -10 is outside 0 to 359.9");
  // The edges of each range are accepted.
  const auto edges = parse(
      "commands: {assumed_dps: 359, completion_tolerance_deg: 0, move_margin_s: 3600}\n"
      "gateway: {domain: 232, offline_after_s: 0.001}");
  EXPECT_EQ(edges.bridge.assumed_dps, 359u);
  EXPECT_EQ(edges.bridge.completion_tolerance_degrees, 0.0);
  EXPECT_EQ(edges.bridge.move_margin, 3600s);
  EXPECT_EQ(edges.domain, 232);
  EXPECT_EQ(edges.bridge.offline_after, 1ms);
}

TEST(GatewayConfig, SimulatedValvesMayStartWithLatchedErrors) {
  const auto config = parse(
      "simulator: {errors: [\"TJV000002:high-voltage:16.2:15.5\", \"3:min-dps:20:30:close\"]}");
  ASSERT_EQ(config.sim_errors.size(), 2u);
  EXPECT_EQ(config.sim_errors[0], (sim::SerialError{2, codec::HighVoltageError{16.2, 15.5}}));
  EXPECT_EQ(
      config.sim_errors[1].error,
      (sim::InjectedError{codec::MinDegreesPerSecondError{20, 30, codec::Direction::kClose}}));
  EXPECT_EQ(error_of("simulator: {errors: [\"2:sparks:1:2\"]}"),
            "test.yaml:1: simulator.errors: '2:sparks:1:2': unknown error kind 'sparks' "
            "(high_voltage, low_voltage, high_current, low_current, high_temperature, "
            "min_degrees_per_second)");
  EXPECT_EQ(error_of("simulator: {errors: TJV000002}"),
            "test.yaml:1: simulator.errors: expected a list of errors "
            "(SERIAL:KIND:VALUE:LIMIT[:DIRECTION])");
}

TEST(GatewayConfig, SimulatorChurnIsOffByDefaultAndItsKeysHaveRanges) {
  const GatewayConfig defaults;
  EXPECT_EQ(defaults.sim_churn_period, 0s);
  EXPECT_EQ(defaults.sim_churn_off_time(), 4s);  // offline_after_s 3 + 1
  const auto config = parse(
      "gateway: {offline_after_s: 2}\nsimulator: {churn_period_s: 3.5, churn_seed: 4294967295}");
  EXPECT_EQ(config.sim_churn_period, 3500ms);
  EXPECT_EQ(config.sim_churn_seed, 4294967295u);
  EXPECT_EQ(config.sim_churn_off_time(), 3s);
  EXPECT_EQ(parse("simulator: {churn_period_s: 0}").sim_churn_period, 0s);
  EXPECT_EQ(error_of("simulator: {churn_period_s: 4}"),
            "test.yaml:1: simulator.churn_period_s: must be 0 (off) or longer than a churned "
            "valve stays off, gateway.offline_after_s + 1 s = 4 s");
  EXPECT_EQ(error_of("simulator: {churn_period_s: -1}"),
            "test.yaml:1: simulator.churn_period_s: -1 is outside 0 to 3600");
  EXPECT_EQ(error_of("simulator: {churn_period_s: .inf}"),
            "test.yaml:1: simulator.churn_period_s: '.inf' is not a number");
  EXPECT_EQ(error_of("simulator: {churn_seed: -1}"),
            "test.yaml:1: simulator.churn_seed: -1 is not a whole number from 0 to 4294967295");
  EXPECT_EQ(error_of("simulator: {churn_seed: 4294967296}"),
            "test.yaml:1: simulator.churn_seed: 4294967296 is not a whole number from 0 to "
            "4294967295");
}

TEST(GatewayConfig, TheChurnReachesTheEmbeddedSimulator) {
  auto config = parse("gateway: {offline_after_s: 0.1}\nsimulator: {churn_period_s: 1.2}");
  config.can = "sim:4";
  auto backend = make_bus_backend(config);
  ASSERT_TRUE(backend) << backend.error().reason;
  ASSERT_TRUE(backend->simulator->start());
  // The first valve goes off 1.2 s after power-up and is back 1.1 s later.
  ASSERT_TRUE(teejet::testing::eventually(
      [&] { return backend->simulator->assignments().size() == 3; }, 5s));
  EXPECT_EQ(backend->simulator->churn_count(), 1u);
  ASSERT_TRUE(teejet::testing::eventually(
      [&] { return backend->simulator->assignments().size() == 4; }, 5s));
  backend->simulator->stop();
}

TEST(GatewayConfig, SimulatedValvesMayHaveChosenSerials) {
  auto config = parse("simulator: {serials: [TJV000107, 102, TJV000250]}");
  EXPECT_EQ(config.sim_serials, (std::vector<std::uint32_t>{107, 102, 250}));
  config.can = "sim:3";
  auto backend = make_bus_backend(config);
  ASSERT_TRUE(backend) << backend.error().reason;
  ASSERT_TRUE(backend->simulator->start());
  EXPECT_EQ(backend->simulator->assignments(),
            (std::vector<sim::Assignment>{{102, 0xD8}, {107, 0xD9}, {250, 0xDA}}));
  backend->simulator->stop();
  config.can = "sim:4";
  EXPECT_EQ(make_bus_backend(config).error().reason,
            "--can sim:4: simulator.serials lists 3 serials for 4 valves");
  EXPECT_EQ(error_of("simulator: {serials: [1, 2, 1]}"),
            "test.yaml:1: simulator.serials: TJV000001 is listed twice");
  EXPECT_EQ(error_of("simulator:\n  first_serial: 5\n  serials: [1]"),
            "test.yaml:3: simulator.serials: give first_serial or serials, not both");
}

TEST(GatewayConfig, SimulatedValveCount) {
  EXPECT_EQ(*simulated_valve_count("can0"), std::nullopt);
  EXPECT_EQ(*simulated_valve_count("sim:4"), 4);
  EXPECT_EQ(*simulated_valve_count("sim:32"), 32);
  EXPECT_EQ(simulated_valve_count("sim:33").error().reason,
            "--can sim:33: sim:N takes 1 to 32 valves (one per address 0xD8..0xF7)");
  EXPECT_FALSE(simulated_valve_count("sim:"));
  EXPECT_FALSE(simulated_valve_count("sim:0"));
  EXPECT_FALSE(simulated_valve_count("sim:4x"));
}

// Issue 10, item 3: what a flooding or mistaken commander meets.
TEST(GatewayConfig, CommandRateLimitAndUnknownSerials) {
  const GatewayConfig defaults;
  EXPECT_EQ(defaults.bridge.command_rate_per_valve, 100.0);
  EXPECT_EQ(defaults.bridge.command_burst_per_valve, 20u);
  EXPECT_FALSE(defaults.bridge.reject_unknown_serials);
  const auto config = parse(
      "gateway: {reject_unknown_serials: true}\n"
      "commands: {rate_per_valve: 0, burst_per_valve: 256}\n");
  EXPECT_TRUE(config.bridge.reject_unknown_serials);
  EXPECT_EQ(config.bridge.command_rate_per_valve, 0.0);
  EXPECT_EQ(config.bridge.command_burst_per_valve, 256u);
  EXPECT_EQ(error_of("commands: {rate_per_valve: -1}"),
            "test.yaml:1: commands.rate_per_valve: -1 is outside 0 to 10000");
  EXPECT_EQ(error_of("commands: {burst_per_valve: 0}"),
            "test.yaml:1: commands.burst_per_valve: 0 is not a whole number from 1 to 256");
  EXPECT_EQ(error_of("gateway: {reject_unknown_serials: maybe}"),
            "test.yaml:1: gateway.reject_unknown_serials: 'maybe' is neither true nor false");
}

}  // namespace
}  // namespace teejet::gateway
