// The client's view of the domain against a gateway played by hand, inside a private network
// namespace (see tests/netns/isolated).

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>

#include "support/dds_peer.hpp"
#include "support/test_domain.hpp"
#include "support/valve_samples.hpp"
#include "teejet/client/valve_view.hpp"
#include "teejet/dds/topics.hpp"
#include "teejet/valvePubSubTypes.h"

namespace teejet::client {
namespace {

using namespace std::chrono_literals;
using teejet::testing::DdsPeer;
using teejet::testing::presence;
using teejet::testing::test_domain;

constexpr auto kDeadline = 15s;

// A gateway that dies before its first liveliness assertion reaches a client (the client had
// just joined) never counts as alive there, so its liveliness cannot lapse either: it used to
// stay shown online for good. Its status writer's unmatch marks it lost. The writer here never
// asserts (manual liveliness, never written) and goes, as a killed gateway's does at its lease.
TEST(ValveView, AGatewayGoneBeforeItsFirstLivelinessReachedTheClientIsShownLost) {
  DdsPeer gateway(test_domain(), "gateway-by-hand");
  auto status_topic = dds::topics::topic_of<GatewayStatus>(gateway.participant());
  ASSERT_TRUE(status_topic);
  auto silent = dds::topics::state_writer_qos();
  silent.liveliness().kind = eprosima::fastdds::dds::MANUAL_BY_PARTICIPANT_LIVELINESS_QOS;
  auto status_writer = gateway.participant().writer(*status_topic, silent);
  ASSERT_TRUE(status_writer) << status_writer.error().reason;
  auto presence_topic = dds::topics::topic_of<ValvePresence>(gateway.participant());
  ASSERT_TRUE(presence_topic);
  auto presence_writer =
      gateway.participant().writer(*presence_topic, dds::topics::state_writer_qos());
  ASSERT_TRUE(presence_writer) << presence_writer.error().reason;
  ValvePresence online = presence(0x0012'3456, true);
  ASSERT_TRUE((*presence_writer)->write(&online));

  DdsPeer client(test_domain(), "client");
  auto view = ValveView::create(client.participant());
  ASSERT_TRUE(view) << view.error().reason;
  const std::atomic<bool> never{false};
  ASSERT_TRUE((*view)->wait_until(
      [](const ValveTable& table) {
        return table.row(0x0012'3456) && table.row(0x0012'3456)->online;
      },
      std::chrono::steady_clock::now() + kDeadline, never));
  // The client's own reader must have matched the status writer: the writer matching the
  // reader says nothing of the other side, and a reader that has not yet learnt of a writer when
  // it is deleted never learns of it at all (CI run 47 deleted it in that window).
  ASSERT_TRUE(
      (*view)->wait_until([](const ValveTable& table) { return table.gateways_matched() == 1; },
                          std::chrono::steady_clock::now() + kDeadline, never));
  EXPECT_FALSE((*view)->snapshot().row(0x0012'3456)->gateway_lost);

  gateway.participant().delete_writer(*status_writer);
  ASSERT_TRUE((*view)->wait_until(
      [](const ValveTable& table) { return table.row(0x0012'3456)->gateway_lost; },
      std::chrono::steady_clock::now() + kDeadline, never))
      << "the row stayed online after its gateway's status writer went";
  EXPECT_EQ((*view)->snapshot().online_count(), 0u);
}

}  // namespace
}  // namespace teejet::client
