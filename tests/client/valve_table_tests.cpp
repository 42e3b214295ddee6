// The latest-state model behind list, watch and the command flows.

#include <gtest/gtest.h>

#include "support/valve_samples.hpp"
#include "teejet/client/valve_table.hpp"
#include "teejet/codec/codec.hpp"

namespace teejet::client {
namespace {

using teejet::testing::presence;

GatewayStatus gateway_status(const std::string& name, std::uint32_t known) {
  GatewayStatus s;
  s.gateway(name);
  s.valves_known(known);
  s.valves_online(known);
  return s;
}

// Gateways "a" (participant 01.0f.aa) and "b" (01.0f.bb), knowing that many valves each.
ValveTable two_gateways(std::uint32_t a_knows, std::uint32_t b_knows) {
  ValveTable table;
  table.on_gateway_status(gateway_status("a", a_knows), "01.0f.aa");
  table.on_gateway_status(gateway_status("b", b_knows), "01.0f.bb");
  return table;
}

TEST(ValvectlTable, TelemetryBeforePresenceStaysHiddenUntilThePresenceArrives) {
  ValveTable table;
  table.on_telemetry(1, codec::Position{12.3}, 10);
  EXPECT_TRUE(table.rows().empty());
  EXPECT_FALSE(table.row(1));
  table.on_presence(presence(1, true));
  ASSERT_TRUE(table.row(1));
  EXPECT_EQ(table.row(1)->position_degrees(), 12.3);
  EXPECT_EQ(table.row(1)->address, 0xD9);
  EXPECT_EQ(table.row(1)->gateway, "gw");
}

// A best-effort subject's catch-up reader delivers each writer's last sample as it matches, which
// may be older than what the stream has brought since.
TEST(ValvectlTable, AWritersLastSampleFillsOnlyWhatNothingReceivedLaterHas) {
  ValveTable table;
  table.on_presence(presence(1, true));
  table.on_telemetry_history(1, codec::Position{10.5}, 100);
  EXPECT_EQ(table.row(1)->position_degrees(), 10.5) << "nothing there yet";
  table.on_telemetry(1, codec::Position{20.5}, 300);
  table.on_telemetry_history(1, codec::Position{15.5}, 200);
  EXPECT_EQ(table.row(1)->position_degrees(), 20.5) << "an older sample replaced a newer one";
  table.on_telemetry_history(1, codec::Position{25.5}, 400);
  EXPECT_EQ(table.row(1)->position_degrees(), 25.5);
  table.on_telemetry_history(1, codec::Temperature{31, 31}, 50);
  EXPECT_EQ(table.row(1)->temperature_c(), 31) << "another subject is judged on its own";
}

TEST(ValvectlTable, RowsAreSortedBySerialAndCountOnline) {
  ValveTable table;
  table.on_presence(presence(3, true));
  table.on_presence(presence(1, false));
  table.on_presence(presence(2, true));
  const auto rows = table.rows();
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[0].serial, 1u);
  EXPECT_EQ(rows[2].serial, 3u);
  EXPECT_EQ(table.online_count(), 2u);
}

TEST(ValvectlTable, DirectoryIsCompleteWhenEveryMatchedGatewayHasToldAllItKnows) {
  ValveTable table;
  EXPECT_FALSE(table.directory_complete());  // nobody found yet
  table.set_gateways_matched(1);
  table.on_gateway_status(gateway_status("a", 2));
  EXPECT_FALSE(table.directory_complete());
  table.on_presence(presence(1, true, "a"));
  EXPECT_FALSE(table.directory_complete());
  table.on_presence(presence(2, false, "a"));
  EXPECT_TRUE(table.directory_complete());
  table.set_gateways_matched(2);  // a second gateway has been found but not reported yet
  EXPECT_FALSE(table.directory_complete());
  table.on_gateway_status(gateway_status("b", 0));
  EXPECT_TRUE(table.directory_complete());
  table.set_discovery_settled(false);  // a participant met just now may be a third gateway
  EXPECT_FALSE(table.directory_complete());
}

// Discovery finds gateways one by one: a client that has met one of eight must not judge the
// directory complete. Each gateway says how many it hears on the domain.
TEST(ValvectlTable, DirectoryWaitsForEveryGatewayThatAGatewaySaysItHears) {
  ValveTable table;
  table.set_gateways_matched(1);
  auto a = gateway_status("a", 1);
  a.gateways_seen(3);
  table.on_gateway_status(a, "01.0f.aa");
  table.on_presence(presence(1, true, "a"));
  EXPECT_EQ(table.gateways_expected(), 3u);
  EXPECT_FALSE(table.directory_complete());
  auto b = gateway_status("b", 0);
  b.gateways_seen(2);  // b has not heard c yet: the most any gateway says counts
  table.on_gateway_status(b, "01.0f.bb");
  EXPECT_FALSE(table.directory_complete());
  table.on_gateway_status(gateway_status("c", 0), "01.0f.cc");
  EXPECT_EQ(table.gateways_expected(), 3u);
  EXPECT_TRUE(table.directory_complete());
  EXPECT_EQ(table.gateways()[0].participants, std::set<std::string>{"01.0f.aa"});
}

// Gateways started together have met only each other when a client meets the first two of
// four: each says gateways_seen 2. Discovery has already told the client of four participants
// announcing themselves as gateways.
TEST(ValvectlTable, DirectoryWaitsForEveryParticipantThatAnnouncesItselfAGateway) {
  ValveTable table = two_gateways(0, 0);
  table.set_gateways_matched(2);
  EXPECT_TRUE(table.directory_complete());
  table.set_gateway_participants(4);
  EXPECT_EQ(table.gateways_expected(), 4u);
  EXPECT_FALSE(table.directory_complete());
  table.on_gateway_status(gateway_status("c", 0), "01.0f.cc");
  table.on_gateway_status(gateway_status("d", 0), "01.0f.dd");
  EXPECT_TRUE(table.directory_complete());
}

TEST(ValvectlTable, AValveRowNamesTheParticipantThatPublishesIt) {
  ValveTable table;
  table.on_presence(presence(1, true, "a"), "01.0f.aa");
  EXPECT_EQ(table.row(1)->participant, "01.0f.aa");
  table.on_presence(presence(1, true, "b"), "01.0f.bb");  // moved to another gateway's bus
  EXPECT_EQ(table.row(1)->participant, "01.0f.bb");
  EXPECT_EQ(table.row(1)->gateway, "b");
  // Until a calls it offline (its timeout), both report it.
  EXPECT_EQ(table.row(1)->also_reported_by, std::vector<std::string>{"a"});
  table.on_presence(presence(1, false, "a"), "01.0f.aa");
  EXPECT_EQ(table.row(1)->gateway, "b");
  EXPECT_TRUE(table.row(1)->also_reported_by.empty());
}

TEST(ValvectlTable, AValveOfALostGatewayIsNeitherOnlineNorCountedUntilItComesBack) {
  ValveTable table = two_gateways(2, 1);
  table.on_presence(presence(1, true, "a"), "01.0f.aa");
  table.on_presence(presence(2, true, "b"), "01.0f.bb");
  table.on_participant_liveliness("01.0f.aa", false);
  EXPECT_TRUE(table.row(1)->gateway_lost);
  EXPECT_FALSE(table.row(2)->gateway_lost);
  EXPECT_EQ(table.online_count(), 1u);
  EXPECT_TRUE(table.gateways()[0].lost);
  EXPECT_FALSE(table.gateways()[1].lost);
  table.on_participant_liveliness("01.0f.aa", true);
  EXPECT_FALSE(table.row(1)->gateway_lost);
  EXPECT_EQ(table.online_count(), 2u);
}

// One DDS instance per serial, whoever publishes it: two gateways reporting one serial online
// (two valves with one serial, or a replay) are both kept, never one hiding the other.
TEST(ValvectlTable, ASerialTwoGatewaysReportOnlineNamesTheOtherUntilOneSaysOfflineOrIsLost) {
  ValveTable table = two_gateways(1, 1);
  table.on_presence(presence(1, true, "a"), "01.0f.aa");
  table.on_presence(presence(1, true, "b"), "01.0f.bb");
  EXPECT_EQ(table.row(1)->gateway, "b");
  EXPECT_EQ(table.row(1)->also_reported_by, std::vector<std::string>{"a"});
  EXPECT_EQ(table.online_count(), 1u);
  EXPECT_TRUE(table.directory_complete());  // each gateway's one valve is there
  // b's valve goes offline: a's report shows, online, whatever came last.
  table.on_presence(presence(1, false, "b"), "01.0f.bb");
  EXPECT_EQ(table.row(1)->gateway, "a");
  EXPECT_TRUE(table.row(1)->online);
  EXPECT_TRUE(table.row(1)->also_reported_by.empty());
  table.on_presence(presence(1, true, "b"), "01.0f.bb");
  EXPECT_EQ(table.row(1)->also_reported_by.size(), 1u);
  // a vanishes: its word no longer counts.
  table.on_participant_liveliness("01.0f.aa", false);
  EXPECT_EQ(table.row(1)->gateway, "b");
  EXPECT_FALSE(table.row(1)->gateway_lost);
  EXPECT_TRUE(table.row(1)->also_reported_by.empty());
}

TEST(ValvectlTable, ErrorsLatchUntilCleared) {
  ValveTable table;
  table.on_presence(presence(1, true));
  table.on_error(1, ERROR_HIGH_VOLTAGE);
  table.on_error(1, ERROR_LOW_CURRENT);
  EXPECT_EQ(table.row(1)->errors.size(), 2u);
  table.on_error_cleared(1, ERROR_HIGH_VOLTAGE);
  EXPECT_EQ(table.row(1)->errors, std::set<ErrorKind>{ERROR_LOW_CURRENT});
}

TEST(ValvectlTable, TelemetryIsCompleteWhenEveryOnlineValveReportedItsValues) {
  ValveTable table;
  table.on_presence(presence(1, true));
  table.on_presence(presence(2, false));  // offline valves are not waited for
  EXPECT_FALSE(table.telemetry_complete());
  table.on_telemetry(1, codec::Position{1.0}, 1);
  table.on_telemetry(1, codec::Temperature{25, 24}, 1);
  EXPECT_FALSE(table.telemetry_complete());
  table.on_telemetry(1, codec::Voltage{12.0}, 1);
  EXPECT_TRUE(table.telemetry_complete());
}

TEST(ValvectlTable, TelemetryKeepsTheLatestMessageOfEachSubject) {
  ValveTable table;
  table.on_presence(presence(4, true));
  table.on_telemetry(4, codec::Voltage{12.0}, 100);
  table.on_telemetry(4, codec::Voltage{12.4}, 150);
  table.on_telemetry(4, codec::BaudRateReply{250000}, 200);
  table.on_telemetry(4, codec::HighVoltageError{17, 16.5}, 300);  // errors are no telemetry
  ASSERT_TRUE(table.reply(4, "voltage"));
  EXPECT_EQ(table.reply(4, "voltage")->received_ns, 150u);
  EXPECT_EQ(table.reply(4, "voltage")->message, codec::FromValveMessage{codec::Voltage{12.4}});
  EXPECT_EQ(table.reply(4, "baud_rate")->message,
            codec::FromValveMessage{codec::BaudRateReply{250000}});
  EXPECT_FALSE(table.reply(4, "current"));
  EXPECT_EQ(table.row(4)->telemetry.size(), 2u);
  EXPECT_EQ(table.row(4)->volts(), 12.4);
  EXPECT_FALSE(table.row(4)->temperature_c());
}

ValveLocation place(const std::string& name, const std::string& gateway, unsigned order,
                    std::optional<std::uint32_t> serial, LocationState state) {
  ValveLocation p;
  p.location(name);
  p.gateway(gateway);
  p.order(static_cast<std::uint16_t>(order));
  p.assigned(serial.has_value());
  p.serial(serial.value_or(0));
  p.state(state);
  return p;
}

TEST(ValvectlTable, PlacesComeInMachineOrderAndAreCompleteWhenEveryGatewayToldThemAll) {
  ValveTable table;
  table.set_gateways_matched(1);
  auto status = gateway_status("a", 0);
  status.locations_known(2);
  table.on_gateway_status(status);
  table.on_location(place("section-02", "a", 3, 5, LOCATION_OK));
  EXPECT_FALSE(table.directory_complete());  // one place of two
  table.on_location(place("left-master", "a", 1, std::nullopt, LOCATION_EMPTY));
  EXPECT_TRUE(table.directory_complete());
  const auto places = table.locations();
  ASSERT_EQ(places.size(), 2u);
  EXPECT_EQ(places[0].name, "left-master");
  EXPECT_EQ(places[0].serial, std::nullopt);
  EXPECT_EQ(places[1].name, "section-02");
  EXPECT_EQ(places[1].serial, 5u);
  table.on_location(place("section-02", "a", 3, 6, LOCATION_MISSING));  // replaced
  EXPECT_EQ(table.locations_named("section-02").at(0).serial, 6u);
  EXPECT_EQ(table.locations_named("section-02").at(0).state, LOCATION_MISSING);
}

TEST(ValvectlTable, ANameTwoGatewaysClaimIsTwoPlaces) {
  ValveTable table;
  table.on_location(place("section-01", "a", 1, 1, LOCATION_OK), "01.0f.aa");
  table.on_location(place("section-01", "b", 1, 2, LOCATION_OK), "01.0f.bb");
  const auto claimed = table.locations_named("section-01");
  ASSERT_EQ(claimed.size(), 2u);
  EXPECT_EQ(claimed[0].gateway, "a");
  EXPECT_EQ(claimed[1].gateway, "b");
  table.on_participant_liveliness("01.0f.bb", false);
  EXPECT_TRUE(table.locations_named("section-01").at(1).gateway_lost);
  EXPECT_TRUE(table.locations_named("section-0").empty());
}

std::vector<std::uint32_t> serials(const std::vector<ValveRow>& rows) {
  std::vector<std::uint32_t> out;
  for (const ValveRow& row : rows) out.push_back(row.serial);
  return out;
}

// What a dashboard sends on each tick: the rows whose shown content changed, not those whose
// presence or reply only came again (every second, or every poll).
TEST(ValvectlTable, OnlyRowsWhoseShownContentChangedAreListedAsChanged) {
  ValveTable table = two_gateways(2, 1);
  table.on_presence(presence(1, true, "a"), "01.0f.aa");
  table.on_presence(presence(2, true, "a"), "01.0f.aa");
  table.on_presence(presence(3, true, "b"), "01.0f.bb");
  table.on_telemetry(1, codec::Position{10.0}, 100);
  EXPECT_EQ(serials(table.rows_changed_since(0)), (std::vector<std::uint32_t>{1, 2, 3}));

  std::uint64_t sent = table.revision();
  EXPECT_TRUE(table.rows_changed_since(sent).empty());
  ValvePresence again = presence(2, true, "a");
  again.last_seen_ns(5'000'000'000);
  table.on_presence(again, "01.0f.aa");
  table.on_telemetry(1, codec::Position{10.0}, 200);
  EXPECT_TRUE(table.rows_changed_since(sent).empty());
  EXPECT_EQ(table.row(1)->reply("position")->received_ns, 200u);

  table.on_telemetry(1, codec::Position{12.5}, 300);
  table.on_presence(presence(3, false, "b"), "01.0f.bb");
  table.on_error(2, ERROR_HIGH_CURRENT);
  EXPECT_EQ(serials(table.rows_changed_since(sent)), (std::vector<std::uint32_t>{1, 2, 3}));

  sent = table.revision();
  table.on_error(2, ERROR_HIGH_CURRENT);          // latched already
  table.on_error_cleared(1, ERROR_HIGH_CURRENT);  // never set
  EXPECT_TRUE(table.rows_changed_since(sent).empty());
  table.on_error_cleared(2, ERROR_HIGH_CURRENT);
  EXPECT_EQ(serials(table.rows_changed_since(sent)), (std::vector<std::uint32_t>{2}));

  // A gateway lost (or back) changes what every row of it shows: all are listed.
  sent = table.revision();
  table.on_participant_liveliness("01.0f.bb", false);
  const auto changed = table.rows_changed_since(sent);
  EXPECT_EQ(serials(changed), (std::vector<std::uint32_t>{1, 2, 3}));
  EXPECT_TRUE(changed[2].gateway_lost);
  sent = table.revision();
  table.on_participant_liveliness("01.0f.bb", false);  // already lost
  EXPECT_TRUE(table.rows_changed_since(sent).empty());
}

// With two reporters the newest report may change which gateway a row names.
TEST(ValvectlTable, APresenceFromASecondReporterIsAChangeEvenWhenAlike) {
  ValveTable table = two_gateways(1, 1);
  table.on_presence(presence(1, true, "a"), "01.0f.aa");
  table.on_presence(presence(1, true, "b"), "01.0f.bb");
  const std::uint64_t sent = table.revision();
  table.on_presence(presence(1, true, "a"), "01.0f.aa");
  ASSERT_EQ(table.rows_changed_since(sent).size(), 1u);
  EXPECT_EQ(table.rows_changed_since(sent)[0].gateway, "a");
}

}  // namespace
}  // namespace teejet::client
