// The Simulator runtime end to end on a VirtualBus: a controller endpoint sends real frames and
// reads the replies. Time is a ManualClock; every wait is for a condition, with a deadline. No
// test measures how long anything takes: speed belongs to the benchmarks.

#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include <functional>
#include <optional>
#include <sstream>

#include "sim_test_support.hpp"
#include "support/eventually.hpp"
#include "teejet/can/virtual_bus.hpp"
#include "teejet/codec/codec.hpp"
#include "teejet/sim/simulator.hpp"

namespace teejet::sim::testing {
namespace {

using teejet::testing::eventually;

struct Received {
  std::uint8_t address;
  codec::FromValveMessage message;
  Timestamp stamp;  // the controller endpoint's wall clock when the frame arrived
};

template <class T>
bool is(const Received& received) {
  return std::holds_alternative<T>(received.message);
}

class SimRuntime : public ::testing::Test {
 protected:
  std::string bus_name =
      std::string("sim-") + ::testing::UnitTest::GetInstance()->current_test_info()->name();
  std::shared_ptr<ManualClock> clock = std::make_shared<ManualClock>(kWallT0, kT0);
  can::VirtualBus controller{bus_name, {.filters = can::controller_side_filters(), .clock = clock}};
  std::unique_ptr<Simulator> simulator;
  can::VirtualBus* simulator_bus = nullptr;  // owned by `simulator`

  void SetUp() override { ASSERT_TRUE(controller.open()); }
  void TearDown() override {
    if (simulator) simulator->stop();
  }

  SimulatorOptions options_for(std::vector<ValveConfig> valves) {
    SimulatorOptions options;
    options.valves = std::move(valves);
    options.clock = clock;
    options.max_wait = std::chrono::milliseconds(2);
    return options;
  }

  void start(SimulatorOptions options) {
    auto bus = std::make_unique<can::VirtualBus>(
        bus_name, can::VirtualBusOptions{.filters = can::valve_side_filters(), .clock = clock});
    simulator_bus = bus.get();
    simulator = std::make_unique<Simulator>(std::move(bus), std::move(options));
    const auto started = simulator->start();
    ASSERT_TRUE(started) << started.error().reason;
  }

  void send(std::uint8_t address, const codec::ToValveMessage& message) {
    const auto frame = codec::encode(address, message);
    ASSERT_TRUE(frame) << frame.error().reason;
    ASSERT_TRUE(controller.send(*frame));
  }

  // Sends and waits until the simulator has acted on the frame.
  void command(std::uint8_t address, const codec::ToValveMessage& message) {
    const auto before = simulator->frames_handled();
    send(address, message);
    ASSERT_TRUE(eventually([&] { return simulator->frames_handled() != before; }, kDeadline))
        << "frame not handled";
  }

  // The next valve frame, decoded; nullopt after the deadline.
  std::optional<Received> next(std::chrono::milliseconds within = kDeadline) {
    const auto frame = controller.receive(within);
    if (!frame) return std::nullopt;
    const auto decoded = codec::decode(frame->frame);
    EXPECT_TRUE(decoded) << decoded.error().reason;
    if (!decoded) return std::nullopt;
    return Received{decoded->route.valve_address,
                    std::get<codec::FromValveMessage>(decoded->message), frame->received};
  }

  // Frames up to and including the first one that matches; fails after the deadline.
  std::vector<Received> until(const std::function<bool(const Received&)>& match) {
    std::vector<Received> seen;
    const auto deadline = std::chrono::steady_clock::now() + kDeadline;
    while (std::chrono::steady_clock::now() < deadline) {
      auto frame = next(std::chrono::duration_cast<std::chrono::milliseconds>(
          deadline - std::chrono::steady_clock::now()));
      if (!frame) break;
      seen.push_back(*frame);
      if (match(seen.back())) return seen;
    }
    ADD_FAILURE() << "no matching frame within the deadline (" << seen.size() << " others)";
    return seen;
  }

