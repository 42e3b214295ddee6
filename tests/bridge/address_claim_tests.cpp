// The gateway engine on a bus shared with other ISOBUS ECUs, seen from another ECU's place on a
// virtual bus: the claim before anything else, commands waiting out the 250 ms after it, answers
// to requests, giving 0xD5 up to a higher-priority NAME (commands REJECTED naming it, nothing
// sent) and taking it back, a second ECU at 0xD5, ECUs claiming where valves live, the claim
// after the bus recovers, and what GatewayStatus says of it all.

#include <gtest/gtest.h>

#include <algorithm>

#include "support/recording_sink.hpp"
#include "support/valve_commands.hpp"
#include "teejet/bridge/bridge.hpp"
#include "teejet/can/virtual_bus.hpp"
#include "teejet/dds/names.hpp"

namespace teejet::bridge {
namespace {

using namespace std::chrono_literals;

using teejet::testing::move_to;
using teejet::testing::RecordingSink;

constexpr Timestamp kStart{1'700'000'000s};

isobus::Name gateway_name() {
  auto name = isobus::ClaimConfig::default_name();
  name.identity_number = 0x100;
  return name;
}
isobus::Name winner() {  // higher priority: a lower value
  auto name = gateway_name();
  name.identity_number = 0x0FF;
  return name;
}

class AddressClaimTest : public ::testing::Test {
 protected:
  AddressClaimTest() {
    EXPECT_TRUE(gateway_bus.open());
    EXPECT_TRUE(other_ecu.open());
  }

  BridgeConfig config() {
    BridgeConfig c;
    c.gateway_name = "gw-claim";
    c.can_interface = "virtual:" + bus_name;
    c.isobus.name = gateway_name();
    return c;
  }

  // Frames the bridge sent, as another ECU on the bus hears them.
  std::vector<codec::CanFrame> heard() {
    std::vector<codec::CanFrame> frames;
    while (auto f = other_ecu.receive(0ms)) frames.push_back(f->frame);
    return frames;
  }
  static std::vector<std::uint32_t> ids(const std::vector<codec::CanFrame>& frames) {
    std::vector<std::uint32_t> found;
    for (const auto& f : frames) found.push_back(f.id);
    return found;
  }

  // The other ECU sends `frame` at `when`; the bridge takes what its filters let through.
  void send_at(Bridge& bridge, Timestamp when, const codec::CanFrame& frame) {
    at(when);
    ASSERT_TRUE(other_ecu.send(frame));
    while (auto f = gateway_bus.receive(0ms)) {
      f->received = clock->wall();  // the virtual bus stamps on the system clock
      bridge.on_frame(*f);
    }
  }
  void at(Timestamp when) {
    ASSERT_GE(when, clock->wall());
    clock->advance(when - clock->wall());
  }
  void tick_at(Bridge& bridge, Timestamp when) {
    at(when);
    bridge.tick();
  }
  void announce_valve(Bridge& bridge, Timestamp when) {
    send_at(bridge, when,
            codec::encode(0xD8, codec::FromValveMessage{codec::IAmHere{0x123, 42, false}}).value());
  }
  GatewayStatus last_status() const { return sink.gateway_statuses().back(); }

  std::string bus_name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
  can::VirtualBus gateway_bus{bus_name, {.filters = frames_to_hear(BridgeConfig{})}};
  can::VirtualBus other_ecu{bus_name, {}};
  RecordingSink sink;
  std::shared_ptr<ManualClock> clock = std::make_shared<ManualClock>(kStart);
};

TEST_F(AddressClaimTest, ClaimsFirstAndSendsNoValveFrameUntil250msLater) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  EXPECT_EQ(ids(heard()), (std::vector<std::uint32_t>{0x18EAFFFE, 0x18EEFFD5}));
  EXPECT_EQ(bridge.claim_state(), isobus::ClaimState::kClaiming);
  // A valve appears 100 ms in: its polls wait; a command for it waits too, unanswered.
  announce_valve(bridge, kStart + 100ms);
  auto command = move_to(42, 45.0F);
  command.command_id(7);
  at(kStart + 150ms);
  bridge.on_command(command);
  tick_at(bridge, kStart + 249ms);
  EXPECT_TRUE(heard().empty()) << "nothing but the claim within 250 ms of it";
  EXPECT_TRUE(sink.states_of(7).empty());
  tick_at(bridge, kStart + 250ms);
  EXPECT_EQ(bridge.claim_state(), isobus::ClaimState::kClaimed);
  const auto after = heard();
  ASSERT_FALSE(after.empty());
  for (const auto& f : after) EXPECT_EQ(f.id, 0x18EFD8D5u);  // polls, then the move
  EXPECT_EQ(after.back().data[0], 0x02) << "Target Degrees went out after the polls";
  EXPECT_EQ(sink.states_of(7), std::vector{COMMAND_ACCEPTED});
}

TEST_F(AddressClaimTest, AnswersARequestForClaimsToEveryoneAndTo0xD5) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  (void)heard();
  send_at(bridge, kStart + 1s, isobus::request_for_address_claimed(0xFF, 0x26));
  send_at(bridge, kStart + 2s, isobus::request_for_address_claimed(0xD5, 0x26));
  const auto answers = heard();
  ASSERT_EQ(answers.size(), 2u);
  for (const auto& answer : answers) {
    EXPECT_EQ(answer.id, 0x18EEFFD5u);
    EXPECT_EQ(answer.dlc, 8);
    EXPECT_EQ(answer.data[1], 0x01) << "the NAME, least significant byte first";
  }
}

TEST_F(AddressClaimTest, YieldsToAHigherPriorityNameRefusesCommandsAndTakesTheAddressBack) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  announce_valve(bridge, kStart + 100ms);
  tick_at(bridge, kStart + 300ms);
  (void)heard();
  send_at(bridge, kStart + 1s, isobus::address_claimed(winner(), 0xD5));
  EXPECT_EQ(ids(heard()), std::vector<std::uint32_t>{0x18EEFFFE}) << "Cannot Claim Address";
  EXPECT_EQ(bridge.claim_state(), isobus::ClaimState::kYielded);

