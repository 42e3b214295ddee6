// The real valvectl binary against a gateway made of the project's bridge, DDS endpoints and
// valve simulator, all inside a private network namespace (tests/netns/isolated). Every valve
// has one job so that the tests do not disturb each other; they share one gateway because its
// discovery is the slow part.

#include <gtest/gtest.h>
#include <signal.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "exit_codes.hpp"
#include "observed_gateway.hpp"
#include "support/dds_peer.hpp"
#include "support/eventually.hpp"
#include "support/subprocess.hpp"
#include "support/test_domain.hpp"
#include "support/text.hpp"
#include "teejet/can/open_bus.hpp"
#include "teejet/codec/codec.hpp"
#include "teejet/sim/isobus_neighbour.hpp"

namespace teejet::testing {
namespace {

using namespace std::chrono_literals;
using namespace teejet::valvectl;

// Valves by role.
constexpr std::uint32_t kListed = 1;
constexpr std::uint32_t kMoved = 2;
constexpr std::uint32_t kMovedWithJson = 3;
constexpr std::uint32_t kSuperseded = 4;
constexpr std::uint32_t kMovedWithoutWait = 5;
[[maybe_unused]] constexpr std::uint32_t kQueried = 6;  // named in the requests below as TJV000006
constexpr std::uint32_t kJogged = 7;
constexpr std::uint32_t kFaulty = 8;
constexpr std::uint32_t kRaced = 9;
constexpr std::uint32_t kAcknowledged = 10;
constexpr std::uint32_t kMovedOnATerminal = 11;
constexpr std::uint32_t kMovedWithProgress = 12;
constexpr std::uint32_t kDrivenWhileWaiting = 13;
constexpr std::uint32_t kValveCount = 13;
constexpr std::uint32_t kSilent = 999;  // announced once, then offline
constexpr std::uint8_t kSilentAddress = 0xF0;

std::string domain_text() { return std::to_string(test_domain()); }

std::vector<std::string> split_lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream stream(text);
  for (std::string line; std::getline(stream, line);) {
    if (!line.empty()) lines.push_back(line);
  }
  return lines;
}

class ValvectlEndToEnd : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    spdlog::set_level(spdlog::level::warn);  // the gateway's info lines would drown the output
    gateway_ = std::make_unique<ObservedGateway>(
        ObservedGatewayOptions{.domain = test_domain(), .valves = static_cast<int>(kValveCount)});
    gateway_->announce_silent_valve(kSilent, kSilentAddress);
  }
  static void TearDownTestSuite() { gateway_.reset(); }

  // valvectl with --domain, then `args`.
  static Finished valvectl(std::vector<std::string> args, std::chrono::milliseconds limit = 30s) {
    args.insert(args.begin(), {VALVECTL_PATH, "--domain", domain_text()});
    return run(args, limit);
  }

  // Commands for `serial` that reached the gateway: accepted or rejected ones leave a status,
  // ones for serials it does not know only its ignored counter.
  static std::size_t commands_for(std::uint32_t serial) {
    std::size_t count = 0;
    for (const auto& command : gateway_->commands()) count += command.serial() == serial;
    return count;
  }
  static std::uint64_t commands_ignored() { return gateway_->bridge().counters().commands_ignored; }

  static bool silent_valve_offline() {
    for (const auto& valve : gateway_->bridge().valves()) {
      if (valve.serial == kSilent) return !valve.online;
    }
    return false;
  }

  static std::unique_ptr<ObservedGateway> gateway_;
};

std::unique_ptr<ObservedGateway> ValvectlEndToEnd::gateway_;

TEST_F(ValvectlEndToEnd, ListShowsEveryValveWithItsTelemetry) {
  const auto listed =
      valvectl({"--profile", LOOPBACK_PROFILE, "list", "--wait-for", std::to_string(kValveCount)});
  ASSERT_EQ(listed.exit_code, kExitOk) << describe(listed);
  const auto lines = split_lines(listed.out);
  ASSERT_GE(lines.size(), kValveCount + 1) << describe(listed);
  EXPECT_EQ(lines[0].rfind("SERIAL", 0), 0u);
  for (std::uint32_t serial = 1; serial <= kValveCount; ++serial) {
    EXPECT_TRUE(contains(listed.out, codec::format_serial(serial))) << describe(listed);
  }
  // TJV000001 at 0xD8, online, at 0.0 degrees, 25 °C, 12.0 V, no errors, on our gateway.
  EXPECT_TRUE(contains(lines[1], "TJV000001  0xD8  yes")) << lines[1];
  EXPECT_TRUE(contains(lines[1], "0.0      25   12.0  -")) << lines[1];
  EXPECT_TRUE(contains(lines[1], gateway_->name())) << lines[1];
}

