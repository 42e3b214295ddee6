// Valve faults the simulator can play: power gone and back (in application or boot code), a
// valve claiming an address another holds, and the churn that does the first at random.

#include <gtest/gtest.h>

#include "sim_test_support.hpp"
#include "support/eventually.hpp"
#include "teejet/can/virtual_bus.hpp"
#include "teejet/sim/simulator.hpp"
#include "teejet/sim/valve_bank.hpp"

namespace teejet::sim::testing {
namespace {

using teejet::testing::eventually;

const codec::TargetDegrees kOpenTo90{100, codec::TargetDirection::kOpen, 90.0};

TEST(SimValvePower, PowerOffStopsTheMotorAndSilencesTheValve) {
  SimulatedValve valve(valve_with(1));
  valve.schedule_i_am_here(kT0);
  valve.handle(codec::RequestPosition{1}, kT0);  // resent every 100 ms
  valve.inject_error(codec::HighVoltageError{16.2, 15.5}, kT0);
  valve.handle(kOpenTo90, kT0);
  valve.power_off(at_ms(500));  // 45 degrees into the move
  EXPECT_FALSE(valve.powered());
  EXPECT_FALSE(valve.running(at_ms(600)));
  EXPECT_DOUBLE_EQ(valve.position(at_ms(5000)), 45.0);
  EXPECT_EQ(valve.next_due(), std::nullopt);
  EXPECT_TRUE(valve.advance(at_ms(10'000)).empty());
  EXPECT_TRUE(valve.handle(codec::RequestVersion{}, at_ms(10'000)).empty());
  EXPECT_TRUE(valve.handle(kOpenTo90, at_ms(10'000)).empty());
  EXPECT_DOUBLE_EQ(valve.position(at_ms(20'000)), 45.0);  // nothing moved it while off
}

TEST(SimValvePower, PowerOnKeepsTheCountersAndStartsAsAfterAPowerUp) {
  SimulatedValve valve(valve_with(1));
  valve.handle(codec::RequestPosition{1}, kT0);
  valve.inject_error(codec::LowVoltageError{9.0, 10.0}, kT0);
  valve.handle(kOpenTo90, kT0);
  valve.power_off(at_ms(2000));  // the move ended at 1 s: 1 s of run time, 1 cycle
  valve.power_on();
  valve.schedule_i_am_here(at_ms(3000));
  EXPECT_TRUE(valve.powered());
  EXPECT_FALSE(valve.boot_mode());
  EXPECT_EQ(valve.cycle_count(), 1u);
  EXPECT_DOUBLE_EQ(valve.run_time_seconds(at_ms(3000)), 1.0);
  EXPECT_DOUBLE_EQ(valve.position(at_ms(3000)), 90.0);
  EXPECT_EQ(valve.resend_period(codec::RequestPosition::kId), std::nullopt);
  EXPECT_FALSE(valve.error_latched("low_voltage"));
  EXPECT_EQ(valve.direction(), codec::Direction::kClose);
  // Last running amps is 0 again until the valve runs at 100 %.
  EXPECT_EQ(only<codec::RunCurrent>(valve.handle(codec::RequestCurrent{0}, at_ms(3000))),
            (codec::RunCurrent{0.0, 0.0}));
  EXPECT_EQ(only<codec::IAmHere>(valve.advance(at_ms(3000))), (codec::IAmHere{0, 1, false}));
  // And it works again.
  valve.handle(codec::TargetDegrees{100, codec::TargetDirection::kClose, 0.0}, at_ms(3000));
  EXPECT_DOUBLE_EQ(valve.position(at_ms(3500)), 45.0);
}

TEST(SimValvePower, BootCodeAnnouncesItselfAnswersVersionAndBaudRateAndDoesNotMove) {
  SimulatedValve valve(valve_with(7));
  valve.power_off(kT0);
  valve.power_on(/*boot_mode=*/true);
  valve.schedule_i_am_here(at_ms(10));
  EXPECT_TRUE(valve.boot_mode());
  EXPECT_EQ(only<codec::IAmHere>(valve.advance(at_ms(10))), (codec::IAmHere{0, 7, true}));
  EXPECT_TRUE(valve.handle(kOpenTo90, at_ms(20)).empty());
  EXPECT_TRUE(valve.handle(codec::Manual{100, codec::Direction::kOpen}, at_ms(20)).empty());
  EXPECT_TRUE(valve.handle(codec::RequestPosition{1}, at_ms(20)).empty());
  EXPECT_FALSE(valve.running(at_ms(500)));
  EXPECT_DOUBLE_EQ(valve.position(at_ms(1000)), 0.0);
  EXPECT_EQ(valve.cycle_count(), 0u);
  EXPECT_EQ(valve.resend_period(codec::RequestPosition::kId), std::nullopt);
  const auto version = only<codec::VersionInfo>(valve.handle(codec::RequestVersion{}, at_ms(30)));
  EXPECT_EQ(version.application, valve.config().application_version);
  EXPECT_EQ(only<codec::BaudRateReply>(valve.handle(
                codec::BaudRate{codec::BaudAction::kRequest, codec::kBitRate250k}, at_ms(30))),
            (codec::BaudRateReply{codec::kBitRate250k}));
  // Restarted into the application, it moves.
  valve.power_off(at_ms(2000));
  valve.power_on();
  EXPECT_FALSE(valve.boot_mode());
  valve.handle(kOpenTo90, at_ms(2000));
  EXPECT_DOUBLE_EQ(valve.position(at_ms(2500)), 45.0);
}

std::vector<ValveConfig> four_valves() {
  return {valve_with(100), valve_with(200), valve_with(300), valve_with(400)};
}

TEST(SimValveBankPower, AValveGoingOffLeavesTheRankingAndTheValvesAboveMoveDown) {
  ValveBank bank;
  ASSERT_TRUE(bank.power_up(four_valves(), kT0));
  bank.advance(at_ms(200));  // the power-up I'm Here of all four
  std::vector<AddressChange> changes;
  ASSERT_TRUE(bank.power_off(200, at_ms(400), &changes));
  EXPECT_EQ(changes, (std::vector<AddressChange>{{300, 0xDA, 0xD9}, {400, 0xDB, 0xDA}}));
  EXPECT_EQ(bank.assignments(), (std::vector<Assignment>{{100, 0xD8}, {300, 0xD9}, {400, 0xDA}}));
  EXPECT_EQ(bank.address_of(200), std::nullopt);
  EXPECT_EQ(bank.size(), 4u);
  // The moved valves announce at their new addresses (ranks 1 and 2), the off one never.
  auto out = bank.advance(at_ms(400) + kIAmHereStagger);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].address, 0xD9);
  EXPECT_EQ(out[0].message, (codec::FromValveMessage{codec::IAmHere{0, 300, false}}));
  out = bank.advance(at_ms(400) + 2 * kIAmHereStagger);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].address, 0xDA);
  for (const auto& sent : bank.advance(at_ms(5000))) {
    EXPECT_NE(std::get<codec::IAmHere>(sent.message).serial, 200u);
  }
  EXPECT_EQ(bank.handle(0xD9, codec::RequestVersion{}, at_ms(5000)).size(), 1u);  // 300 answers
}

TEST(SimValveBankPower, AValveComingBackIsRankedLikeAnAddedOne) {
  ValveBank bank;
  ASSERT_TRUE(bank.power_up(four_valves(), kT0));
  ASSERT_TRUE(bank.power_off(200, at_ms(400)));
  bank.advance(at_ms(900));
  std::vector<AddressChange> changes;
  ASSERT_TRUE(bank.power_on(200, /*boot_mode=*/true, at_ms(5000), &changes));
  EXPECT_EQ(changes, (std::vector<AddressChange>{
                         {200, std::nullopt, 0xD9}, {300, 0xD9, 0xDA}, {400, 0xDA, 0xDB}}));
  EXPECT_EQ(bank.assignments(),
            (std::vector<Assignment>{{100, 0xD8}, {200, 0xD9}, {300, 0xDA}, {400, 0xDB}}));
  bank.advance(at_ms(5000));  // the once-a-second I'm Here of 100, which kept its rhythm
  const auto out = bank.advance(at_ms(5000) + kIAmHereStagger);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].address, 0xD9);
  EXPECT_EQ(out[0].message, (codec::FromValveMessage{codec::IAmHere{0, 200, true}}));
}

TEST(SimValveBankPower, UnknownSerialsAndRepeatedSwitchingAreRefusedWithAReason) {
  ValveBank bank;
  ASSERT_TRUE(bank.power_up(four_valves(), kT0));
  const auto unknown = bank.power_off(999, kT0);
  ASSERT_FALSE(unknown);
  EXPECT_EQ(unknown.error().reason, "no valve with serial TJV000999");
  const auto on = bank.power_on(100, false, kT0);
  ASSERT_FALSE(on);
  EXPECT_EQ(on.error().reason, "TJV000100 is already on");
  ASSERT_TRUE(bank.power_off(100, kT0));
  const auto off = bank.power_off(100, kT0);
  ASSERT_FALSE(off);
  EXPECT_EQ(off.error().reason, "TJV000100 is already off");
  EXPECT_FALSE(bank.power_on(999, false, kT0));
  EXPECT_FALSE(bank.force_address(100, 0xD8, kT0));  // off
  EXPECT_FALSE(bank.force_address(200, 0xD0, kT0));  // not a valve address
}

TEST(SimValveBankPower, AForcedAddressIsSharedByTwoValvesUntilTheBankIsReranked) {
  ValveBank bank;
  ASSERT_TRUE(bank.power_up(four_valves(), kT0));
  bank.advance(at_ms(200));
  ASSERT_TRUE(bank.force_address(300, 0xD9, at_ms(500)));
  EXPECT_EQ(bank.assignments(),
            (std::vector<Assignment>{{100, 0xD8}, {200, 0xD9}, {300, 0xD9}, {400, 0xDB}}));
  // It announces at once at the contested address, and both valves answer there.
  const auto out = bank.advance(at_ms(500));
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].address, 0xD9);
  EXPECT_EQ(out[0].message, (codec::FromValveMessage{codec::IAmHere{0, 300, false}}));
  EXPECT_EQ(bank.handle(0xD9, codec::RequestVersion{}, at_ms(600)).size(), 2u);
  EXPECT_TRUE(bank.handle(0xDA, codec::RequestVersion{}, at_ms(600)).empty());
  // A re-rank (here a valve going off) ends it: the arbitration rule holds again.
  ASSERT_TRUE(bank.power_off(100, at_ms(700)));
  EXPECT_EQ(bank.assignments(), (std::vector<Assignment>{{200, 0xD8}, {300, 0xD9}, {400, 0xDA}}));
}

// ---- The churn, on the runtime -------------------------------------------------------------

class SimChurn : public ::testing::Test {
 protected:
  std::shared_ptr<ManualClock> clock = std::make_shared<ManualClock>(kWallT0, kT0);
  int instances = 0;

  std::unique_ptr<Simulator> start(std::uint64_t seed, std::size_t valves = 8) {
    SimulatorOptions options;
    for (std::uint32_t serial = 1; serial <= valves; ++serial) {
      options.valves.push_back(valve_with(serial));
    }
    options.clock = clock;
    options.max_wait = std::chrono::milliseconds(2);
    options.churn = {
        .period = std::chrono::seconds(10), .off_for = std::chrono::seconds(4), .seed = seed};
    auto simulator = std::make_unique<Simulator>(
        std::make_unique<can::VirtualBus>(
            std::string("churn-") +
                ::testing::UnitTest::GetInstance()->current_test_info()->name() + "-" +
                std::to_string(++instances),
            can::VirtualBusOptions{.filters = can::valve_side_filters(), .clock = clock}),
        std::move(options));
    EXPECT_TRUE(simulator->start());
    return simulator;
  }

  // The serial that is off, once the simulator has acted on the clock; 0 when all are on.
  static std::uint32_t missing(const Simulator& simulator, std::size_t valves) {
    const auto on = simulator.assignments();
    if (on.size() == valves) return 0;
    for (std::uint32_t serial = 1; serial <= valves; ++serial) {
      if (std::none_of(on.begin(), on.end(),
                       [&](const Assignment& a) { return a.serial == serial; })) {
        return serial;
      }
    }
    return 0;
  }
};

TEST_F(SimChurn, EveryPeriodOneValveGoesOffAndComesBackTheSameForTheSameSeed) {
  auto first = start(42);
  std::vector<std::uint32_t> picked_first;
  std::vector<std::uint32_t> picked_second;
  auto second = start(42);
  auto other = start(7);
  std::vector<std::uint32_t> picked_other;
  for (int cycle = 1; cycle <= 6; ++cycle) {
    clock->advance(std::chrono::seconds(10) - (cycle == 1 ? Duration{0} : std::chrono::seconds(4)));
    for (auto* simulator : {first.get(), second.get(), other.get()}) {
      ASSERT_TRUE(eventually(
          [&] { return simulator->churn_count() == static_cast<std::uint64_t>(cycle); }, kDeadline))
          << "cycle " << cycle;
      ASSERT_TRUE(eventually([&] { return simulator->assignments().size() == 7; }, kDeadline));
    }
    picked_first.push_back(missing(*first, 8));
    picked_second.push_back(missing(*second, 8));
    picked_other.push_back(missing(*other, 8));
    clock->advance(std::chrono::seconds(4));  // off_for later all are back
    for (auto* simulator : {first.get(), second.get(), other.get()}) {
      ASSERT_TRUE(eventually([&] { return simulator->assignments().size() == 8; }, kDeadline));
      EXPECT_EQ(simulator->churn_count(), static_cast<std::uint64_t>(cycle));
    }
  }
  EXPECT_EQ(picked_first, picked_second);
  EXPECT_NE(picked_first, picked_other);
  for (const auto serial : picked_first) EXPECT_NE(serial, 0u);
}

TEST_F(SimChurn, APeriodThatEndsWhileItsValveIsStillOffIsSkipped) {
  SimulatorOptions options;
  options.valves = {valve_with(1), valve_with(2)};
  options.clock = clock;
  options.max_wait = std::chrono::milliseconds(2);
  options.churn = {
      .period = std::chrono::seconds(1), .off_for = std::chrono::seconds(3), .seed = 1};
  Simulator simulator(std::make_unique<can::VirtualBus>(
                          "churn-skip", can::VirtualBusOptions{.filters = can::valve_side_filters(),
                                                               .clock = clock}),
                      std::move(options));
  ASSERT_TRUE(simulator.start());
  clock->advance(std::chrono::seconds(1));
  ASSERT_TRUE(eventually([&] { return simulator.assignments().size() == 1; }, kDeadline));
  const auto sent = simulator.frames_sent();
  clock->advance(std::chrono::seconds(2));  // two more periods end; the valve is still off
  // The I'm Here due at 3 s goes out in the same turn of the loop as the churn's look at 3 s.
  ASSERT_TRUE(eventually([&] { return simulator.frames_sent() > sent; }, kDeadline));
  EXPECT_EQ(simulator.assignments().size(), 1u);
  EXPECT_EQ(simulator.churn_count(), 1u);
  clock->advance(std::chrono::seconds(1));  // back at 4 s, and that period's valve goes off
  ASSERT_TRUE(eventually([&] { return simulator.churn_count() == 2; }, kDeadline));
  EXPECT_EQ(simulator.assignments().size(), 1u);
}

TEST_F(SimChurn, AChurnWithoutAnOffTimeIsRefused) {
  SimulatorOptions options;
  options.valves = {valve_with(1)};
  options.churn = {.period = std::chrono::seconds(1), .off_for = Duration{0}, .seed = 1};
  Simulator simulator(
      std::make_unique<can::VirtualBus>(
          "churn-bad", can::VirtualBusOptions{.filters = can::valve_side_filters()}),
      std::move(options));
  const auto started = simulator.start();
  ASSERT_FALSE(started);
  EXPECT_NE(started.error().reason.find("churn"), std::string::npos) << started.error().reason;
}

}  // namespace
}  // namespace teejet::sim::testing
