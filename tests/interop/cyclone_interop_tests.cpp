// A CycloneDDS ECU against the real teejet-gateway (--can sim:4, a separate process), both in a
// private network namespace on loopback (tests/netns/isolated, config/cyclonedds-loopback.xml):
// watching every topic, a late joiner included; every command kind to its final status; Clear
// Errors disposing the error instance; and the fail-safe stopping the valve of a Cyclone
// commander that dies. Issue 8: Fast DDS 2.9's encoding of the readers' type information made
// CycloneDDS refuse the gateway's command reader; no Cyclone ECU could move a valve.

#include <gtest/gtest.h>
#include <signal.h>

#include <cstdlib>
#include <fstream>
#include <map>
#include <memory>
#include <optional>

#include "cyclone_ecu.hpp"
#include "support/eventually.hpp"
#include "support/scratch_dir.hpp"
#include "support/subprocess.hpp"
#include "support/test_domain.hpp"

namespace teejet::interop {
namespace {

using namespace std::chrono_literals;
using teejet::testing::eventually;
using teejet::testing::ScratchDir;
using teejet::testing::Subprocess;
using teejet::testing::test_domain;

constexpr int kValves = 4;  // TJV000001..TJV000004 at 0xD8..0xDB
constexpr const char* kGatewayName = "interop-gateway";
// Discovery across vendors runs on unicast announcements (1 s apart): allow a few.
constexpr auto kDiscovery = 20s;

class CycloneInterop : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    ::setenv("CYCLONEDDS_URI", "file://" CYCLONE_CONFIG, 1);
    scratch_ = std::make_unique<ScratchDir>();
    const auto config = *scratch_ / "gateway.yaml";
    // Full-turn valves, so that a manual run never ends by itself; latched errors to watch and
    // to clear.
    std::ofstream(config) << "simulator:\n"
                             "  dps: 180\n"
                             "  opened_deg: 360\n"
                             "  errors: [\"TJV000003:high-voltage:16.2:15.5\",\n"
                             "           \"TJV000004:low-current:0.05:0.1\"]\n"
                             // Two places, without mechanics: moves go as sent.
                             "layout:\n"
                             "  locations:\n"
                             "    - {name: left-master, order: 1, role: master, serial: 4}\n"
                             "    - {name: section-01, order: 2, serial: 1}\n";
    gateway_ = std::make_unique<Subprocess>(std::vector<std::string>{
        GATEWAY_PATH, "--can", "sim:" + std::to_string(kValves), "--domain",
        std::to_string(test_domain()), "--name", kGatewayName, "--allow-baud-change", "--log-level",
        "warn", "-c", config.string()});
  }
  static void TearDownTestSuite() {
    gateway_->signal(SIGTERM);
    const auto finished = gateway_->wait(gateway_->elapsed() + 15s);
    EXPECT_EQ(finished.exit_code, 0) << finished.err;
    gateway_.reset();
    scratch_.reset();
  }

  // Statuses are TRANSIENT_LOCAL: every test's ECU has an origin of its own.
  CycloneInterop() : ecu_(test_domain()), origin_("cyclone-ecu-" + std::to_string(++ecus_)) {}

  // Writes a command with the next id once the gateway knows this ECU's status reader and
  // command writer (CommandChannel); the id.
  std::uint32_t send(teejet_ValveCommand command) {
    if (!channel_) {
      channel_.emplace(ecu_);
      EXPECT_TRUE(eventually([&] { return channel_->ready(); }, kDiscovery))
          << "the gateway never matched this CycloneDDS ECU's command writer";
    }
    command.command_id = ++next_id_;
    std::snprintf(command.origin, sizeof command.origin, "%s", origin_.c_str());
    EXPECT_EQ(dds_write(channel_->commands(), &command), DDS_RETCODE_OK);
    return command.command_id;
  }

  // The statuses of command `id` until a final one (or the deadline).
  std::vector<teejet_CommandStatus> follow(std::uint32_t id,
                                           std::chrono::milliseconds deadline = 15s) {
    std::vector<teejet_CommandStatus> mine;
    eventually(
        [&] {
          for (const auto& taken : take_all<teejet_CommandStatus>(channel_->statuses())) {
            if (taken.info.valid_data) statuses_seen_.push_back(taken.sample);
          }
          mine.clear();
          for (const auto& status : statuses_seen_) {
            if (status.command_id == id && status.origin == origin_) {
              mine.push_back(status);
            }
          }
          return !mine.empty() && mine.back().state != teejet_COMMAND_ACCEPTED;
        },
        deadline);
    return mine;
  }