TEST_F(ValvectlEndToEnd, ListAsJsonIsAnArrayOfValveObjects) {
  const auto listed = valvectl({"list", "--json", "--wait-for", std::to_string(kValveCount)});
  ASSERT_EQ(listed.exit_code, kExitOk) << describe(listed);
  const auto json = nlohmann::json::parse(listed.out);
  ASSERT_TRUE(json.is_array());
  ASSERT_GE(json.size(), kValveCount);
  const auto& first = json[0];
  EXPECT_EQ(first["serial"], codec::format_serial(kListed));
  EXPECT_EQ(first["address"], 0xD8);
  EXPECT_EQ(first["online"], true);
  EXPECT_DOUBLE_EQ(first["position"].get<double>(), 0.0);
  EXPECT_EQ(first["temperature_c"], 25);
  EXPECT_DOUBLE_EQ(first["volts"].get<double>(), 12.0);
  EXPECT_EQ(first["errors"], nlohmann::json::array());
  EXPECT_EQ(first["gateway"], gateway_->name());
}

// The "TJVnnnnnn position D" lines of an output, as degrees.
std::vector<double> positions_in(const std::string& out, const std::string& serial) {
  std::vector<double> degrees;
  const std::string prefix = serial + " position ";
  for (const auto& line : split_lines(out)) {
    if (line.rfind(prefix, 0) == 0) degrees.push_back(std::stod(line.substr(prefix.size())));
  }
  return degrees;
}

// Into a pipe (a script, a test rig) only the final position: following the moving position
// would cost every gateway ten samples a second of each of its valves for this client.
TEST_F(ValvectlEndToEnd, MoveWithWaitIntoAPipePrintsTheFinalPositionAndExitsZeroOnCompletion) {
  const auto moved = valvectl({"move", "TJV000002", "--to", "45", "--wait"});
  ASSERT_EQ(moved.exit_code, kExitOk) << describe(moved);
  const auto lines = split_lines(moved.out);
  ASSERT_EQ(lines.size(), 3u) << describe(moved);
  EXPECT_TRUE(contains(lines[0], "TJV000002 target_degrees #")) << lines[0];
  EXPECT_TRUE(contains(lines[0], ": ACCEPTED")) << lines[0];
  const auto positions = positions_in(moved.out, "TJV000002");
  ASSERT_EQ(positions.size(), 1u) << describe(moved);
  EXPECT_TRUE(contains(lines[1], "TJV000002 position ")) << lines[1];
  EXPECT_NEAR(positions[0], 45.0, 1.0);
  EXPECT_TRUE(contains(lines[2], ": COMPLETED")) << lines[2];
  EXPECT_NEAR(gateway_->position_of(kMoved), 45.0, 1.0);
}

// --progress: a log of the move into a pipe, as on a terminal.
TEST_F(ValvectlEndToEnd, MoveWithWaitAndProgressIntoAPipeShowsTheValveMoving) {
  const std::string serial = codec::format_serial(kMovedWithProgress);
  const auto moved = valvectl({"move", serial, "--to", "90", "--wait", "--progress"});
  ASSERT_EQ(moved.exit_code, kExitOk) << describe(moved);
  const auto lines = split_lines(moved.out);
  const auto positions = positions_in(moved.out, serial);
  ASSERT_GE(positions.size(), 2u) << describe(moved);
  EXPECT_LT(positions.front(), 80.0) << describe(moved);
  EXPECT_NEAR(positions.back(), 90.0, 1.0);
  EXPECT_TRUE(contains(lines.back(), ": COMPLETED")) << lines.back();
}