  auto command = move_to(42, 45.0F);
  command.command_id(8);
  at(kStart + 1100ms);
  bridge.on_command(command);
  EXPECT_EQ(sink.states_of(8), std::vector{COMMAND_REJECTED});
  EXPECT_EQ(sink.last_reason(),
            "the gateway gave its address 0xD5 up to an ECU with NAME 0x20088000000000FF "
            "(higher priority): it sends nothing until the address is free (docs/isobus.md)");
  // The valve keeps announcing and its polls would be due: still nothing from 0xD5.
  announce_valve(bridge, kStart + 2s);
  tick_at(bridge, kStart + 2500ms);
  EXPECT_TRUE(heard().empty());
  const auto status = last_status();
  EXPECT_EQ(status.address_claim(), CLAIM_YIELDED);
  EXPECT_EQ(dds::to_string(status.address_claim()), "yielded");
  EXPECT_EQ(status.address_holder(), 0x20088000000000FFULL);
  EXPECT_EQ(status.name(), 0x2008800000000100ULL);
  EXPECT_EQ(status.source_address(), 0xD5);

  // 5 s later it asks who holds 0xD5; nobody answers within 1.25 s: it claims again.
  tick_at(bridge, kStart + 6s);
  EXPECT_EQ(ids(heard()), std::vector<std::uint32_t>{0x18EAD5FE});
  tick_at(bridge, kStart + 7250ms);
  EXPECT_EQ(ids(heard()), std::vector<std::uint32_t>{0x18EEFFD5});
  announce_valve(bridge, kStart + 7300ms);
  tick_at(bridge, kStart + 7500ms);
  EXPECT_EQ(bridge.claim_state(), isobus::ClaimState::kClaimed);
  command.command_id(9);
  at(kStart + 7600ms);
  (void)heard();
  bridge.on_command(command);
  EXPECT_EQ(sink.states_of(9), std::vector{COMMAND_ACCEPTED});
}

TEST_F(AddressClaimTest, ALowerPriorityContenderIsToldOffAndNothingChanges) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  tick_at(bridge, kStart + 300ms);
  (void)heard();
  auto loser = gateway_name();
  loser.identity_number = 0x101;
  send_at(bridge, kStart + 1s, isobus::address_claimed(loser, 0xD5));
  EXPECT_EQ(ids(heard()), std::vector<std::uint32_t>{0x18EEFFD5});
  EXPECT_EQ(bridge.claim_state(), isobus::ClaimState::kClaimed);
}

TEST_F(AddressClaimTest, AnotherEcuSendingFrom0xD5IsAViolationAnsweredWithTheClaim) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  tick_at(bridge, kStart + 300ms);
  (void)heard();
  send_at(bridge, kStart + 1s, codec::encode(0xD9, codec::ToValveMessage{codec::Stop{}}).value());
  EXPECT_EQ(ids(heard()), std::vector<std::uint32_t>{0x18EEFFD5});
  tick_at(bridge, kStart + 2s);
  EXPECT_EQ(last_status().address_violations(), 1u);
}