  std::vector<teejet_CommandState> states_of(const teejet_ValveCommand& command) {
    std::vector<teejet_CommandState> states;
    for (const auto& status : follow(send(command))) states.push_back(status.state);
    return states;
  }

  static teejet_ValveCommand command(std::uint32_t serial, teejet_CommandKind kind) {
    teejet_ValveCommand c{};
    c.serial = serial;
    c.kind = kind;
    c.speed_percent = 100;
    c.direction = teejet_DIRECTION_OPEN;
    return c;
  }

  // The newest sample per serial that `reader` has delivered, accumulated in `seen`.
  template <class Sample>
  static std::map<std::uint32_t, Sample>& latest(dds_entity_t reader,
                                                 std::map<std::uint32_t, Sample>& seen) {
    for (const auto& taken : take_all<Sample>(reader)) {
      if (taken.info.valid_data) seen[taken.sample.serial] = taken.sample;
    }
    return seen;
  }

  CycloneEcu ecu_;
  const std::string origin_;
  std::optional<CommandChannel> channel_;
  std::vector<teejet_CommandStatus> statuses_seen_;
  std::uint32_t next_id_ = 0;

  static std::unique_ptr<ScratchDir> scratch_;
  static std::unique_ptr<Subprocess> gateway_;
  static inline int ecus_ = 0;
};

std::unique_ptr<ScratchDir> CycloneInterop::scratch_;
std::unique_ptr<Subprocess> CycloneInterop::gateway_;

const std::vector<teejet_CommandState> kDone{teejet_COMMAND_ACCEPTED, teejet_COMMAND_COMPLETED};

TEST_F(CycloneInterop, ALateJoinerSeesEveryValveAtOnce) {
  // Known to be up once an early reader has seen every valve; then a new participant joins.
  {
    CycloneEcu early(test_domain());
    const auto reader = early.state_reader(teejet_ValvePresence_desc, "teejet/valve/presence");
    std::map<std::uint32_t, teejet_ValvePresence> seen;
    ASSERT_TRUE(eventually([&] { return latest(reader, seen).size() == kValves; }, kDiscovery));
  }
  CycloneEcu late(test_domain());
  const auto reader = late.state_reader(teejet_ValvePresence_desc, "teejet/valve/presence");
  std::map<std::uint32_t, teejet_ValvePresence> seen;
  ASSERT_TRUE(eventually([&] { return latest(reader, seen).size() == kValves; }, kDiscovery))
      << seen.size() << " of " << kValves << " valves";
  for (std::uint32_t serial = 1; serial <= kValves; ++serial) {
    EXPECT_EQ(seen[serial].address, 0xD8 + serial - 1);
    EXPECT_TRUE(seen[serial].online);
    EXPECT_STREQ(seen[serial].gateway, kGatewayName);
  }
}

TEST_F(CycloneInterop, AnEcuResolvesALocationToItsSerialAndCommandsIt) {
  const auto locations = ecu_.state_reader(teejet_ValveLocation_desc, "teejet/valve/location");
  std::map<std::string, teejet_ValveLocation> places;
  const auto resolved = [&] {
    for (const auto& taken : take_all<teejet_ValveLocation>(locations)) {
      if (taken.info.valid_data) places[taken.sample.location] = taken.sample;
    }
    return places.contains("left-master") && places.at("left-master").state == teejet_LOCATION_OK;
  };
  ASSERT_TRUE(eventually(resolved, kDiscovery)) << places.size() << " places";
  const auto& master = places.at("left-master");
  EXPECT_STREQ(master.gateway, kGatewayName);
  EXPECT_EQ(master.role, teejet_ROLE_MASTER);
  EXPECT_EQ(master.order, 1u);
  ASSERT_TRUE(master.assigned);
  EXPECT_EQ(master.serial, 4u);
  EXPECT_FALSE(master.mechanics_known);

  auto move = command(master.serial, teejet_COMMAND_TARGET_DEGREES);
  move.degrees = 90.0f;
  EXPECT_EQ(states_of(move), kDone);
  const auto presence = ecu_.state_reader(teejet_ValvePresence_desc, "teejet/valve/presence");
  std::map<std::uint32_t, teejet_ValvePresence> seen;
  ASSERT_TRUE(eventually(
      [&] {
        latest(presence, seen);
        return seen.contains(4) && seen.contains(2);
      },
      kDiscovery));
  EXPECT_STREQ(seen[4].location, "left-master");
  EXPECT_STREQ(seen[2].location, "");
}