// On a terminal a person watches the valve move: the position as it changes, the final one
// last before COMPLETED.
TEST_F(ValvectlEndToEnd, MoveWithWaitOnATerminalShowsTheValveMoving) {
  const std::string serial = codec::format_serial(kMovedOnATerminal);
  Subprocess moving(
      {VALVECTL_PATH, "--domain", domain_text(), "move", serial, "--to", "90", "--wait"},
      Subprocess::Input::kDevNull, Subprocess::Output::kTerminal);
  const auto moved = moving.wait(60s);
  ASSERT_EQ(moved.exit_code, kExitOk) << describe(moved);
  const auto lines = split_lines(moved.out);
  ASSERT_GE(lines.size(), 4u) << describe(moved);
  EXPECT_TRUE(contains(lines.front(), ": ACCEPTED")) << lines.front();
  EXPECT_TRUE(contains(lines.back(), ": COMPLETED")) << lines.back();
  const auto positions = positions_in(moved.out, serial);
  ASSERT_GE(positions.size(), 2u) << describe(moved);
  EXPECT_LT(positions.front(), 80.0) << describe(moved);
  EXPECT_NEAR(positions.back(), 90.0, 1.0);
  EXPECT_TRUE(contains(lines[lines.size() - 2], serial + " position ")) << describe(moved);
}

TEST_F(ValvectlEndToEnd, MoveAsJsonPrintsOneParsableObjectPerLine) {
  const auto moved = valvectl({"--json", "move", "3", "--to", "30", "--wait"});
  ASSERT_EQ(moved.exit_code, kExitOk) << describe(moved);
  std::vector<nlohmann::json> statuses;
  for (const auto& line : split_lines(moved.out)) {
    const auto json = nlohmann::json::parse(line);
    if (json["event"] == "status") statuses.push_back(json);
  }
  ASSERT_GE(statuses.size(), 2u) << describe(moved);
  EXPECT_EQ(statuses.front()["state"], "accepted");
  EXPECT_EQ(statuses.back()["state"], "completed");
  EXPECT_EQ(statuses.front()["command_id"], statuses.back()["command_id"]);
  EXPECT_EQ(statuses.front()["serial"], codec::format_serial(kMovedWithJson));
  EXPECT_EQ(statuses.front()["kind"], "target_degrees");
  EXPECT_EQ(statuses.front()["origin"].get<std::string>().rfind("valvectl@", 0), 0u);
}

TEST_F(ValvectlEndToEnd, InvalidArgumentsExit64BeforeAnythingIsSent) {
  const auto before = gateway_->commands().size();
  for (const auto& args : std::vector<std::vector<std::string>>{
           {"move", "1", "--to", "400"},
           {"move", "1", "--to", "10", "--speed", "101"},
           {"move", "TJV12x", "--to", "10"},
           {"manual", "1", "--speed", "50", "--direction", "shortest"}}) {
    const auto refused = valvectl(args);
    EXPECT_EQ(refused.exit_code, kExitUsage) << describe(refused);
    EXPECT_TRUE(contains(refused.err, "valvectl: ")) << describe(refused);
    EXPECT_TRUE(refused.out.empty()) << describe(refused);
  }
  // A valid command sent now reaches the gateway before anything sent earlier could be missed.
  const auto stopped = valvectl({"stop", "1"});
  ASSERT_EQ(stopped.exit_code, kExitOk) << describe(stopped);
  ASSERT_TRUE(eventually([&] { return gateway_->commands().size() > before; }, 5s));
  const auto commands = gateway_->commands();
  ASSERT_EQ(commands.size(), before + 1);
  EXPECT_EQ(commands.back().kind(), COMMAND_STOP);
}