TEST_F(AddressClaimTest, AnEcuClaimingAValveAddressIsNotTakenForAValve) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  tick_at(bridge, kStart + 300ms);
  isobus::Name terminal;
  terminal.function = 29;
  terminal.industry_group = 2;
  send_at(bridge, kStart + 500ms, isobus::address_claimed(terminal, 0xE0));
  // Its proprietary frame to 0xD5 happens to look like an I'm Here.
  send_at(bridge, kStart + 600ms,
          codec::encode(0xE0, codec::FromValveMessage{codec::IAmHere{0x1, 77, false}}).value());
  EXPECT_TRUE(bridge.valves().empty());
  EXPECT_EQ(bridge.counters().neighbour_frames, 1u);
  tick_at(bridge, kStart + 2s);
  const auto status = last_status();
  EXPECT_EQ(status.claims_in_valve_range(), 1u);
  ASSERT_EQ(status.neighbours().size(), 1u);
  EXPECT_EQ(status.neighbours()[0].address(), 0xE0);
  EXPECT_EQ(status.neighbours()[0].name(), isobus::to_value(terminal));
  EXPECT_EQ(status.neighbours()[0].last_seen_ns(), unix_nanoseconds(kStart + 600ms));
}

TEST_F(AddressClaimTest, ClaimsAgainWhenTheBusComesBack) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  tick_at(bridge, kStart + 300ms);
  (void)heard();
  can::VirtualBus::set_link_up(bus_name, false);
  tick_at(bridge, kStart + 1s);
  EXPECT_TRUE(heard().empty()) << "nothing while the link is down";
  can::VirtualBus::set_link_up(bus_name, true);
  tick_at(bridge, kStart + 2s);
  EXPECT_EQ(ids(heard()), (std::vector<std::uint32_t>{0x18EAFFFE, 0x18EEFFD5}));
  EXPECT_EQ(bridge.claim_state(), isobus::ClaimState::kClaiming);
}

// An outage between two looks, and the look taken by the thread that keeps the commands'
// deadlines (the bus reader may not look for a long time while the address is held).
TEST_F(AddressClaimTest, ClaimsAgainAfterAnOutageNoLookSawAndBusOffToo) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  tick_at(bridge, kStart + 300ms);
  (void)heard();
  can::VirtualBus::set_link_up(bus_name, false);
  can::VirtualBus::set_link_up(bus_name, true);
  at(kStart + 2s);
  bridge.tick_commands();
  EXPECT_EQ(ids(heard()), (std::vector<std::uint32_t>{0x18EAFFFE, 0x18EEFFD5}));
  tick_at(bridge, kStart + 3s);
  EXPECT_EQ(bridge.claim_state(), isobus::ClaimState::kClaimed);
  can::VirtualBus::set_controller_state(bus_name, can::BusState::kBusOff, 256, 0);
  can::VirtualBus::set_controller_state(bus_name, can::BusState::kErrorActive, 0, 0);
  at(kStart + 4s);
  bridge.tick_commands();
  EXPECT_EQ(ids(heard()), (std::vector<std::uint32_t>{0x18EAFFFE, 0x18EEFFD5}));
}

TEST_F(AddressClaimTest, TheStopOnExitGoesOutWithinThe250msButNeverOnceTheAddressIsGivenUp) {
  Bridge bridge(config(), gateway_bus, sink, clock);
  announce_valve(bridge, kStart + 100ms);
  (void)heard();
  at(kStart + 150ms);
  EXPECT_EQ(bridge.stop_all(), 1u);
  const auto stopped = heard();
  ASSERT_EQ(stopped.size(), 1u);
  EXPECT_EQ(stopped[0].id, 0x18EFD8D5u);
  EXPECT_EQ(stopped[0].data[0], 0x00) << "Stop";

  tick_at(bridge, kStart + 300ms);
  send_at(bridge, kStart + 1s, isobus::address_claimed(winner(), 0xD5));
  (void)heard();
  at(kStart + 1100ms);
  EXPECT_EQ(bridge.stop_all(), 0u);
  EXPECT_TRUE(heard().empty()) << "0xD5 is another ECU's now";
}

TEST_F(AddressClaimTest, WithClaimingOffNothingIsClaimedAndCommandsGoOutAtOnce) {
  auto c = config();
  c.isobus.claim = false;
  Bridge bridge(c, gateway_bus, sink, clock);
  EXPECT_TRUE(heard().empty());
  announce_valve(bridge, kStart + 10ms);
  EXPECT_FALSE(heard().empty()) << "polls at once";
  EXPECT_EQ(bridge.claim_state(), isobus::ClaimState::kOff);
}

}  // namespace
}  // namespace teejet::bridge
