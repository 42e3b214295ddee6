// The client's view of the domain against a gateway played by hand, inside a private network
// namespace (see tests/netns/isolated).

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <vector>

#include "support/dds_peer.hpp"
#include "support/eventually.hpp"
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

// A command's valvectl follows only the directory and the telemetry it shows: every topic it
// leaves out is one sample per valve fewer that each gateway sends it as it joins.
TEST(ValveView, AViewOfSomeTelemetryNeitherSubscribesToNorShowsTheRest) {
  DdsPeer gateway(test_domain(), "gateway-by-hand");
  const auto writer_of = [&gateway](auto identity) {
    using Sample = typename decltype(identity)::type;
    auto topic = dds::topics::topic_of<Sample>(gateway.participant());
    EXPECT_TRUE(topic);
    auto writer = gateway.participant().writer(*topic, dds::topics::state_writer_qos());
    EXPECT_TRUE(writer);
    return writer ? *writer : nullptr;
  };
  auto* presence_writer = writer_of(std::type_identity<ValvePresence>{});
  auto* position_writer = writer_of(std::type_identity<ValvePosition>{});
  auto* temperature_writer = writer_of(std::type_identity<ValveTemperature>{});
  ASSERT_TRUE(presence_writer && position_writer && temperature_writer);
  ValvePresence online = presence(0x0012'3456, true);
  ValvePosition position;
  position.serial(0x0012'3456);
  position.degrees(42.5F);
  ValveTemperature temperature;
  temperature.serial(0x0012'3456);
  temperature.valve_c(31);
  ASSERT_TRUE(presence_writer->write(&online));
  ASSERT_TRUE(position_writer->write(&position));
  ASSERT_TRUE(temperature_writer->write(&temperature));

  DdsPeer lean_client(test_domain(), "lean-client");
  DdsPeer full_client(test_domain(), "full-client");
  auto lean = ValveView::create(lean_client.participant(),
                                {.everything = false, .telemetry = {"position"}});
  ASSERT_TRUE(lean) << lean.error().reason;
  auto full = ValveView::create(full_client.participant());
  ASSERT_TRUE(full) << full.error().reason;
  const std::atomic<bool> never{false};
  const auto shown = [&never](ValveView& view, auto has) {
    return view.wait_until(
        [&has](const ValveTable& table) {
          const auto row = table.row(0x0012'3456);
          return row && row->online && has(*row);
        },
        std::chrono::steady_clock::now() + teejet::testing::scaled(kDeadline), never);
  };
  ASSERT_TRUE(shown(**full, [](const ValveRow& row) { return row.temperature_c().has_value(); }));
  ASSERT_TRUE(shown(**lean, [](const ValveRow& row) { return row.position_degrees() == 42.5; }));
  // Both views' position readers matched; only the full view's temperature reader exists.
  ASSERT_TRUE(teejet::testing::eventually(
      [&] {
        eprosima::fastdds::dds::PublicationMatchedStatus matched;
        position_writer->get_publication_matched_status(matched);
        return matched.current_count == 2;
      },
      kDeadline));
  eprosima::fastdds::dds::PublicationMatchedStatus temperature_matched;
  temperature_writer->get_publication_matched_status(temperature_matched);
  EXPECT_EQ(temperature_matched.current_count, 1);
  EXPECT_FALSE((*lean)->snapshot().row(0x0012'3456)->temperature_c());
}

constexpr std::uint32_t kOwn = 0x0012'3456;    // the valve a view names
constexpr std::uint32_t kOther = 0x0065'4321;  // and one it does not

// A gateway played by hand that publishes the presence and position of its valves (kOwn and
// kOther unless told).
class PositionGateway {
 public:
  explicit PositionGateway(std::vector<std::uint32_t> serials = {kOwn, kOther})
      : serials_(std::move(serials)) {
    auto presence_topic = dds::topics::topic_of<ValvePresence>(peer_.participant());
    auto position_topic = dds::topics::topic_of<ValvePosition>(peer_.participant());
    if (!presence_topic || !position_topic) return;
    auto presence = peer_.participant().writer(*presence_topic, dds::topics::state_writer_qos());
    auto position = peer_.participant().writer(*position_topic, dds::topics::state_writer_qos());
    if (presence && position) {
      presence_writer_ = *presence;
      position_writer = *position;
    }
  }
  bool ready() const { return presence_writer_ != nullptr && position_writer != nullptr; }
  bool announce() {
    for (const std::uint32_t serial : serials_) {
      ValvePresence online = presence(serial, true);
      if (!presence_writer_->write(&online)) return false;
    }
    return true;
  }
  // The first valve at `first` degrees, each next one 10 degrees further.
  bool write_positions(float first) {
    bool written = true;
    float degrees = first;
    for (const std::uint32_t serial : serials_) {
      ValvePosition position;
      position.serial(serial);
      position.degrees(degrees);
      written = position_writer->write(&position) && written;
      degrees += 10.0F;
    }
    return written;
  }

  eprosima::fastdds::dds::DataWriter* position_writer = nullptr;

 private:
  std::vector<std::uint32_t> serials_;
  DdsPeer peer_{test_domain(), "gateway-by-hand"};
  eprosima::fastdds::dds::DataWriter* presence_writer_ = nullptr;
};

bool shows_position(const ValveView& view, std::uint32_t serial, double degrees) {
  const auto row = view.snapshot().row(serial);
  return row && row->position_degrees() == degrees;
}

// `valvectl move TJV… --wait` follows the position of its own valve only: the others arrive and
// are dropped by a serial filter before they reach the table (dds/serial_filter.hpp).
TEST(ValveView, AViewOfSomeValvesShowsTheirTelemetryAndNoOthers) {
  PositionGateway gateway;
  ASSERT_TRUE(gateway.ready());
  DdsPeer client(test_domain(), "client");
  auto view = ValveView::create(
      client.participant(), {.everything = false, .telemetry = {"position"}, .serials = {kOwn}});
  ASSERT_TRUE(view) << view.error().reason;
  DdsPeer full_client(test_domain(), "full-client");
  auto full = ValveView::create(full_client.participant());
  ASSERT_TRUE(full) << full.error().reason;

  // Written after both views exist, again and again: both the history a joiner gets and the
  // samples written since go through the filter.
  ASSERT_TRUE(gateway.announce());
  ASSERT_TRUE(teejet::testing::eventually(
      [&] {
        gateway.write_positions(10.5F);
        return shows_position(**full, kOther, 20.5) && shows_position(**view, kOwn, 10.5);
      },
      kDeadline));
  const auto other = (*view)->snapshot().row(kOther);
  ASSERT_TRUE(other) << "presence is not filtered";
  EXPECT_FALSE(other->position_degrees()) << "another valve's position reached the view";
}

// A `move --wait` into a pipe shows only the final position: it follows positions once its
// command completes, and gets the last of its valve's at once (TRANSIENT_LOCAL), no other's.
TEST(ValveView, TelemetryFollowedLaterArrivesWithItsLastSampleForTheNamedValvesOnly) {
  PositionGateway gateway;
  ASSERT_TRUE(gateway.ready());
  ASSERT_TRUE(gateway.announce());
  ASSERT_TRUE(gateway.write_positions(10.5F));

  DdsPeer client(test_domain(), "client");
  auto view = ValveView::create(client.participant(), {.everything = false});
  ASSERT_TRUE(view) << view.error().reason;
  const std::atomic<bool> never{false};
  const auto until = [] { return std::chrono::steady_clock::now() + kDeadline; };
  ASSERT_TRUE((*view)->wait_until(
      [](const ValveTable& table) { return table.row(kOwn) && table.row(kOther); }, until(),
      never));
  EXPECT_FALSE((*view)->snapshot().row(kOwn)->position_degrees()) << "followed too early";

  const ViewTopics positions{.everything = false, .telemetry = {"position"}, .serials = {kOwn}};
  const auto followed = (*view)->follow(positions);
  ASSERT_TRUE(followed) << followed.error().reason;
  ASSERT_TRUE((*view)->wait_until(
      [](const ValveTable& table) { return table.row(kOwn)->position_degrees() == 10.5; }, until(),
      never));
  ASSERT_TRUE((*view)->follow(positions)) << "following again";
  // A sample written since arrives too; the other valve's never does.
  ASSERT_TRUE(teejet::testing::eventually(
      [&] {
        gateway.write_positions(11.5F);
        return shows_position(**view, kOwn, 11.5);
      },
      kDeadline));
  EXPECT_FALSE((*view)->snapshot().row(kOther)->position_degrees());
  eprosima::fastdds::dds::PublicationMatchedStatus matched;
  gateway.position_writer->get_publication_matched_status(matched);
  EXPECT_EQ(matched.current_count, 1) << "one position reader, however often followed";
}

// teejet-web takes the telemetry the gateways resend every poll best effort. A gateway's last
// sample still reaches it as the gateway appears, however long before the view it was written
// and whenever the gateway comes: a reliable reader follows the subject for a while after each
// new writer, then goes.
TEST(ValveView, ABestEffortSubjectGetsEachNewGatewaysLastSampleAndThenItsStream) {
  PositionGateway gateway;
  ASSERT_TRUE(gateway.ready());
  ASSERT_TRUE(gateway.announce());
  ASSERT_TRUE(gateway.write_positions(10.5F));

  DdsPeer client(test_domain(), "client");
  auto view = ValveView::create(client.participant(), {.best_effort = {"position"}});
  ASSERT_TRUE(view) << view.error().reason;
  const std::atomic<bool> never{false};
  const auto until = [] {
    return std::chrono::steady_clock::now() + teejet::testing::scaled(kDeadline);
  };
  ASSERT_TRUE((*view)->wait_until(
      [](const ValveTable& table) {
        return table.row(kOwn) && table.row(kOwn)->position_degrees() == 10.5 &&
               table.row(kOther) && table.row(kOther)->position_degrees() == 20.5;
      },
      until(), never))
      << "the sample written before the view was not caught up";

  // The catch-up reader goes once no writer has matched for a while: the stream's is left.
  // Counted on the client's side: a writer in the same process as the reader goes on counting
  // a deleted reliable reader as matched (Fast DDS 2.9.1; across processes it unmatches).
  const auto position_readers = [&client] {
    return client.participant().readers_of(dds::topics::topic_name<ValvePosition>());
  };
  ASSERT_TRUE(teejet::testing::eventually([&] { return position_readers() == 1; },
                                          kDeadline + ValveView::kCatchUpQuiet))
      << "the catch-up reader stayed";
  ASSERT_TRUE(teejet::testing::eventually(
      [&] {
        gateway.write_positions(11.5F);
        return shows_position(**view, kOwn, 11.5) && shows_position(**view, kOther, 21.5);
      },
      kDeadline))
      << "the stream itself brought nothing";

  // A gateway that comes later is caught up too.
  constexpr std::uint32_t kLater = 0x00AB'CDEF;
  PositionGateway later({kLater});
  ASSERT_TRUE(later.ready());
  ASSERT_TRUE(later.announce());
  ASSERT_TRUE(later.write_positions(33.5F));
  ASSERT_TRUE((*view)->wait_until(
      [](const ValveTable& table) {
        return table.row(kLater) && table.row(kLater)->position_degrees() == 33.5;
      },
      until(), never))
      << "the later gateway's last sample was not caught up";
  EXPECT_TRUE(teejet::testing::eventually([&] { return position_readers() == 1; },
                                          kDeadline + ValveView::kCatchUpQuiet))
      << "the second catch-up reader stayed";
}

}  // namespace
}  // namespace teejet::client