// A recorder must hold every command it was waited for. valvectl --command-readers therefore
// keeps its writer until every matched reader acknowledged: a reader with no room (a KEEP_ALL
// history of one, still full) does not, so valvectl says so after --timeout and exits 4; and
// once that reader has room again, it gets the command from the waiting valvectl by repair.
TEST_F(ValvectlEndToEnd, CommandReadersMustAcknowledgeBeforeValvectlExits) {
  DdsPeer recorder(test_domain(), "one-command-recorder");
  auto qos = dds::topics::command_reader_qos();
  qos.resource_limits().max_samples = 1;
  qos.resource_limits().max_samples_per_instance = 1;
  qos.resource_limits().max_instances = 1;
  auto* commands = recorder.reader<ValveCommand>(qos);
  ASSERT_NE(commands, nullptr);
  const std::string serial = codec::format_serial(kAcknowledged);
  const std::vector<std::string> stop = {"--command-readers", "2", "stop", serial};

  auto first = stop;
  first.insert(first.begin(), {"--timeout", "10"});
  const auto held = valvectl(first);
  ASSERT_EQ(held.exit_code, kExitOk) << describe(held);
  ASSERT_TRUE(eventually([&] { return commands->get_unread_count() == 1; }, 5s));

  auto second = stop;
  second.insert(second.begin(), {"--timeout", "2"});
  const auto unacknowledged = valvectl(second);
  EXPECT_EQ(unacknowledged.exit_code, kExitTimedOut) << describe(unacknowledged);
  EXPECT_TRUE(contains(unacknowledged.out, serial + " stop #")) << describe(unacknowledged);
  EXPECT_TRUE(contains(unacknowledged.err,
                       "valvectl: a command reader did not acknowledge the command(s) within 2 s; "
                       "it may not hold them"))
      << describe(unacknowledged);

  auto third = stop;
  third.insert(third.begin(), {VALVECTL_PATH, "--domain", domain_text(), "--timeout", "20"});
  Subprocess waiting(third);
  ASSERT_TRUE(waiting.wait_for_stdout(serial + " stop #", 15s)) << waiting.err();
  const auto ok = eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK;
  ValveCommand taken;
  eprosima::fastdds::dds::SampleInfo info;
  ASSERT_EQ(commands->take_next_sample(&taken, &info), ok);
  ASSERT_TRUE(eventually([&] { return commands->get_unread_count() == 1; }, 10s));
  const auto delivered = waiting.wait(25s);
  EXPECT_EQ(delivered.exit_code, kExitOk) << describe(delivered);
  ASSERT_EQ(commands->take_next_sample(&taken, &info), ok);
  EXPECT_EQ(taken.serial(), kAcknowledged);
  // Appended, not "#" + id: GCC 12 reports a false -Wrestrict on that at -O3.
  std::string command_id = "#";
  command_id += std::to_string(taken.command_id());
  EXPECT_TRUE(contains(delivered.out, command_id + ":")) << describe(delivered);
}

TEST_F(ValvectlEndToEnd, UnknownSerialExits2WithoutWaitingTheWholeTimeout) {
  const auto ignored_before = commands_ignored();
  // Every gateway had told all it knows: no need to wait for the timeout. One far beyond the
  // 30 s this test gives valvectl tells the two apart without timing it.
  const auto unknown = valvectl({"--timeout", "3600", "move", "123", "--to", "10"});
  EXPECT_FALSE(unknown.timed_out) << "valvectl waited for its --timeout";
  EXPECT_EQ(unknown.exit_code, kExitNotFound) << describe(unknown);
  EXPECT_TRUE(contains(unknown.err,
                       "valve TJV000123 is not known to any of the 1 gateway(s) on domain " +
                           domain_text() + " (" + std::to_string(kValveCount + 1) + " valves)"))
      << describe(unknown);
  std::printf("[ measured ] valvectl: an unknown serial refused after %lld ms\n",
              static_cast<long long>(unknown.took.count()));
  // Nothing was written: a command for an unknown serial would show as ignored by the gateway.
  EXPECT_EQ(commands_ignored(), ignored_before);
}

// A gateway whose participant discovery has met but whose topics have not matched yet (here: a
// participant announcing itself as a gateway that never publishes) holds the verdict: valvectl
// does not call a valve unknown on the word of the gateways it has heard so far.
TEST_F(ValvectlEndToEnd, AGatewayMetButNotYetHeardKeepsAValveFromBeingCalledUnknown) {
  auto starting = dds::Participant::create(
      {.domain = test_domain(), .name = "starting-gateway", .role = dds::kGatewayRole});
  ASSERT_TRUE(starting);
  const auto waited = valvectl({"--timeout", "2", "move", "123", "--to", "10"});
  EXPECT_EQ(waited.exit_code, kExitNotFound) << describe(waited);
  EXPECT_TRUE(contains(waited.err, "valve TJV000123 was not found within 2 s on domain " +
                                       domain_text() + ": met 1 of 2 gateway(s)"))
      << describe(waited);
  starting->reset();
  const auto unknown = valvectl({"--timeout", "3600", "move", "123", "--to", "10"});
  EXPECT_FALSE(unknown.timed_out) << "valvectl waited for its --timeout";
  EXPECT_TRUE(contains(unknown.err, "is not known to any of the 1 gateway(s)"))
      << describe(unknown);
}