TEST_F(CycloneInterop, EveryTelemetryTopicArrivesInEngineeringUnits) {
  const auto version = ecu_.state_reader(teejet_ValveVersion_desc, "teejet/valve/version");
  const auto position = ecu_.state_reader(teejet_ValvePosition_desc, "teejet/valve/position");
  const auto temperature =
      ecu_.state_reader(teejet_ValveTemperature_desc, "teejet/valve/temperature");
  const auto voltage = ecu_.state_reader(teejet_ValveVoltage_desc, "teejet/valve/voltage");
  const auto current = ecu_.state_reader(teejet_ValveCurrent_desc, "teejet/valve/current");
  const auto dps =
      ecu_.state_reader(teejet_ValveDegreesPerSecond_desc, "teejet/valve/degrees_per_second");
  const auto speed =
      ecu_.state_reader(teejet_ValveSpeedDirection_desc, "teejet/valve/speed_direction");
  const auto run_time = ecu_.state_reader(teejet_ValveRunTime_desc, "teejet/valve/run_time");
  const auto cycles = ecu_.state_reader(teejet_ValveCycleCounts_desc, "teejet/valve/cycle_counts");
  const auto baud = ecu_.state_reader(teejet_ValveBaudRate_desc, "teejet/valve/baud_rate");
  const auto errors = ecu_.state_reader(teejet_ValveError_desc, "teejet/valve/error");
  const auto status = ecu_.state_reader(teejet_GatewayStatus_desc, "teejet/gateway/status");
  // The baud rate is only ever an answer.
  EXPECT_EQ(states_of(command(2, teejet_COMMAND_REQUEST_BAUD_RATE)), kDone);

  std::map<std::uint32_t, teejet_ValveVersion> versions;
  std::map<std::uint32_t, teejet_ValvePosition> positions;
  std::map<std::uint32_t, teejet_ValveTemperature> temperatures;
  std::map<std::uint32_t, teejet_ValveVoltage> voltages;
  std::map<std::uint32_t, teejet_ValveCurrent> currents;
  std::map<std::uint32_t, teejet_ValveDegreesPerSecond> speeds;
  std::map<std::uint32_t, teejet_ValveSpeedDirection> directions;
  std::map<std::uint32_t, teejet_ValveRunTime> run_times;
  std::map<std::uint32_t, teejet_ValveCycleCounts> cycle_counts;
  std::map<std::uint32_t, teejet_ValveBaudRate> baud_rates;
  ASSERT_TRUE(eventually(
      [&] {
        return latest(version, versions).size() == kValves &&
               latest(position, positions).size() == kValves &&
               latest(temperature, temperatures).size() == kValves &&
               latest(voltage, voltages).size() == kValves &&
               latest(current, currents).size() == kValves &&
               latest(dps, speeds).size() == kValves &&
               latest(speed, directions).size() == kValves &&
               latest(run_time, run_times).size() == kValves &&
               latest(cycles, cycle_counts).size() == kValves &&
               latest(baud, baud_rates).contains(2);
      },
      kDiscovery));
  // The simulator's values (gateway/sim): 12.0 V, 25 °C, 180 dps as configured, release 1.00.
  EXPECT_FLOAT_EQ(voltages[1].volts, 12.0f);
  EXPECT_EQ(temperatures[1].valve_c, 25);
  EXPECT_EQ(temperatures[1].sensor_c, 25);
  EXPECT_EQ(speeds[1].dps, 180);
  EXPECT_EQ(versions[1].application.major, 1);
  EXPECT_EQ(versions[1].application.minor, 0);
  EXPECT_EQ(directions[1].opening_direction, teejet_ROTATION_CLOCKWISE);
  EXPECT_EQ(baud_rates[2].bit_rate, 250000u);
  EXPECT_GT(positions[1].received_ns, 1'700'000'000'000'000'000u);

  // Latched errors: one instance per valve and kind.
  std::map<std::uint32_t, teejet_ValveError> latched;
  ASSERT_TRUE(eventually([&] { return latest(errors, latched).contains(3); }, kDiscovery));
  EXPECT_EQ(latched[3].kind, teejet_ERROR_HIGH_VOLTAGE);
  EXPECT_FLOAT_EQ(latched[3].value, 16.2f);
  EXPECT_FLOAT_EQ(latched[3].limit, 15.5f);

  // Gateway status, keyed by the gateway's name: the first may predate the valves.
  teejet_GatewayStatus health{};
  ASSERT_TRUE(eventually(
      [&] {
        for (const auto& taken : take_all<teejet_GatewayStatus>(status)) {
          if (taken.info.valid_data) health = taken.sample;
        }
        return health.valves_online == kValves;
      },
      kDiscovery));
  EXPECT_STREQ(health.gateway, kGatewayName);
  EXPECT_STREQ(health.can_interface, "sim:4");
  EXPECT_EQ(health.bus_state, teejet_BUS_ERROR_ACTIVE);
  EXPECT_EQ(health.valves_known, static_cast<std::uint32_t>(kValves));
  EXPECT_GT(health.frames_in, 0u);
}

