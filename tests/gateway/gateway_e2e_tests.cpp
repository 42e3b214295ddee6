// The whole gateway (bus, bridge, DDS) with simulated valves on a virtual bus, watched and
// commanded by independent DDS participants, as an ECU would. Runs inside a private network
// namespace (tests/netns/isolated).

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <map>

#include "gateway.hpp"
#include "support/eventually.hpp"
#include "support/subprocess.hpp"
#include "teejet/dds/participant.hpp"
#include "teejet/dds/topics.hpp"
#include "teejet/valvePubSubTypes.h"

namespace teejet::gateway {
namespace {

using namespace std::chrono_literals;
using eprosima::fastdds::dds::DataReader;
using eprosima::fastdds::dds::DataWriter;
using eprosima::fastdds::dds::SampleInfo;
using ReturnCode = eprosima::fastrtps::types::ReturnCode_t;

using teejet::testing::eventually;

int domain_for_this_run() { return 100 + static_cast<int>(::getpid() % 100); }

GatewayConfig sim_config(const std::string& name, int valves, std::uint32_t first_serial = 1) {
  GatewayConfig config;
  config.can = "sim:" + std::to_string(valves);
  config.domain = domain_for_this_run();
  config.bridge.gateway_name = name;
  config.sim_first_serial = first_serial;
  config.sim_degrees_per_second = 180;  // quick moves keep the suite short
  config.bridge.offline_after = 1500ms;
  config.bridge.move_margin = 1s;
  config.bridge.default_limits = bridge::ValveLimits{0, 90};
  return config;
}

// An ECU on the same domain: reads every topic it is asked about, writes commands.
class Ecu {
 public:
  Ecu() : participant_({.domain = domain_for_this_run(), .name = "test-ecu"}) {
    commands_ =
        participant_.writer(participant_.topic<ValveCommandPubSubType>(dds::topics::kCommand),
                            dds::topics::command_writer_qos());
    statuses_ = participant_.reader(
        participant_.topic<CommandStatusPubSubType>(dds::topics::kCommandStatus),
        dds::topics::status_reader_qos());
  }

  template <class PubSubType>
  DataReader* state_reader(const char* topic) {
    return participant_.reader(participant_.topic<PubSubType>(topic),
                               dds::topics::state_reader_qos());
  }

  // Writes once at least one gateway listens; returns the command id used.
  std::uint32_t send(ValveCommand command) {
    command.command_id(++next_id_);
    command.origin("e2e-test");
    EXPECT_TRUE(eventually(
        [&] {
          eprosima::fastdds::dds::PublicationMatchedStatus matched;
          commands_->get_publication_matched_status(matched);
          return matched.current_count > 0;
        },
        15s));
    EXPECT_TRUE(commands_->write(&command));
    return command.command_id();
  }

  // Collects statuses for `id` until `final` arrives (or the deadline passes).
  std::vector<CommandStatus> follow(std::uint32_t id, std::chrono::milliseconds deadline = 15s) {
    std::vector<CommandStatus> mine;
    eventually(
        [&] {
          CommandStatus status;
          SampleInfo info;
          while (statuses_->take_next_sample(&status, &info) == ReturnCode::RETCODE_OK) {
            if (info.valid_data) all_statuses_.push_back(status);
          }
          mine.clear();
          for (const auto& s : all_statuses_) {
            if (s.command_id() == id) mine.push_back(s);
          }
          return !mine.empty() && mine.back().state() != COMMAND_ACCEPTED;
        },
        deadline);
    return mine;
  }

  static std::vector<CommandState> states(const std::vector<CommandStatus>& statuses) {
    std::vector<CommandState> out;
    for (const auto& s : statuses) out.push_back(s.state());
    return out;
  }