TEST_F(ValvectlEndToEnd, NoGatewayOnTheDomainExits2) {
  const std::string empty_domain = std::to_string(teejet::testing::another_test_domain());
  const auto listed = run({VALVECTL_PATH, "--domain", empty_domain, "--timeout", "1", "list"});
  EXPECT_EQ(listed.exit_code, kExitNotFound) << describe(listed);
  EXPECT_TRUE(contains(listed.err, "no gateway found on domain " + empty_domain));
  const auto moved =
      run({VALVECTL_PATH, "--domain", empty_domain, "--timeout", "1", "move", "1", "--to", "5"});
  EXPECT_EQ(moved.exit_code, kExitNotFound) << describe(moved);
  EXPECT_TRUE(contains(moved.err, "no gateway found on domain " + empty_domain));
}

TEST_F(ValvectlEndToEnd, CommandToAnOfflineValveIsRejectedWithTheReason) {
  ASSERT_TRUE(eventually([] { return silent_valve_offline(); }, 15s));
  const auto rejected = valvectl({"move", "TJV000999", "--to", "10", "--wait"});
  EXPECT_EQ(rejected.exit_code, kExitRejected) << describe(rejected);
  EXPECT_TRUE(contains(rejected.out, "TJV000999 target_degrees #"));
  EXPECT_TRUE(contains(rejected.out, ": REJECTED: valve TJV000999 is offline"))
      << describe(rejected);
}

// Another ECU on the gateway's bus: a terminal at 0x26 shows in `valvectl neighbours`; a
// contender for 0xD5 with a NAME of higher priority makes the gateway give its address up, and
// valvectl's command is REJECTED naming that NAME, until the contender cannot claim any more.
TEST_F(ValvectlEndToEnd, NeighboursAreListedAndAContenderFor0xD5StopsCommandsUntilItLeaves) {
  const std::string bus = "virtual:" + gateway_->simulator().bus_name();
  isobus::Name terminal_name = isobus::from_value(0xA00C81045A20021BULL);
  sim::IsobusNeighbour terminal(can::make_bus(bus, std::vector<can::Filter>{}), terminal_name,
                                0x26);
  ASSERT_TRUE(terminal.start());
  ASSERT_TRUE(terminal.claim());
  Finished listed;
  ASSERT_TRUE(eventually(
      [&] {
        listed = valvectl({"neighbours"});
        return contains(listed.out, "0x26  0xA00C81045A20021B");
      },
      15s))
      << describe(listed);
  EXPECT_EQ(listed.exit_code, kExitOk) << describe(listed);
  EXPECT_TRUE(contains(listed.out, "holds 0xD5 as NAME 0x2008800000000000, 1 neighbour(s)"))
      << describe(listed);

  const auto winner = isobus::from_value(0x1000000000000001ULL);  // industry group 1: lower
  sim::IsobusNeighbour contender(can::make_bus(bus, std::vector<can::Filter>{}), winner, 0xD5);
  ASSERT_TRUE(contender.start());
  ASSERT_TRUE(contender.claim());
  ASSERT_TRUE(eventually(
      [&] { return gateway_->bridge().claim_state() == isobus::ClaimState::kYielded; }, 10s));
  // Cannot Claim Address, from the null address, with the gateway's NAME.
  EXPECT_TRUE(contender.wait_for(
      [](const codec::CanFrame& f) { return f.id == 0x18EEFFFEu && f.data[7] == 0x20; }, 5s));
  const auto refused = valvectl({"move", "1", "--to", "10"});
  EXPECT_EQ(refused.exit_code, kExitRejected) << describe(refused);
  EXPECT_TRUE(contains(refused.out,
                       ": REJECTED: the gateway gave its address 0xD5 up to an ECU with NAME "
                       "0x1000000000000001 (higher priority)"))
      << describe(refused);

  ASSERT_TRUE(contender.give_up());
  ASSERT_TRUE(eventually(
      [&] { return gateway_->bridge().claim_state() == isobus::ClaimState::kClaimed; }, 10s));
  const auto moved = valvectl({"move", "1", "--to", "10", "--wait"});
  EXPECT_EQ(moved.exit_code, kExitOk) << describe(moved);
}