TEST_F(CycloneInterop, EveryCommandKindReachesItsFinalState) {
  const auto position = ecu_.state_reader(teejet_ValvePosition_desc, "teejet/valve/position");
  auto move = command(1, teejet_COMMAND_TARGET_DEGREES);
  move.degrees = 45.0f;
  EXPECT_EQ(states_of(move), kDone);
  std::map<std::uint32_t, teejet_ValvePosition> positions;
  EXPECT_TRUE(eventually(
      [&] {
        latest(position, positions);
        return positions.contains(1) && std::abs(positions[1].degrees - 45.0f) <= 1.0f;
      },
      5s))
      << "the position never showed the move";

  auto relative = command(1, teejet_COMMAND_DEGREES_FROM_POSITION);
  relative.direction = teejet_DIRECTION_CLOSE;
  relative.degrees = 20.0f;
  EXPECT_EQ(states_of(relative), kDone);
  auto jog = command(1, teejet_COMMAND_MILLISECONDS_TO_RUN);
  jog.milliseconds = 200;
  EXPECT_EQ(states_of(jog), kDone);
  EXPECT_EQ(states_of(command(1, teejet_COMMAND_STOP)), kDone);
  EXPECT_EQ(states_of(command(1, teejet_COMMAND_CLEAR_ERRORS)), kDone);
  for (const auto telemetry :
       {teejet_TELEMETRY_VERSION, teejet_TELEMETRY_POSITION, teejet_TELEMETRY_TEMPERATURE,
        teejet_TELEMETRY_VOLTAGE, teejet_TELEMETRY_CURRENT, teejet_TELEMETRY_DEGREES_PER_SECOND,
        teejet_TELEMETRY_SPEED_DIRECTION, teejet_TELEMETRY_RUN_TIME,
        teejet_TELEMETRY_CYCLE_COUNTS}) {
    auto request = command(1, teejet_COMMAND_REQUEST);
    request.telemetry = telemetry;
    request.resend_tenths = telemetry == teejet_TELEMETRY_VERSION ? 0 : 10;
    EXPECT_EQ(states_of(request), kDone) << "telemetry " << telemetry;
  }
  EXPECT_EQ(states_of(command(1, teejet_COMMAND_REQUEST_BAUD_RATE)), kDone);
  auto baud = command(1, teejet_COMMAND_SET_BAUD_RATE);
  baud.bit_rate = 500000;
  EXPECT_EQ(states_of(baud), kDone);

  // Manual has no observable end: accepted, then superseded by the next command.
  auto manual = command(1, teejet_COMMAND_MANUAL);
  manual.speed_percent = 20;
  const auto manual_id = send(manual);
  EXPECT_EQ(states_of(command(1, teejet_COMMAND_STOP)), kDone);
  const auto manual_states = follow(manual_id);
  ASSERT_EQ(manual_states.size(), 2u);
  EXPECT_EQ(manual_states[1].state, teejet_COMMAND_SUPERSEDED);

  // Out of the sheet's range: rejected with the reason, never sent.
  auto too_far = command(1, teejet_COMMAND_TARGET_DEGREES);
  too_far.degrees = 400.0f;
  const auto rejected = follow(send(too_far));
  ASSERT_EQ(rejected.size(), 1u);
  EXPECT_EQ(rejected[0].state, teejet_COMMAND_REJECTED);
  EXPECT_STREQ(rejected[0].reason, "target_degrees: degrees 400 is outside 0 to 359.9");
}