 private:
  dds::Participant participant_;
  DataWriter* commands_ = nullptr;
  DataReader* statuses_ = nullptr;
  std::vector<CommandStatus> all_statuses_;
  std::uint32_t next_id_ = 0;
};

template <class Sample>
std::map<std::uint32_t, Sample> latest_by_serial(DataReader* reader,
                                                 std::map<std::uint32_t, Sample>& seen) {
  Sample sample;
  SampleInfo info;
  while (reader->take_next_sample(&sample, &info) == ReturnCode::RETCODE_OK) {
    if (info.valid_data) seen[sample.serial()] = sample;
  }
  return seen;
}

ValveCommand command(std::uint32_t serial, CommandKind kind) {
  ValveCommand c;
  c.serial(serial);
  c.kind(kind);
  c.speed_percent(100);
  c.direction(DIRECTION_OPEN);
  return c;
}

ValveCommand move_to(std::uint32_t serial, float degrees) {
  auto c = command(serial, COMMAND_TARGET_DEGREES);
  c.degrees(degrees);
  return c;
}

// Where a simulated valve really is: what the wire should have made it do.
double position_of(Gateway& gateway, std::uint32_t serial) {
  auto* simulator = gateway.simulator();
  return simulator->inspect([&](const sim::ValveBank& bank) {
    return bank.valve_with_serial(serial)->position(simulator->clock()->now());
  });
}

class GatewayE2E : public ::testing::Test {
 protected:
  void start(Gateway& gateway, std::size_t valves) {
    ASSERT_TRUE(gateway.start());
    ASSERT_TRUE(eventually(
        [&] {
          const auto known = gateway.bridge().valves();
          return known.size() == valves &&
                 std::all_of(known.begin(), known.end(), [](auto& v) { return v.online; });
        },
        15s))
        << "the gateway never saw its simulated valves";
  }
};

TEST_F(GatewayE2E, ALateJoinerSeesEveryValveOfAFullBusAtOnce) {
  // 32 valves, every address of the bus: more than any per-topic instance default of a DDS
  // implementation (Fast DDS: 10) must not matter.
  Gateway gateway(sim_config("gw-late", 32));
  start(gateway, 32);
  Ecu late;
  auto* presence = late.state_reader<ValvePresencePubSubType>(dds::topics::kPresence);
  auto* position = late.state_reader<ValvePositionPubSubType>(dds::topics::kPosition);
  std::map<std::uint32_t, ValvePresence> seen;
  std::map<std::uint32_t, ValvePosition> positions;
  ASSERT_TRUE(eventually(
      [&] {
        return latest_by_serial(presence, seen).size() == 32 &&
               latest_by_serial(position, positions).size() == 32;
      },
      15s))
      << seen.size() << " presences, " << positions.size() << " positions";
  for (std::uint32_t serial = 1; serial <= 32; ++serial) {
    EXPECT_EQ(seen[serial].address(), 0xD8 + serial - 1);
    EXPECT_TRUE(seen[serial].online());
    EXPECT_EQ(seen[serial].gateway().to_string(), "gw-late");
  }
  // And the 32nd valve takes commands like the first.
  EXPECT_EQ(Ecu::states(late.follow(late.send(move_to(32, 20.0f)))),
            (std::vector{COMMAND_ACCEPTED, COMMAND_COMPLETED}));
}

TEST_F(GatewayE2E, EveryTelemetryTopicCarriesEngineeringUnits) {
  Gateway gateway(sim_config("gw-telemetry", 1));
  start(gateway, 1);
  ASSERT_TRUE(gateway.simulator()->inject_error(1, {sim::ErrorKind::kHighVoltage, 17.2, 16.5}));
  Ecu ecu;
  auto* version = ecu.state_reader<ValveVersionPubSubType>(dds::topics::kVersion);
  auto* position = ecu.state_reader<ValvePositionPubSubType>(dds::topics::kPosition);
  auto* temperature = ecu.state_reader<ValveTemperaturePubSubType>(dds::topics::kTemperature);
  auto* voltage = ecu.state_reader<ValveVoltagePubSubType>(dds::topics::kVoltage);
  auto* current = ecu.state_reader<ValveCurrentPubSubType>(dds::topics::kCurrent);
  auto* dps = ecu.state_reader<ValveDegreesPerSecondPubSubType>(dds::topics::kDegreesPerSecond);
  auto* speed = ecu.state_reader<ValveSpeedDirectionPubSubType>(dds::topics::kSpeedDirection);
  auto* run_time = ecu.state_reader<ValveRunTimePubSubType>(dds::topics::kRunTime);
  auto* cycles = ecu.state_reader<ValveCycleCountPubSubType>(dds::topics::kCycleCount);
  auto* errors = ecu.state_reader<ValveErrorPubSubType>(dds::topics::kError);
  auto* baud = ecu.state_reader<ValveBaudRatePubSubType>(dds::topics::kBaudRate);
  auto* status = ecu.state_reader<GatewayStatusPubSubType>(dds::topics::kGatewayStatus);

  const auto baud_request = ecu.send(command(1, COMMAND_REQUEST_BAUD_RATE));
  EXPECT_EQ(Ecu::states(ecu.follow(baud_request)),
            (std::vector{COMMAND_ACCEPTED, COMMAND_COMPLETED}));

  std::map<std::uint32_t, ValveVersion> versions;
  std::map<std::uint32_t, ValvePosition> positions;
  std::map<std::uint32_t, ValveTemperature> temperatures;
  std::map<std::uint32_t, ValveVoltage> voltages;
  std::map<std::uint32_t, ValveCurrent> currents;
  std::map<std::uint32_t, ValveDegreesPerSecond> speeds;
  std::map<std::uint32_t, ValveSpeedDirection> directions;
  std::map<std::uint32_t, ValveRunTime> run_times;
  std::map<std::uint32_t, ValveCycleCount> cycle_counts;
  std::map<std::uint32_t, ValveError> error_samples;
  std::map<std::uint32_t, ValveBaudRate> baud_rates;
  ASSERT_TRUE(eventually(
      [&] {
        return !latest_by_serial(version, versions).empty() &&
               !latest_by_serial(position, positions).empty() &&
               !latest_by_serial(temperature, temperatures).empty() &&
               !latest_by_serial(voltage, voltages).empty() &&
               !latest_by_serial(current, currents).empty() &&
               !latest_by_serial(dps, speeds).empty() &&
               !latest_by_serial(speed, directions).empty() &&
               !latest_by_serial(run_time, run_times).empty() &&
               !latest_by_serial(cycles, cycle_counts).empty() &&
               !latest_by_serial(errors, error_samples).empty() &&
               !latest_by_serial(baud, baud_rates).empty();
      },
      15s));
  // The simulator's defaults (tools/valve-sim): 12.0 V, 25 °C, 180 dps configured, 250 kbit/s.
  EXPECT_FLOAT_EQ(voltages[1].volts(), 12.0f);
  EXPECT_EQ(temperatures[1].valve_c(), 25);
  EXPECT_EQ(speeds[1].dps(), 180);
  EXPECT_FLOAT_EQ(positions[1].degrees(), 0.0f);
  EXPECT_EQ(baud_rates[1].bit_rate(), 250000u);
  EXPECT_EQ(error_samples[1].kind(), ERROR_HIGH_VOLTAGE);
  EXPECT_FLOAT_EQ(error_samples[1].value(), 17.2f);
  EXPECT_EQ(versions[1].application().major(), 1);
  EXPECT_GT(positions[1].received_ns(), 1'700'000'000'000'000'000u);

  // Published once a second; the first may predate the valve's first I'm Here.
  GatewayStatus gateway_status;
  SampleInfo info;
  ASSERT_TRUE(eventually(
      [&] {
        while (status->take_next_sample(&gateway_status, &info) == ReturnCode::RETCODE_OK) {
          if (info.valid_data && gateway_status.valves_online() == 1) return true;
        }
        return false;
      },
      15s));
  EXPECT_EQ(gateway_status.gateway().to_string(), "gw-telemetry");
  EXPECT_EQ(gateway_status.valves_online(), 1u);
  EXPECT_GT(gateway_status.frames_in(), 0u);
  EXPECT_EQ(gateway_status.bus_state(), BUS_ERROR_ACTIVE);
}

TEST_F(GatewayE2E, EveryCommandKindReachesItsFinalState) {
  auto config = sim_config("gw-commands", 1);
  config.bridge.allow_baud_change = true;
  Gateway gateway(config);
  start(gateway, 1);
  Ecu ecu;
  const auto done = std::vector{COMMAND_ACCEPTED, COMMAND_COMPLETED};

  EXPECT_EQ(Ecu::states(ecu.follow(ecu.send(move_to(1, 45.0f)))), done);
  auto relative = command(1, COMMAND_DEGREES_FROM_POSITION);
  relative.direction(DIRECTION_CLOSE);
  relative.degrees(20.0f);
  EXPECT_EQ(Ecu::states(ecu.follow(ecu.send(relative))), done);
  auto jog = command(1, COMMAND_MILLISECONDS_TO_RUN);
  jog.milliseconds(200);
  EXPECT_EQ(Ecu::states(ecu.follow(ecu.send(jog))), done);
  EXPECT_EQ(Ecu::states(ecu.follow(ecu.send(command(1, COMMAND_STOP)))), done);
  EXPECT_EQ(Ecu::states(ecu.follow(ecu.send(command(1, COMMAND_CLEAR_ERRORS)))), done);
  for (auto telemetry : {TELEMETRY_VERSION, TELEMETRY_POSITION, TELEMETRY_TEMPERATURE,
                         TELEMETRY_VOLTAGE, TELEMETRY_CURRENT, TELEMETRY_DEGREES_PER_SECOND,
                         TELEMETRY_SPEED_DIRECTION, TELEMETRY_RUN_TIME, TELEMETRY_CYCLE_COUNTS}) {
    auto request = command(1, COMMAND_REQUEST);
    request.telemetry(telemetry);
    EXPECT_EQ(Ecu::states(ecu.follow(ecu.send(request))), done) << "telemetry " << telemetry;
  }
  auto baud = command(1, COMMAND_SET_BAUD_RATE);
  baud.bit_rate(500000);
  EXPECT_EQ(Ecu::states(ecu.follow(ecu.send(baud))), done);

  // Manual has no observable end: accepted, then superseded by the next command.
  const auto manual = ecu.send(command(1, COMMAND_MANUAL));
  const auto stop = ecu.send(command(1, COMMAND_STOP));
  EXPECT_EQ(Ecu::states(ecu.follow(manual)), (std::vector{COMMAND_ACCEPTED, COMMAND_SUPERSEDED}));
  EXPECT_EQ(Ecu::states(ecu.follow(stop)), done);
}

TEST_F(GatewayE2E, RejectionsCarryTheirReasonAndTimeoutsAreReported) {
  Gateway gateway(sim_config("gw-reject", 1));
  start(gateway, 1);
  Ecu ecu;
  auto out_of_range = ecu.follow(ecu.send(move_to(1, 400.0f)));
  ASSERT_EQ(Ecu::states(out_of_range), std::vector{COMMAND_REJECTED});
  EXPECT_EQ(out_of_range[0].reason().to_string(),
            "target_degrees: degrees 400 is outside 0 to 359.9");

  auto baud = command(1, COMMAND_SET_BAUD_RATE);
  baud.bit_rate(500000);
  auto refused = ecu.follow(ecu.send(baud));
  ASSERT_EQ(Ecu::states(refused), std::vector{COMMAND_REJECTED});
  EXPECT_EQ(refused[0].reason().to_string(),
            "setting the baud rate is not allowed; start the gateway with --allow-baud-change");

  // The valve stops at its opened limit (90): a target the gateway thinks is reachable (limits
  // configured as full-turn for this serial) never arrives and times out.
  gateway.stop();
  auto config = sim_config("gw-timeout", 1);
  config.bridge.limits[1] = bridge::ValveLimits{0, 360};
  Gateway unreachable(config);
  start(unreachable, 1);
  auto timed_out = ecu.follow(ecu.send(move_to(1, 180.0f)), 20s);
  ASSERT_EQ(Ecu::states(timed_out), (std::vector{COMMAND_ACCEPTED, COMMAND_TIMED_OUT}));
  EXPECT_EQ(timed_out[1].reason().to_string(), "position 90.0 did not reach 180.0 in time");
}

TEST_F(GatewayE2E, AReaddressedValveKeepsItsInstanceAndItsCommands) {
  Gateway gateway(sim_config("gw-readdress", 2, 10));  // TJV000010 at 0xD8, TJV000011 at 0xD9
  start(gateway, 2);
  Ecu ecu;
  auto* presence = ecu.state_reader<ValvePresencePubSubType>(dds::topics::kPresence);
  std::map<std::uint32_t, ValvePresence> seen;
  ASSERT_TRUE(eventually([&] { return latest_by_serial(presence, seen).size() == 2; }, 15s));
  EXPECT_EQ(seen[10].address(), 0xD8);

  sim::ValveConfig newcomer;
  newcomer.serial = 5;  // the lowest serial takes 0xD8: everyone else moves up
  newcomer.degrees_per_second = 180;
  ASSERT_TRUE(gateway.simulator()->add_valve(newcomer));
  ASSERT_TRUE(eventually(
      [&] {
        latest_by_serial(presence, seen);
        return seen.size() == 3 && seen[10].address() == 0xD9 && seen[11].address() == 0xDA;
      },
      15s));
  EXPECT_EQ(seen[5].address(), 0xD8);

  EXPECT_EQ(Ecu::states(ecu.follow(ecu.send(move_to(10, 30.0f)))),
            (std::vector{COMMAND_ACCEPTED, COMMAND_COMPLETED}));
  // The move went to TJV000010 at its new address, not to whoever holds 0xD8 now.
  const double newcomer_position = position_of(gateway, 5);
  EXPECT_EQ(newcomer_position, 0.0);
}

TEST_F(GatewayE2E, ValvesGoOfflineWhenTheirIAmHereStops) {
  Gateway gateway(sim_config("gw-offline", 2));
  start(gateway, 2);
  Ecu ecu;
  auto* presence = ecu.state_reader<ValvePresencePubSubType>(dds::topics::kPresence);
  std::map<std::uint32_t, ValvePresence> seen;
  ASSERT_TRUE(eventually([&] { return latest_by_serial(presence, seen).size() == 2; }, 15s));
  const auto silenced_at = std::chrono::steady_clock::now();
  gateway.simulator()->stop();
  ASSERT_TRUE(eventually(
      [&] {
        latest_by_serial(presence, seen);
        return !seen[1].online() && !seen[2].online();
      },
      15s));
  // Offline after 1.5 s of silence (configured), detected by a 50 ms clock: within 3 s.
  EXPECT_LT(std::chrono::steady_clock::now() - silenced_at, 3s);
  auto rejected = ecu.follow(ecu.send(move_to(1, 10.0f)));
  ASSERT_EQ(Ecu::states(rejected), std::vector{COMMAND_REJECTED});
  EXPECT_EQ(rejected[0].reason().to_string(), "valve TJV000001 is offline");
}

TEST_F(GatewayE2E, TwoGatewaysShareADomainEachActingForItsOwnValves) {
  Gateway left(sim_config("gw-left", 2, 1));
  Gateway right(sim_config("gw-right", 2, 101));
  start(left, 2);
  start(right, 2);
  Ecu ecu;
  auto* presence = ecu.state_reader<ValvePresencePubSubType>(dds::topics::kPresence);
  std::map<std::uint32_t, ValvePresence> seen;
  ASSERT_TRUE(eventually([&] { return latest_by_serial(presence, seen).size() == 4; }, 15s));
  EXPECT_EQ(seen[2].gateway().to_string(), "gw-left");
  EXPECT_EQ(seen[102].gateway().to_string(), "gw-right");
  // Both gateways use address 0xD8 on their own bus: identity is the serial, not the address.
  EXPECT_EQ(seen[1].address(), seen[101].address());

  const auto statuses = ecu.follow(ecu.send(move_to(102, 20.0f)));
  EXPECT_EQ(Ecu::states(statuses), (std::vector{COMMAND_ACCEPTED, COMMAND_COMPLETED}));
  const double moved = position_of(right, 102);
  EXPECT_NEAR(moved, 20.0, 1.0);
  const double untouched = position_of(left, 2);
  EXPECT_EQ(untouched, 0.0);
}

TEST_F(GatewayE2E, WhenACommanderDiesItsValvesAreStopped) {
  auto config = sim_config("gw-failsafe", 2);
  config.sim_opened_degrees = 360;  // full-turn valves: a manual run never ends by itself
  Gateway gateway(config);
  start(gateway, 2);
  const auto running = [&](std::uint32_t serial) {
    auto* simulator = gateway.simulator();
    return simulator->inspect([&](const sim::ValveBank& bank) {
      return bank.valve_with_serial(serial)->running(simulator->clock()->now());
    });
  };
  Ecu bystander;  // another ECU's manual run must survive the first one's death
  auto manual = command(2, COMMAND_MANUAL);
  manual.speed_percent(10);
  const auto bystander_run = bystander.send(manual);
  ASSERT_EQ(Ecu::states(bystander.follow(bystander_run, 1s)), std::vector{COMMAND_ACCEPTED});

  // tests/dds/command_writer: writes Manual (open, 50 %) for serial 1, then waits to be killed.
  teejet::testing::Subprocess commander(
      {COMMAND_WRITER_PATH, std::to_string(domain_for_this_run()), "1"});
  ASSERT_TRUE(commander.wait_for_stdout("sent", 20s));
  ASSERT_TRUE(eventually([&] { return running(1); }, 5s)) << "the manual run never started";
  commander.signal(SIGKILL);
  const auto killed_at = std::chrono::steady_clock::now();

  // Liveliness lease 2 s, then the gateway sends Stop.
  ASSERT_TRUE(eventually([&] { return !running(1); }, 6s)) << "valve 1 still running";
  const auto stopped_after = std::chrono::steady_clock::now() - killed_at;
  EXPECT_GE(stopped_after, 1500ms);  // not before the lease could have run out
  std::printf("fail-safe stopped the valve %lld ms after SIGKILL\n",
              static_cast<long long>(
                  std::chrono::duration_cast<std::chrono::milliseconds>(stopped_after).count()));
  EXPECT_TRUE(running(2)) << "the fail-safe stopped a valve the dead commander never drove";
}

}  // namespace
}  // namespace teejet::gateway