TEST_F(ValvectlEndToEnd, SettingTheBaudRateWithoutPermissionIsRejected) {
  const auto rejected = valvectl({"--json", "baud", "6", "--set", "500000"});
  EXPECT_EQ(rejected.exit_code, kExitRejected) << describe(rejected);
  const auto status = nlohmann::json::parse(split_lines(rejected.out).at(0));
  EXPECT_EQ(status["state"], "rejected");
  EXPECT_EQ(status["kind"], "set_baud_rate");
  EXPECT_TRUE(contains(status["reason"].get<std::string>(), "not allowed"));
}

TEST_F(ValvectlEndToEnd, ANewerCommandSupersedesAWaitingMove) {
  const auto before = commands_for(kSuperseded);
  Subprocess slow_move({VALVECTL_PATH, "--domain", domain_text(), "move", "4", "--to", "80",
                        "--speed", "10", "--wait"});
  // Once the gateway has handled the slow move, the next command replaces it.
  ASSERT_TRUE(eventually([&] { return commands_for(kSuperseded) > before; }, 15s));
  const auto newer = valvectl({"move", "4", "--to", "0", "--direction", "close"});
  EXPECT_EQ(newer.exit_code, kExitOk) << describe(newer);
  const auto replaced = slow_move.wait(30s);
  EXPECT_EQ(replaced.exit_code, kExitSuperseded) << describe(replaced);
  EXPECT_TRUE(contains(split_lines(replaced.out).back(), ": SUPERSEDED: replaced by command"))
      << describe(replaced);
}

// Every gateway sends each client that follows presence every valve's I'm Here once a second: a
// hundred clients waiting for their commands' statuses filled the gateways' sockets. Once a
// command has found its valve, valvectl stops following presence for the rest of its wait.
TEST_F(ValvectlEndToEnd, AWaitingCommandStopsFollowingPresenceOnceItFoundItsValve) {
  const int others = gateway_->readers_of<ValvePresence>();
  const std::string serial = codec::format_serial(kDrivenWhileWaiting);
  // At 1 % of 90 °/s the move takes 100 s: valvectl waits for its completion all along.
  Subprocess waiting({VALVECTL_PATH, "--domain", domain_text(), "move", serial, "--to", "90",
                      "--speed", "1", "--wait", "--wait-timeout", "120"});
  // Its presence reader matched the gateway's writer before it could find the valve.
  ASSERT_TRUE(waiting.wait_for_stdout(": ACCEPTED", 15s)) << waiting.err();
  EXPECT_TRUE(eventually([&] { return gateway_->readers_of<ValvePresence>() == others; }, 10s))
      << gateway_->readers_of<ValvePresence>() - others << " presence reader(s) of valvectl left";
  waiting.signal(SIGINT);
  const auto interrupted = waiting.wait(15s);
  EXPECT_EQ(interrupted.exit_code, kExitInterrupted) << describe(interrupted);
  const auto stopped = valvectl({"stop", serial});
  EXPECT_EQ(stopped.exit_code, kExitOk) << describe(stopped);
}

TEST_F(ValvectlEndToEnd, AMoveGoesOnAfterValvectlExitsWithoutWait) {
  const auto moved = valvectl({"move", "5", "--to", "60"});
  ASSERT_EQ(moved.exit_code, kExitOk) << describe(moved);
  const auto lines = split_lines(moved.out);
  ASSERT_EQ(lines.size(), 1u) << describe(moved);
  EXPECT_TRUE(contains(lines[0], ": ACCEPTED"));
  // valvectl's writer went away in good order: that is no reason for the fail-safe to stop it.
  EXPECT_TRUE(eventually([] { return gateway_->position_of(kMovedWithoutWait) >= 59.0; }, 10s))
      << "position " << gateway_->position_of(kMovedWithoutWait);
}