TEST_F(CycloneInterop, ClearErrorsDisposesTheErrorInstance) {
  const auto errors = ecu_.state_reader(teejet_ValveError_desc, "teejet/valve/error");
  std::vector<Taken<teejet_ValveError>> history;
  const auto has = [&](auto predicate) {
    for (const auto& taken : take_all<teejet_ValveError>(errors)) history.push_back(taken);
    return std::any_of(history.begin(), history.end(), predicate);
  };
  ASSERT_TRUE(eventually(
      [&] { return has([](const auto& t) { return t.info.valid_data && t.sample.serial == 4; }); },
      kDiscovery));
  EXPECT_EQ(states_of(command(4, teejet_COMMAND_CLEAR_ERRORS)), kDone);
  EXPECT_TRUE(eventually(
      [&] {
        return has([](const auto& t) {
          return t.sample.serial == 4 && t.sample.kind == teejet_ERROR_LOW_CURRENT &&
                 t.info.instance_state == DDS_IST_NOT_ALIVE_DISPOSED;
        });
      },
      10s))
      << "the error instance of TJV000004 was never disposed";
}

TEST_F(CycloneInterop, TheFailSafeStopsTheValveOfACycloneCommanderThatDies) {
  // This test's own command writer stays alive meanwhile: Fast DDS 2.9 then misses the dead
  // writer's liveliness (docs/gateway.md), and the participant's 3 s lease is what stops it.
  CommandChannel channel(ecu_);
  ASSERT_TRUE(eventually([&] { return channel.ready(); }, kDiscovery));
  const auto statuses = channel.statuses();
  const auto position = ecu_.state_reader(teejet_ValvePosition_desc, "teejet/valve/position");
  Subprocess commander({CYCLONE_COMMANDER_PATH, std::to_string(test_domain()), "2"});
  ASSERT_TRUE(commander.wait_for_stdout("sent", kDiscovery)) << commander.err();

  std::vector<teejet_CommandStatus> seen;
  const auto states = [&] {
    for (const auto& taken : take_all<teejet_CommandStatus>(statuses)) {
      if (taken.info.valid_data && std::string(taken.sample.origin) == "cyclone-commander") {
        seen.push_back(taken.sample);
      }
    }
    return seen.size();
  };
  ASSERT_TRUE(eventually([&] { return states() >= 1; }, 10s));
  ASSERT_EQ(seen[0].state, teejet_COMMAND_ACCEPTED);
  std::map<std::uint32_t, teejet_ValvePosition> positions;
  const auto moved_from = [&] {
    latest(position, positions);
    return positions.contains(2) ? positions[2].degrees : -1.0f;
  };
  const float before = moved_from();
  ASSERT_TRUE(eventually([&] { return moved_from() != before; }, 5s)) << "the valve never ran";

  commander.signal(SIGKILL);
  const auto killed_at = std::chrono::steady_clock::now();
  ASSERT_TRUE(eventually([&] { return states() >= 2; }, 10s)) << "no fail-safe after the kill";
  EXPECT_EQ(seen[1].state, teejet_COMMAND_SUPERSEDED);
  EXPECT_STREQ(seen[1].reason, "fail-safe: the commanding writer was lost");
  std::printf("fail-safe stopped the Cyclone commander's valve %lld ms after SIGKILL\n",
              static_cast<long long>(std::chrono::duration_cast<std::chrono::milliseconds>(
                                         std::chrono::steady_clock::now() - killed_at)
                                         .count()));
  // Stopped: five reports in a row at one position (running at 10 % of 180 deg/s it moved
  // 1.8 deg between two reports, 100 ms apart).
  float held = -1.0f;
  int in_a_row = 0;
  EXPECT_TRUE(eventually(
      [&] {
        for (const auto& taken : take_all<teejet_ValvePosition>(position)) {
          if (!taken.info.valid_data || taken.sample.serial != 2) continue;
          in_a_row = taken.sample.degrees == held ? in_a_row + 1 : 1;
          held = taken.sample.degrees;
        }
        return in_a_row >= 5;
      },
      5s))
      << "TJV000002 still moves after the fail-safe";
  commander.wait(commander.elapsed() + 5s);
}

}  // namespace
}  // namespace teejet::interop
