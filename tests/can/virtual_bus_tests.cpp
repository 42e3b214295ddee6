#include <gtest/gtest.h>

#include <atomic>
#include <optional>
#include <thread>
#include <vector>

#include "support/eventually.hpp"
#include "teejet/can/virtual_bus.hpp"
#include "teejet/codec/codec.hpp"

namespace teejet::can {
namespace {

using namespace std::chrono_literals;
using teejet::testing::eventually;

codec::CanFrame position_from(std::uint8_t valve, double degrees) {
  return codec::encode(valve, codec::Position{degrees}).value();
}

codec::CanFrame stop_to(std::uint8_t valve) { return codec::encode(valve, codec::Stop{}).value(); }

class VirtualBusTest : public ::testing::Test {
 protected:
  // A unique bus per test: parallel ctest runs share the process-wide registry of names.
  std::string bus_name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
  std::shared_ptr<ManualClock> clock =
      std::make_shared<ManualClock>(Timestamp{Duration{1'700'000'000'000'000'000}});
};

TEST_F(VirtualBusTest, DeliversToOtherEndpointsButNotBackToTheSender) {
  VirtualBus a(bus_name), b(bus_name), c(bus_name);
  ASSERT_TRUE(a.open());
  ASSERT_TRUE(b.open());
  ASSERT_TRUE(c.open());
  ASSERT_TRUE(a.send(position_from(0xD8, 12.3)));
  for (VirtualBus* receiver : {&b, &c}) {
    auto got = receiver->receive(1s);
    ASSERT_TRUE(got);
    EXPECT_EQ(got->frame, position_from(0xD8, 12.3));
  }
  EXPECT_FALSE(a.receive(0ms));
  EXPECT_EQ(a.statistics().frames_out, 1u);
  EXPECT_EQ(b.statistics().frames_in, 1u);
}

TEST_F(VirtualBusTest, BusesWithDifferentNamesAreSeparate) {
  VirtualBus a(bus_name), other(bus_name + "-other");
  ASSERT_TRUE(a.open());
  ASSERT_TRUE(other.open());
  ASSERT_TRUE(a.send(stop_to(0xD8)));
  EXPECT_FALSE(other.receive(10ms));
}

TEST_F(VirtualBusTest, ControllerAndValveFiltersSplitTheDirections) {
  VirtualBus sender(bus_name);
  VirtualBus controller(bus_name, {.filters = controller_side_filters()});
  VirtualBus valve(bus_name, {.filters = valve_side_filters()});
  ASSERT_TRUE(sender.open());
  ASSERT_TRUE(controller.open());
  ASSERT_TRUE(valve.open());
  ASSERT_TRUE(sender.send(position_from(0xD9, 1.0)));
  ASSERT_TRUE(sender.send(stop_to(0xD9)));
  ASSERT_TRUE(sender.send(codec::CanFrame{.id = 0x18FEF100, .dlc = 8}));                // other PGN
  ASSERT_TRUE(sender.send(codec::CanFrame{.id = 0x0D5, .extended = false, .dlc = 1}));  // 11-bit
  ASSERT_TRUE(sender.send(codec::CanFrame{.id = 0x18EFD5D9, .remote = true}));          // RTR

  auto to_controller = controller.receive(1s);
  ASSERT_TRUE(to_controller);
  EXPECT_EQ(to_controller->frame.id, 0x18EFD5D9u);
  EXPECT_FALSE(controller.receive(0ms));

  auto to_valve = valve.receive(1s);
  ASSERT_TRUE(to_valve);
  EXPECT_EQ(to_valve->frame.id, 0x18EFD9D5u);
  EXPECT_FALSE(valve.receive(0ms));
}

TEST_F(VirtualBusTest, StampsFramesWithTheInjectedClock) {
  VirtualBus a(bus_name), b(bus_name, {.clock = clock});
  ASSERT_TRUE(a.open());
  ASSERT_TRUE(b.open());
  clock->advance(1500us);
  ASSERT_TRUE(a.send(stop_to(0xD8)));
  auto got = b.receive(1s);
  ASSERT_TRUE(got);
  EXPECT_EQ(got->received, Timestamp{Duration{1'700'000'000'001'500'000}});
}

TEST_F(VirtualBusTest, InjectedFramesReachOnlyThatEndpoint) {
  VirtualBus a(bus_name), b(bus_name);
  ASSERT_TRUE(a.open());
  ASSERT_TRUE(b.open());
  a.inject(stop_to(0xE0));
  ASSERT_TRUE(a.receive(1s));
  EXPECT_FALSE(b.receive(0ms));
}

TEST_F(VirtualBusTest, ReceiveWaitsForAFrameFromAnotherThread) {
  VirtualBus a(bus_name), b(bus_name);
  ASSERT_TRUE(a.open());
  ASSERT_TRUE(b.open());
  std::optional<TimedFrame> got;
  std::jthread receiver([&] { got = b.receive(30s); });
  // Send only once the receiver is blocked: a frame already queued would not test the wait.
  ASSERT_TRUE(eventually([&] { return b.waiting_receivers() == 1; }, 5s));
  ASSERT_TRUE(a.send(stop_to(0xD8)));
  receiver.join();
  ASSERT_TRUE(got);
  EXPECT_EQ(got->frame, stop_to(0xD8));
  EXPECT_EQ(b.waiting_receivers(), 0u);
}

TEST_F(VirtualBusTest, FullQueueDropsAndCountsLikeTheKernel) {
  VirtualBus a(bus_name), b(bus_name, {.queue_limit = 3});
  ASSERT_TRUE(a.open());
  ASSERT_TRUE(b.open());
  for (int i = 0; i < 5; ++i) ASSERT_TRUE(a.send(stop_to(0xD8)));
  EXPECT_EQ(b.statistics().rx_dropped, 2u);
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(b.receive(0ms));
  EXPECT_FALSE(b.receive(0ms));
}

// A burst sent as one batch arrives in order and leaves in one receive_batch, as far as `max`
// allows; frames the queue cannot hold are dropped and counted as if sent one by one.
TEST_F(VirtualBusTest, BatchesKeepOrderRespectMaxAndCountDrops) {
  VirtualBus a(bus_name), b(bus_name, {.queue_limit = 4});
  ASSERT_TRUE(a.open());
  ASSERT_TRUE(b.open());
  const std::vector<codec::CanFrame> burst{position_from(0xD8, 1.0), position_from(0xD9, 2.0),
                                           position_from(0xDA, 3.0), position_from(0xDB, 4.0),
                                           position_from(0xDC, 5.0), position_from(0xDD, 6.0)};
  const auto sent = a.send_batch(burst);
  EXPECT_TRUE(sent.status);
  EXPECT_EQ(sent.sent, 6u);
  EXPECT_EQ(a.statistics().frames_out, 6u);
  EXPECT_EQ(b.statistics().rx_dropped, 2u);

  std::vector<TimedFrame> got;
  EXPECT_EQ(b.receive_batch(got, 3, 1s), 3u);
  EXPECT_EQ(b.receive_batch(got, 3, 1s), 1u);
  EXPECT_EQ(b.receive_batch(got, 3, 0ms), 0u);
  ASSERT_EQ(got.size(), 4u);
  for (std::size_t i = 0; i < got.size(); ++i) EXPECT_EQ(got[i].frame, burst[i]) << i;
  EXPECT_EQ(b.statistics().frames_in, 4u);
}

TEST_F(VirtualBusTest, ABatchOnALinkThatIsDownSendsNothing) {
  VirtualBus a(bus_name), b(bus_name);
  ASSERT_TRUE(a.open());
  ASSERT_TRUE(b.open());
  VirtualBus::set_link_up(bus_name, false);
  const std::vector<codec::CanFrame> burst{stop_to(0xD8), stop_to(0xD9)};
  const auto sent = a.send_batch(burst);
  EXPECT_EQ(sent.sent, 0u);
  ASSERT_FALSE(sent.status);
  EXPECT_EQ(sent.status.error().os_error, ENETDOWN);
  std::vector<TimedFrame> got;
  EXPECT_EQ(b.receive_batch(got, 8, 0ms), 0u);
}

TEST_F(VirtualBusTest, LinkDownRefusesSendsVisiblyAndRecovers) {
  VirtualBus a(bus_name), b(bus_name);
  ASSERT_TRUE(a.open());
  ASSERT_TRUE(b.open());
  VirtualBus::set_link_up(bus_name, false);
  const Status refused = a.send(stop_to(0xD8));
  EXPECT_FALSE(refused);
  EXPECT_EQ(refused.error().os_error, ENETDOWN);
  EXPECT_EQ(a.statistics().state, BusState::kDown);
  EXPECT_EQ(a.statistics().tx_failed, 1u);
  VirtualBus::set_link_up(bus_name, true);
  EXPECT_TRUE(a.send(stop_to(0xD8)));
  EXPECT_TRUE(b.receive(1s));
}

TEST_F(VirtualBusTest, ControllerStateShowsInStatistics) {
  VirtualBus a(bus_name);
  ASSERT_TRUE(a.open());
  VirtualBus::set_controller_state(bus_name, BusState::kErrorPassive, 130, 7);
  const auto stats = a.statistics();
  EXPECT_EQ(stats.state, BusState::kErrorPassive);
  EXPECT_EQ(stats.tx_errors, 130);
  EXPECT_EQ(stats.rx_errors, 7);
}

TEST_F(VirtualBusTest, ClosedBusRefusesAndWakesReceivers) {
  VirtualBus a(bus_name);
  EXPECT_FALSE(a.send(stop_to(0xD8)));
  ASSERT_TRUE(a.open());
  std::optional<TimedFrame> got = TimedFrame{};
  std::atomic<bool> returned = false;
  std::jthread receiver([&] {
    got = a.receive(30s);
    returned = true;
  });
  // Close only once the receiver is blocked: closing first would not test the wake-up.
  ASSERT_TRUE(eventually([&] { return a.waiting_receivers() == 1; }, 5s));
  a.close();
  // Well before its 30 s timeout: close() woke it.
  ASSERT_TRUE(eventually([&] { return returned.load(); }, 5s));
  receiver.join();
  EXPECT_FALSE(got);
  EXPECT_FALSE(a.send(stop_to(0xD8)));
}

}  // namespace
}  // namespace teejet::can