// Issue 10: with several valvectl processes starting at once, ~0.3 % of commands were reported
// to get no status ("no status for command ... within 5 s"), as if a command or its status was
// written before the other side had matched. Four parallel loops of moves without --wait: each
// one must reach the gateway once and be answered.
TEST_F(ValvectlEndToEnd, ParallelClientsEachGetTheirStatus) {
  constexpr int kLoops = 4, kMovesPerLoop = 6;
  const std::size_t before = commands_for(kRaced);
  std::vector<Finished> finished(kLoops * kMovesPerLoop);
  std::vector<std::thread> loops;
  for (int loop = 0; loop < kLoops; ++loop) {
    loops.emplace_back([&, loop] {
      for (int move = 0; move < kMovesPerLoop; ++move) {
        const int index = loop * kMovesPerLoop + move;
        finished[static_cast<std::size_t>(index)] =
            valvectl({"move", std::to_string(kRaced), "--to", std::to_string(10 + index)});
      }
    });
  }
  for (auto& loop : loops) loop.join();
  for (const auto& one : finished) {
    ASSERT_EQ(one.exit_code, kExitOk) << describe(one);
    EXPECT_TRUE(contains(one.out, ": ACCEPTED")) << describe(one);
  }
  EXPECT_EQ(commands_for(kRaced) - before, finished.size());
}

TEST_F(ValvectlEndToEnd, RequestWithWaitPrintsTheReply) {
  const auto requested = valvectl({"request", "TJV000006", "voltage", "--wait"});
  ASSERT_EQ(requested.exit_code, kExitOk) << describe(requested);
  EXPECT_TRUE(contains(requested.out, "TJV000006 request #")) << describe(requested);
  EXPECT_TRUE(contains(requested.out, ": COMPLETED")) << describe(requested);
  EXPECT_TRUE(contains(requested.out, "TJV000006 voltage volts=12.0")) << describe(requested);

  const auto baud = valvectl({"--json", "baud", "6", "--request", "--wait"});
  ASSERT_EQ(baud.exit_code, kExitOk) << describe(baud);
  const auto reply = nlohmann::json::parse(split_lines(baud.out).back());
  EXPECT_EQ(reply["event"], "reply");
  EXPECT_EQ(reply["values"]["bit_rate"], 250000);
}

TEST_F(ValvectlEndToEnd, JogWithWaitCompletesWhenTheTimeIsUp) {
  const auto jogged = valvectl({"jog", "7", "--ms", "300", "--speed", "50", "--wait"});
  ASSERT_EQ(jogged.exit_code, kExitOk) << describe(jogged);
  EXPECT_TRUE(contains(split_lines(jogged.out).back(), "milliseconds_to_run")) << jogged.out;
  EXPECT_TRUE(contains(split_lines(jogged.out).back(), ": COMPLETED")) << jogged.out;
  EXPECT_GT(gateway_->position_of(kJogged), 5.0);  // 45 deg/s for 0.3 s
}

TEST_F(ValvectlEndToEnd, LatchedErrorsShowInTheListUntilCleared) {
  ASSERT_TRUE(gateway_->simulator().inject_error(kFaulty, codec::HighVoltageError{16.2, 15.5}));
  const auto error_listed = [](const std::string& expected) {
    return eventually(
        [&] {
          const auto listed = valvectl({"--json", "list"});
          if (listed.exit_code != kExitOk) return false;
          for (const auto& valve : nlohmann::json::parse(listed.out)) {
            if (valve["serial"] == codec::format_serial(kFaulty)) {
              return valve["errors"].dump() == expected;
            }
          }
          return false;
        },
        20s);
  };
  ASSERT_TRUE(error_listed(R"(["high_voltage"])"));
  // The table too: a text list follows the errors, though only its columns' telemetry.
  const auto table = valvectl({"list"});
  ASSERT_EQ(table.exit_code, kExitOk) << describe(table);
  const auto lines = split_lines(table.out);
  const auto faulty = std::find_if(lines.begin(), lines.end(), [](const std::string& line) {
    return line.rfind(codec::format_serial(kFaulty), 0) == 0;
  });
  ASSERT_NE(faulty, lines.end()) << table.out;
  EXPECT_TRUE(contains(*faulty, "high_voltage")) << *faulty;
  const auto cleared = valvectl({"clear-errors", "8", "--wait"});
  ASSERT_EQ(cleared.exit_code, kExitOk) << describe(cleared);
  EXPECT_TRUE(contains(cleared.out, "TJV000008 clear_errors #")) << cleared.out;
  EXPECT_TRUE(error_listed("[]"));
}