  template <class T>
  T reply_of(std::uint8_t address, const codec::ToValveMessage& request) {
    send(address, request);
    const auto seen = until([&](const Received& r) {
      return r.address == address && std::holds_alternative<T>(r.message);
    });
    if (seen.empty() || !std::holds_alternative<T>(seen.back().message)) return T{};
    return std::get<T>(seen.back().message);
  }

  // Moves the clock to just before `due`, sees that the simulator has acted on that moment
  // without resending the position, then moves it onto `due` and expects the resend, stamped
  // `stamp` by the controller's endpoint as it arrives. (The clock stands still meanwhile.)
  void position_resent_exactly_at(SteadyTime due, Timestamp stamp) {
    clock->advance(due - std::chrono::nanoseconds(1) - clock->steady());
    for (const auto& r : drain(0xD8)) EXPECT_FALSE(is<codec::Position>(r)) << "sent early";
    clock->advance(std::chrono::nanoseconds(1));
    const auto seen = until([](const Received& r) { return is<codec::Position>(r); });
    ASSERT_FALSE(seen.empty());
    EXPECT_EQ(seen.back().stamp, stamp);
    EXPECT_EQ(seen.back().address, 0xD8);
  }

  // Every frame the simulator sends until it has acted on all that happened before (two round
  // trips: the replies of one loop turn are sent together).
  std::vector<Received> drain(std::uint8_t address) {
    std::vector<Received> seen;
    for (int round = 0; round < 2; ++round) {
      send(address, codec::RequestVersion{});
      auto part = until([&](const Received& r) {
        return r.address == address && std::holds_alternative<codec::VersionInfo>(r.message);
      });
      part.pop_back();
      seen.insert(seen.end(), part.begin(), part.end());
    }
    return seen;
  }
};

TEST_F(SimRuntime, ValvesAnnounceThemselvesAtTheirAddressesOnceASecond) {
  start(options_for({valve_with(200), valve_with(100)}));
  auto first = next();
  ASSERT_TRUE(first);
  EXPECT_EQ(first->address, 0xD8);
  EXPECT_EQ(first->message, (codec::FromValveMessage{codec::IAmHere{0, 100, false}}));
  clock->advance(kIAmHereStagger);
  auto second = next();
  ASSERT_TRUE(second);
  EXPECT_EQ(second->address, 0xD9);
  EXPECT_EQ(second->message, (codec::FromValveMessage{codec::IAmHere{0, 200, false}}));
  for (const auto& r : drain(0xD8)) EXPECT_FALSE(is<codec::IAmHere>(r));  // not before a second
  clock->advance(std::chrono::seconds(1) - kIAmHereStagger);
  auto again = next();
  ASSERT_TRUE(again);
  EXPECT_EQ(again->address, 0xD8);
  EXPECT_TRUE(is<codec::IAmHere>(*again));
}

TEST_F(SimRuntime, RequestsOverTheBusAreAnsweredFromTheRightAddress) {
  start(options_for({valve_with(1, 12.3), valve_with(2, 45.6)}));
  EXPECT_EQ(reply_of<codec::Position>(0xD9, codec::RequestPosition{0}), codec::Position{45.6});
  EXPECT_EQ(reply_of<codec::Position>(0xD8, codec::RequestPosition{0}), codec::Position{12.3});
  EXPECT_EQ(reply_of<codec::VersionInfo>(0xD8, codec::RequestVersion{}),
            (codec::VersionInfo{{1, 0, 0}, {1, 0, 0}}));
  EXPECT_EQ(reply_of<codec::BaudRateReply>(0xD9, codec::BaudRate{codec::BaudAction::kSet, 500000}),
            codec::BaudRateReply{500000});
  EXPECT_EQ(
      reply_of<codec::BaudRateReply>(0xD9, codec::BaudRate{codec::BaudAction::kRequest, 250000}),
      codec::BaudRateReply{500000});
  EXPECT_EQ(
      reply_of<codec::BaudRateReply>(0xD8, codec::BaudRate{codec::BaudAction::kRequest, 250000}),
      codec::BaudRateReply{250000});
}

TEST_F(SimRuntime, ATargetMoveOverTheBusFollowsTheClock) {
  start(options_for({valve_with(1)}));
  command(0xD8, codec::TargetDegrees{100, codec::TargetDirection::kOpen, 90.0});
  clock->advance(std::chrono::milliseconds(500));
  EXPECT_EQ(reply_of<codec::Position>(0xD8, codec::RequestPosition{0}), codec::Position{45.0});
  EXPECT_EQ(reply_of<codec::SpeedDirection>(0xD8, codec::RequestSpeedDirection{0}),
            (codec::SpeedDirection{100, codec::Direction::kOpen, codec::Rotation::kClockwise}));
  clock->advance(std::chrono::milliseconds(700));
  EXPECT_EQ(reply_of<codec::Position>(0xD8, codec::RequestPosition{0}), codec::Position{90.0});
  EXPECT_EQ(reply_of<codec::RunTime>(0xD8, codec::RequestRunTime{0}), codec::RunTime{1});
  EXPECT_EQ(reply_of<codec::CycleCounts>(0xD8, codec::RequestCycleCounts{0}),
            codec::CycleCounts{1});
}

TEST_F(SimRuntime, AutomaticResendFollowsTheClockAndStopsOnZero) {
  start(options_for({valve_with(1)}));
  command(0xD8, codec::Manual{100, codec::Direction::kOpen});
  EXPECT_EQ(reply_of<codec::Position>(0xD8, codec::RequestPosition{1}), codec::Position{0.0});
  for (int tenth = 1; tenth <= 5; ++tenth) {
    clock->advance(std::chrono::milliseconds(100));
    const auto seen = until([](const Received& r) { return is<codec::Position>(r); });
    ASSERT_FALSE(seen.empty());
    EXPECT_EQ(seen.back().message, (codec::FromValveMessage{codec::Position{9.0 * tenth}}));
  }
  EXPECT_EQ(reply_of<codec::Position>(0xD8, codec::RequestPosition{0}), codec::Position{45.0});
  clock->advance(std::chrono::milliseconds(300));
  for (const auto& r : drain(0xD8)) EXPECT_FALSE(is<codec::Position>(r));
}

TEST_F(SimRuntime, AValveAddedAtRunTimeReshufflesTheAddresses) {
  start(options_for({valve_with(10, 10.0), valve_with(30, 30.0)}));
  std::vector<AddressChange> changes;
  ASSERT_TRUE(simulator->add_valve(valve_with(20, 20.0), &changes));
  EXPECT_EQ(changes, (std::vector<AddressChange>{{20, std::nullopt, 0xD9}, {30, 0xD9, 0xDA}}));
  EXPECT_EQ(simulator->assignments(),
            (std::vector<Assignment>{{10, 0xD8}, {20, 0xD9}, {30, 0xDA}}));
  clock->advance(kIAmHereStagger);  // rank 1 announces one stagger after the change
  const auto announced = until([](const Received& r) {
    return r.address == 0xD9 && r.message == codec::FromValveMessage{codec::IAmHere{0, 20, false}};
  });
  EXPECT_FALSE(announced.empty());
  EXPECT_EQ(reply_of<codec::Position>(0xD9, codec::RequestPosition{0}), codec::Position{20.0});
  EXPECT_EQ(reply_of<codec::Position>(0xDA, codec::RequestPosition{0}), codec::Position{30.0});
  clock->advance(kIAmHereStagger);
  EXPECT_FALSE(until([](const Received& r) {
                 return r.address == 0xDA &&
                        r.message == codec::FromValveMessage{codec::IAmHere{0, 30, false}};
               }).empty());
}

TEST_F(SimRuntime, AReplacedValveFallsSilentAndItsSuccessorClaimsAnAddressWithItsSettings) {
  auto old_valve = valve_with(30, 30.0);
  old_valve.opened_degrees = 80.0;
  start(options_for({valve_with(10, 10.0), old_valve}));
  EXPECT_FALSE(simulator->replace_valve(31, 40));  // no such valve
  EXPECT_FALSE(simulator->replace_valve(30, 10));  // the new serial is taken
  EXPECT_EQ(simulator->assignments(), (std::vector<Assignment>{{10, 0xD8}, {30, 0xD9}}));
  ASSERT_TRUE(simulator->replace_valve(30, 20));
  EXPECT_EQ(simulator->assignments(), (std::vector<Assignment>{{10, 0xD8}, {20, 0xD9}}));
  EXPECT_EQ(simulator->inspect([](const ValveBank& bank) {
    return bank.valve_with_serial(20)->config().opened_degrees;
  }),
            80.0);
  clock->advance(kIAmHereStagger);
  EXPECT_FALSE(until([](const Received& r) {
                 return r.address == 0xD9 &&
                        r.message == codec::FromValveMessage{codec::IAmHere{0, 20, false}};
               }).empty());
}

TEST_F(SimRuntime, InjectedErrorsRepeatUntilClearErrorsOverTheBus) {
  auto options = options_for({valve_with(1), valve_with(2)});
  options.errors.push_back({2, codec::LowVoltageError{9.5, 10.0}});
  start(std::move(options));
  auto seen = until([](const Received& r) { return is<codec::LowVoltageError>(r); });
  ASSERT_FALSE(seen.empty());
  EXPECT_EQ(seen.back().address, 0xD9);
  EXPECT_EQ(seen.back().message, (codec::FromValveMessage{codec::LowVoltageError{9.5, 10.0}}));
  ASSERT_TRUE(simulator->inject_error(1, codec::HighCurrentError{2.5, 2.0}));
  EXPECT_FALSE(until([](const Received& r) { return is<codec::HighCurrentError>(r); }).empty());
  EXPECT_FALSE(simulator->inject_error(9, codec::HighCurrentError{2.5, 2.0}));
  clock->advance(std::chrono::seconds(1));
  seen = until([](const Received& r) { return is<codec::HighCurrentError>(r); });
  EXPECT_EQ(seen.back().address, 0xD8);

  command(0xD9, codec::ClearErrors{});
  command(0xD8, codec::ClearErrors{});
  drain(0xD8);
  clock->advance(std::chrono::seconds(3));
  for (const auto& r : drain(0xD8)) {
    EXPECT_FALSE(is<codec::LowVoltageError>(r) || is<codec::HighCurrentError>(r));
  }
}

TEST_F(SimRuntime, FramesForOtherAddressesAndUndecodableFramesAreIgnored) {
  start(options_for({valve_with(1)}));
  command(0xE0, codec::RequestVersion{});
  codec::CanFrame unknown{.id = codec::to_valve_id(0xD8), .dlc = 1};
  unknown.data[0] = 0x42;
  const auto before = simulator->frames_handled();
  ASSERT_TRUE(controller.send(unknown));
  EXPECT_EQ(reply_of<codec::VersionInfo>(0xD8, codec::RequestVersion{}),
            (codec::VersionInfo{{1, 0, 0}, {1, 0, 0}}));
  EXPECT_EQ(simulator->frames_handled(), before + 2);
}

TEST_F(SimRuntime, VerboseLogsEveryFrameDecoded) {
  std::ostringstream log;
  auto logger = std::make_shared<spdlog::logger>(
      "sim-test", std::make_shared<spdlog::sinks::ostream_sink_mt>(log));
  logger->set_pattern("%v");
  auto options = options_for({valve_with(1, 90.0)});
  options.verbose = true;
  options.logger = logger;
  start(std::move(options));
  EXPECT_EQ(reply_of<codec::Position>(0xD8, codec::RequestPosition{0}), codec::Position{90.0});
  simulator->stop();
  const auto text = log.str();
  EXPECT_NE(text.find("rx (1700000000.000000) " + bus_name +
                      " 18EFD8D5#1100FFFFFFFFFFFF  0xD8 request_position resend_tenths=0"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("tx (1700000000.000000) " + bus_name +
                      " 18EFD5D8#020384FFFFFFFFFF  0xD8 position degrees=90.0"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("i_am_here part_number=0 serial=TJV000001 boot_mode=false"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("TJV000001 at address 0xD8"), std::string::npos) << text;
}

TEST(SimDescribeFrame, CandumpTextThenTheDecodedMessageOrWhyNot) {
  const auto frame = codec::encode(0xD9, codec::RunCurrent{0.25, 1.5}).value();
  EXPECT_EQ(describe_frame(kWallT0 + std::chrono::microseconds(123), "vcan0", frame),
            "(1700000000.000123) vcan0 18EFD5D9#0500190096FFFFFF  0xD9 run_current amps=0.25 "
            "last_running_amps=1.5");
  const codec::CanFrame foreign{.id = 0x18FEF100, .dlc = 1};
  EXPECT_EQ(
      describe_frame(kWallT0, "can0", foreign).rfind("(1700000000.000000) can0 18FEF100#00  (", 0),
      0u);
}

TEST_F(SimRuntime, StartFailsVisiblyWhenTheBusCannotOpenOrTheBankIsBad) {
  Simulator unnamed(std::make_unique<can::VirtualBus>(""), options_for({valve_with(1)}));
  const auto refused = unnamed.start();
  EXPECT_FALSE(refused);
  EXPECT_NE(refused.error().reason.find("cannot open"), std::string::npos)
      << refused.error().reason;
  EXPECT_FALSE(unnamed.started());

  Simulator empty(std::make_unique<can::VirtualBus>(bus_name), options_for({}));
  EXPECT_FALSE(empty.start());
  auto options = options_for({valve_with(1)});
  options.errors.push_back({7, codec::LowVoltageError{9, 10}});
  Simulator wrong_serial(std::make_unique<can::VirtualBus>(bus_name), std::move(options));
  EXPECT_FALSE(wrong_serial.start());
}

TEST_F(SimRuntime, EachResendIsSentAtItsDueTimeAndNotBefore) {
  start(options_for({valve_with(1)}));
  const SteadyTime requested = clock->steady();
  send(0xD8, codec::RequestPosition{1});
  const auto answer = until([](const Received& r) { return is<codec::Position>(r); });
  ASSERT_FALSE(answer.empty());
  EXPECT_EQ(answer.back().stamp, wall_at(requested));
  for (int tenth = 1; tenth <= 10; ++tenth) {
    const SteadyTime due = requested + tenth * kTenthOfSecond;
    position_resent_exactly_at(due, wall_at(due));
  }
}

// An NTP or GPS step of the wall clock shows in the stamps and nowhere else.
TEST_F(SimRuntime, AWallClockStepMovesTheStampsButNotTheSchedule) {
  start(options_for({valve_with(1)}));
  const SteadyTime requested = clock->steady();
  send(0xD8, codec::RequestPosition{1});
  ASSERT_FALSE(until([](const Received& r) { return is<codec::Position>(r); }).empty());
  clock->step_wall(-std::chrono::hours(1));
  const SteadyTime first = requested + kTenthOfSecond;
  position_resent_exactly_at(first, wall_at(first) - std::chrono::hours(1));
  clock->step_wall(std::chrono::hours(3));
  const SteadyTime second = requested + 2 * kTenthOfSecond;
  position_resent_exactly_at(second, wall_at(second) + std::chrono::hours(2));
}

TEST_F(SimRuntime, StopEndsTheThreadAndClosesTheBusAndStartRunsAgain) {
  start(options_for({valve_with(1, 12.3)}));
  EXPECT_TRUE(simulator->started());
  simulator->stop();
  EXPECT_FALSE(simulator->started());
  const auto refused = simulator_bus->send(codec::encode(0xD8, codec::Stop{}).value());
  ASSERT_FALSE(refused);
  EXPECT_EQ(refused.error().code, ErrorCode::kUnavailable) << refused.error().reason;
  simulator->stop();  // idempotent
  EXPECT_FALSE(simulator->started());

  const auto restarted = simulator->start();
  ASSERT_TRUE(restarted) << restarted.error().reason;
  EXPECT_TRUE(simulator->started());
  EXPECT_EQ(reply_of<codec::Position>(0xD8, codec::RequestPosition{0}), codec::Position{12.3});
}

TEST(SimReceiveTimeout, WaitsUntilTheNextEventRoundedUpAndAtMostMaxWait) {
  using std::chrono::milliseconds;
  using std::chrono::nanoseconds;
  const milliseconds max_wait(50);
  EXPECT_EQ(receive_timeout(std::nullopt, kT0, max_wait), max_wait);
  EXPECT_EQ(receive_timeout(kT0 + milliseconds(37), kT0, max_wait), milliseconds(37));
  EXPECT_EQ(receive_timeout(kT0 + milliseconds(37) + nanoseconds(1), kT0, max_wait),
            milliseconds(38));  // never wakes before the event
  EXPECT_EQ(receive_timeout(kT0 + nanoseconds(1), kT0, max_wait), milliseconds(1));
  EXPECT_EQ(receive_timeout(kT0, kT0, max_wait), milliseconds(0));
  EXPECT_EQ(receive_timeout(kT0 - std::chrono::seconds(1), kT0, max_wait), milliseconds(0));
  EXPECT_EQ(receive_timeout(kT0 + milliseconds(50), kT0, max_wait), max_wait);
  EXPECT_EQ(receive_timeout(kT0 + std::chrono::hours(24 * 365), kT0, max_wait), max_wait);
}

TEST(SimReceiveTimeout, PeriodicMessagesWaitForTheNextTimerTick) {
  using std::chrono::milliseconds;
  using std::chrono::nanoseconds;
  const milliseconds max_wait(50), tick(10);
  const SteadyTime on_tick(std::chrono::seconds(1000));  // a multiple of the tick
  EXPECT_EQ(receive_timeout(on_tick + milliseconds(3), on_tick, max_wait, tick), milliseconds(10));
  EXPECT_EQ(receive_timeout(on_tick + milliseconds(10), on_tick, max_wait, tick),
            milliseconds(10));  // due on a tick: that tick
  EXPECT_EQ(receive_timeout(on_tick + milliseconds(10) + nanoseconds(1), on_tick, max_wait, tick),
            milliseconds(20));
  EXPECT_EQ(receive_timeout(on_tick + milliseconds(8), on_tick + milliseconds(7), max_wait, tick),
            milliseconds(3));  // woken by a frame between ticks: back on the grid
  EXPECT_EQ(receive_timeout(on_tick - milliseconds(1), on_tick, max_wait, tick), milliseconds(0));
  EXPECT_EQ(receive_timeout(on_tick + milliseconds(41), on_tick, max_wait, tick), max_wait);
  // Before the clock's epoch (a test clock may start there) the grid is the same.
  const SteadyTime before_epoch(-std::chrono::seconds(5));
  EXPECT_EQ(receive_timeout(before_epoch + milliseconds(3), before_epoch, max_wait, tick),
            milliseconds(10));
}

// With the real clocks, nobody moves time and nobody sends: the thread wakes for each resend on
// its own. Counts and values only; how punctually is the benchmarks' business.
TEST(SimRuntimeRealTime, ResendsComeOnTheirOwnWithTheSystemClock) {
  const std::string name = "sim-real-time";
  can::VirtualBus controller(name, {.filters = can::controller_side_filters()});
  ASSERT_TRUE(controller.open());
  SimulatorOptions options;
  options.valves = {valve_with(1, 33.3)};
  Simulator simulator(std::make_unique<can::VirtualBus>(
                          name, can::VirtualBusOptions{.filters = can::valve_side_filters()}),
                      options);
  ASSERT_TRUE(simulator.start());
  ASSERT_TRUE(controller.send(codec::encode(0xD8, codec::RequestPosition{1}).value()));
  int positions = 0;
  const auto deadline = std::chrono::steady_clock::now() + kDeadline;
  while (positions < 11 && std::chrono::steady_clock::now() < deadline) {
    const auto frame = controller.receive(std::chrono::milliseconds(500));
    if (!frame) continue;
    const auto decoded = codec::decode(frame->frame);
    ASSERT_TRUE(decoded) << decoded.error().reason;
    const auto& message = std::get<codec::FromValveMessage>(decoded->message);
    if (!std::holds_alternative<codec::Position>(message)) continue;
    EXPECT_EQ(decoded->route.valve_address, 0xD8);
    EXPECT_EQ(std::get<codec::Position>(message), codec::Position{33.3});
    ++positions;
  }
  EXPECT_EQ(positions, 11);  // the answer and ten resends
}

}  // namespace
}  // namespace teejet::sim::testing