TEST_F(ValvectlEndToEnd, StopAllStopsEveryOnlineValve) {
  ASSERT_TRUE(eventually([] { return silent_valve_offline(); }, 15s));
  const auto stopped = valvectl({"stop", "--all", "--wait"});
  ASSERT_EQ(stopped.exit_code, kExitOk) << describe(stopped);
  std::size_t completed = 0;
  for (const auto& line : split_lines(stopped.out)) completed += contains(line, ": COMPLETED");
  EXPECT_EQ(completed, kValveCount) << describe(stopped);
  EXPECT_FALSE(contains(stopped.out, "TJV000999"));  // offline: not commanded
}

TEST_F(ValvectlEndToEnd, WatchAsJsonPrintsOneArrayPerRefreshAndEndsWithExitZeroOnCtrlC) {
  Subprocess watching(
      {VALVECTL_PATH, "--domain", domain_text(), "--json", "watch", "--interval", "100"});
  // Refreshes go on while the gateway is being discovered; wait for one that shows the valves.
  ASSERT_TRUE(watching.wait_for_stdout(codec::format_serial(kValveCount), 15s));
  watching.signal(SIGINT);
  const auto watched = watching.wait(15s);
  EXPECT_EQ(watched.exit_code, kExitOk) << describe(watched);
  const auto lines = split_lines(watched.out);
  ASSERT_FALSE(lines.empty());
  for (const auto& line : lines) EXPECT_TRUE(nlohmann::json::parse(line).is_array()) << line;
  EXPECT_GE(nlohmann::json::parse(lines.back()).size(), kValveCount);
}

TEST_F(ValvectlEndToEnd, WatchAsTextPrintsATablePerRefreshWithoutScreenControlIntoAPipe) {
  Subprocess watching({VALVECTL_PATH, "--domain", domain_text(), "watch", "--interval", "100",
                       "--title", "dashboard: http://127.0.0.1:8080/"});
  ASSERT_TRUE(watching.wait_for_stdout(codec::format_serial(kValveCount), 15s));
  watching.signal(SIGINT);
  const auto watched = watching.wait(15s);
  EXPECT_EQ(watched.exit_code, kExitOk) << describe(watched);
  EXPECT_TRUE(contains(
      watched.out, "dashboard: http://127.0.0.1:8080/\nvalvectl watch: domain " + domain_text()));
  EXPECT_TRUE(contains(watched.out,
                       "gateway " + gateway_->name() + " on sim:" + std::to_string(kValveCount)));
  EXPECT_TRUE(contains(watched.out, "SERIAL     ADDR  ONLINE"));
  EXPECT_FALSE(contains(watched.out, "\x1b["));
}

// The table shows position, temperature and voltage: a text watch or list follows only those
// (and the errors), and every gateway sends it seven samples fewer per valve as it joins, and
// no current, speed or other reply the table would not show.
TEST_F(ValvectlEndToEnd, AWatchAsTextFollowsOnlyTheTelemetryItsTableShows) {
  const int positions = gateway_->readers_of<ValvePosition>();
  const int errors = gateway_->readers_of<ValveError>();
  const int currents = gateway_->readers_of<ValveCurrent>();
  Subprocess watching({VALVECTL_PATH, "--domain", domain_text(), "watch", "--interval", "100"});
  ASSERT_TRUE(watching.wait_for_stdout(codec::format_serial(kValveCount), 15s));
  EXPECT_TRUE(eventually(
      [&] {
        return gateway_->readers_of<ValvePosition>() == positions + 1 &&
               gateway_->readers_of<ValveError>() == errors + 1;
      },
      10s));
  EXPECT_EQ(gateway_->readers_of<ValveCurrent>(), currents);
  watching.signal(SIGINT);
  const auto watched = watching.wait(15s);
  EXPECT_EQ(watched.exit_code, kExitOk) << describe(watched);
  // Its table is whole: position, temperature and voltage of TJV000001.
  EXPECT_TRUE(contains(watched.out, "0.0      25   12.0  -")) << watched.out;
}

TEST_F(ValvectlEndToEnd, WatchEndsByItselfAfterItsDuration) {
  const auto watched = valvectl({"--json", "watch", "--interval", "100", "--duration", "0.5"});
  EXPECT_EQ(watched.exit_code, kExitOk) << describe(watched);
  EXPECT_FALSE(split_lines(watched.out).empty()) << describe(watched);
}

}  // namespace
}  // namespace teejet::testing
