// The JSON teejet-web sends: the valve table, gateway health and the batched updates.

#include <gtest/gtest.h>

#include "command_samples.hpp"
#include "dashboard_json.hpp"
#include "web_fixture.hpp"

namespace teejet::web {
namespace {

using nlohmann::json;
using testing::presence;
using testing::status;
using testing::three_valves;

GatewayStatus bench_status() {
  GatewayStatus s;
  s.gateway("bench");
  s.can_interface("can0");
  s.bus_state(BUS_ERROR_WARNING);
  s.tx_errors(97);
  s.rx_errors(3);
  s.frames_in(1200);
  s.frames_out(340);
  s.decode_errors(2);
  s.rx_dropped(5);
  s.valves_online(2);
  s.valves_known(3);
  return s;
}

TEST(WebValves, AValveCarriesTheTableRowTelemetryRepliesAndTheTargetOfItsMove) {
  client::ValveTable table;
  table.on_presence(presence(1, true));
  table.on_telemetry(1, codec::Position{45.3}, 10);
  table.on_telemetry(1, codec::Temperature{25, 31}, 10);
  table.on_telemetry(1, codec::Voltage{12.1}, 10);
  table.on_error(1, ERROR_HIGH_CURRENT);
  table.on_telemetry(1, codec::RunCurrent{0.35, 0.5}, 10);
  table.on_telemetry(
      1, codec::SpeedDirection{80, codec::Direction::kOpen, codec::Rotation::kClockwise}, 10);
  const json telemetry = {
      {"position", {{"degrees", 45.3}}},
      {"temperature", {{"valve_c", 25}, {"sensor_c", 31}}},
      {"voltage", {{"volts", 12.1}}},
      {"current", {{"amps", 0.35}, {"last_running_amps", 0.5}}},
      {"speed_direction",
       {{"speed_percent", 80}, {"direction", "open"}, {"opening_direction", "clockwise"}}},
  };
  const json expected = {
      {"serial", "TJV000001"},
      {"address", 217},
      {"online", true},
      {"boot_mode", false},
      {"position", 45.3},
      {"temperature_c", 25},
      {"volts", 12.1},
      {"errors", json::array({"high_current"})},
      {"gateway", "gw"},
      {"gateway_lost", false},
      {"location", ""},
      {"target", 90.0},
      {"amps", 0.35},
      {"speed_percent", 80},
      {"direction", "open"},
      {"telemetry", telemetry},
      {"also_reported_by", json::array()},
  };
  EXPECT_EQ(valves_json(table, {{1, 90.0}}), json::array({expected}));
}

TEST(WebValves, UnknownValuesAreNullAndValvesAreSortedBySerial) {
  const json valves = valves_json(three_valves(), {});
  ASSERT_EQ(valves.size(), 3u);
  EXPECT_EQ(valves[0]["serial"], "TJV000001");
  EXPECT_EQ(valves[2]["serial"], "TJV000003");
  EXPECT_EQ(valves[2]["online"], false);
  for (const char* field :
       {"position", "temperature_c", "volts", "target", "amps", "speed_percent", "direction"}) {
    EXPECT_TRUE(valves[0][field].is_null()) << field;
  }
  EXPECT_EQ(valves[0]["errors"], json::array());
}

TEST(WebValves, AnEmptyTableIsAnEmptyArray) { EXPECT_EQ(valves_json({}, {}).dump(), "[]"); }

TEST(WebGateways, HealthHasBusStateErrorCountersFramesAndDrops) {
  client::ValveTable table;
  table.on_gateway_status(bench_status());
  ASSERT_EQ(table.gateways().size(), 1u);
  auto health = gateway_json(table.gateways().at(0));
  const auto claim = health["address_claim"];
  health.erase("address_claim");
  EXPECT_EQ(health.dump(),
            R"({"bus_state":"error_warning","can_interface":"can0","decode_errors":2,)"
            R"("frames_in":1200,"frames_out":340,"gateway":"bench","lost":false,"rx_dropped":5,)"
            R"("rx_errors":3,"tx_errors":97,"valves_known":3,"valves_online":2})");
  EXPECT_EQ(claim["state"], "off");
}

TEST(WebGateways, TheAddressClaimNamesTheHolderAndEveryNeighbourFieldByField) {
  auto status = bench_status();
  status.address_claim(CLAIM_YIELDED);
  status.source_address(0xD5);
  status.name(0x2008800000000000ULL);
  status.address_holder(0x1000000000000001ULL);
  BusNeighbour terminal;
  terminal.address(0x26);
  terminal.name(0xA00C81045A20021BULL);
  terminal.last_seen_ns(1'700'000'000'000'000'000ULL);
  status.neighbours({terminal});
  client::ValveTable table;
  table.on_gateway_status(status);
  const auto claim = gateway_json(table.gateways().at(0))["address_claim"];
  EXPECT_EQ(claim["state"], "yielded");
  EXPECT_EQ(claim["address"], "0xD5");
  EXPECT_EQ(claim["name"]["name"], "0x2008800000000000");
  EXPECT_EQ(claim["holder"]["name"], "0x1000000000000001");
  EXPECT_EQ(claim["holder"]["industry_group"], 1);
  EXPECT_EQ(claim["neighbours"].dump(),
            R"([{"address":"0x26","last_seen_ns":1700000000000000000,"name":{)"
            R"("arbitrary_address_capable":1,"device_class":6,"device_class_instance":0,)"
            R"("ecu_instance":4,"function":129,"function_instance":0,"identity_number":539,)"
            R"("industry_group":2,"manufacturer_code":721,"name":"0xA00C81045A20021B"}}])");
}

TEST(WebUpdates, TheSnapshotHoldsEverythingAndAQuietTickSendsNothing) {
  client::ValveTable table = three_valves();
  table.on_gateway_status(bench_status());
  UpdateBatcher batcher;
  const json snapshot = batcher.snapshot(dashboard_frame(table, {}));
  EXPECT_EQ(snapshot["type"], "snapshot");
  EXPECT_EQ(snapshot["valves"].size(), 3u);
  EXPECT_EQ(snapshot["gateways"].size(), 1u);
  EXPECT_EQ(batcher.tick(dashboard_frame(table, {}), 1000), std::nullopt);
}

TEST(WebUpdates, ATickCarriesOnlyTheLatestStateOfWhatChangedSinceTheLastOne) {
  client::ValveTable table = three_valves();
  UpdateBatcher batcher;
  batcher.snapshot(dashboard_frame(table, {}));
  // Three samples of valve 2 between ticks: one entry, the latest.
  table.on_telemetry(2, codec::Position{10.0}, 1);
  table.on_telemetry(2, codec::Position{10.5}, 2);
  table.on_telemetry(2, codec::Position{11.0}, 3);
  const auto update = batcher.tick(dashboard_frame(table, {}), 40);
  ASSERT_TRUE(update);
  EXPECT_EQ((*update)["type"], "update");
  EXPECT_EQ((*update)["tick"], 1);
  EXPECT_EQ((*update)["stamp_ms"], 40);
  ASSERT_EQ((*update)["valves"].size(), 1u);
  EXPECT_EQ((*update)["valves"][0]["serial"], "TJV000002");
  EXPECT_EQ((*update)["valves"][0]["position"], 11.0);
  EXPECT_EQ((*update)["gateways"], json::array());
  EXPECT_EQ((*update)["statuses"], json::array());
  EXPECT_EQ(batcher.tick(dashboard_frame(table, {}), 80), std::nullopt);
}

TEST(WebUpdates, ANewValveAGatewayChangeAndATargetAppearInTheNextTick) {
  client::ValveTable table = three_valves();
  UpdateBatcher batcher;
  batcher.snapshot(dashboard_frame(table, {}));
  table.on_presence(presence(4, true));
  table.on_gateway_status(bench_status());
  const auto update = batcher.tick(dashboard_frame(table, {{1, 90.0}}), 40);
  ASSERT_TRUE(update);
  ASSERT_EQ((*update)["valves"].size(), 2u);
  EXPECT_EQ((*update)["valves"][0]["serial"], "TJV000001");
  EXPECT_EQ((*update)["valves"][0]["target"], 90.0);
  EXPECT_EQ((*update)["valves"][1]["serial"], "TJV000004");
  ASSERT_EQ((*update)["gateways"].size(), 1u);
  EXPECT_EQ((*update)["gateways"][0]["gateway"], "bench");
}

// The server's tick builds JSON only for the rows changed since the last tick and those whose
// target changed: the page gets what a frame of every valve would have sent it.
TEST(WebUpdates, AFrameOfTheChangedAndRetargetedRowsSendsWhatAFrameOfEveryRowWould) {
  client::ValveTable table = three_valves();
  table.on_telemetry(1, codec::Position{5.0}, 1);
  UpdateBatcher every, changed;
  every.snapshot(dashboard_frame(table, {}));
  changed.snapshot(dashboard_frame(table, {}));
  const std::uint64_t sent = table.revision();
  table.on_telemetry(2, codec::Position{33.0}, 5);
  table.on_telemetry(1, codec::Position{5.0}, 6);  // the same again
  const Targets targets{{3, 45.0}};
  const auto also = retargeted({}, targets);
  EXPECT_EQ(also, (std::set<std::uint32_t>{3}));
  const auto rows = table.rows_changed_since(sent, also);
  ASSERT_EQ(rows.size(), 2u);
  const auto update = changed.tick(dashboard_frame(rows, table.gateways(), {}, targets), 40);
  ASSERT_TRUE(update);
  EXPECT_EQ(*update, every.tick(dashboard_frame(table, targets), 40));
  ASSERT_EQ((*update)["valves"].size(), 2u);
  EXPECT_EQ((*update)["valves"][0]["position"], 33.0);
  EXPECT_EQ((*update)["valves"][1]["target"], 45.0);
  EXPECT_EQ(retargeted(targets, {}), (std::set<std::uint32_t>{3}));
  EXPECT_EQ(retargeted(targets, {{3, 50.0}}), (std::set<std::uint32_t>{3}));
  EXPECT_TRUE(retargeted(targets, targets).empty());
}

TEST(WebUpdates, EveryStatusSinceTheLastTickIsSentOnceInOrder) {
  client::ValveTable table = three_valves();
  UpdateBatcher batcher;
  batcher.snapshot(dashboard_frame(table, {}));
  batcher.add_status(status(1, 7, COMMAND_ACCEPTED));
  batcher.add_status(status(1, 7, COMMAND_COMPLETED));
  const auto update = batcher.tick(dashboard_frame(table, {}), 40);
  ASSERT_TRUE(update);
  ASSERT_EQ((*update)["statuses"].size(), 2u);
  EXPECT_EQ((*update)["statuses"][0]["state"], "accepted");
  EXPECT_EQ((*update)["statuses"][1]["state"], "completed");
  EXPECT_EQ((*update)["statuses"][1]["command_id"], 7);
  EXPECT_EQ((*update)["statuses"][1]["serial"], "TJV000001");
  EXPECT_EQ(batcher.tick(dashboard_frame(table, {}), 80), std::nullopt);
}

TEST(WebUpdates, ALayoutChangesStatusGoesWithTheCommandsInOrder) {
  client::ValveTable table = three_valves();
  UpdateBatcher batcher;
  batcher.snapshot(dashboard_frame(table, {}));
  batcher.add_status(status(1, 7, COMMAND_COMPLETED));
  LayoutChangeStatus change;
  change.change_id(4);
  change.origin("teejet-web@host:1");
  change.location("section-03");
  change.gateway("gw");
  change.kind(LAYOUT_ASSIGN);
  change.state(LAYOUT_CHANGE_REJECTED);
  change.serial(0);
  change.reason("TJV000009 is not online on this gateway's bus");
  batcher.add_status(change);
  const auto update = batcher.tick(dashboard_frame(table, {}), 40);
  ASSERT_TRUE(update);
  ASSERT_EQ((*update)["statuses"].size(), 2u);
  EXPECT_EQ((*update)["statuses"][0]["event"], "status");
  EXPECT_EQ((*update)["statuses"][1],
            (json{{"event", "layout_change"},
                  {"location", "section-03"},
                  {"gateway", "gw"},
                  {"kind", "assign"},
                  {"state", "rejected"},
                  {"serial", nullptr},
                  {"reason", "TJV000009 is not online on this gateway's bus"},
                  {"change_id", 4},
                  {"origin", "teejet-web@host:1"}}));
}

TEST(WebUpdates, EveryPlaceIsInTheSnapshotInMachineOrderAndAChangedOneInTheNextTick) {
  client::ValveTable table = three_valves();
  const auto place = [](const char* name, std::uint16_t order, std::uint32_t serial,
                        LocationState state) {
    ValveLocation sample;
    sample.location(name);
    sample.gateway("gw");
    sample.order(order);
    sample.role(order == 1 ? ROLE_MASTER : ROLE_SECTION);
    sample.assigned(serial != 0);
    sample.serial(serial);
    sample.state(state);
    sample.mechanics_known(true);
    sample.closed_degrees(0.0f);
    sample.opened_degrees(order == 1 ? 360.0f : 90.0f);
    return sample;
  };
  table.on_location(place("section-01", 2, 2, LOCATION_OK));
  table.on_location(place("left-master", 1, 1, LOCATION_OK));
  table.on_location(place("section-02", 3, 0, LOCATION_EMPTY));
  UpdateBatcher batcher;
  const json snapshot = batcher.snapshot(dashboard_frame(table, {}));
  ASSERT_EQ(snapshot["places"].size(), 3u);
  EXPECT_EQ(snapshot["places"][0].dump(),
            R"({"closed_deg":0.0,"gateway":"gw","location":"left-master","opened_deg":360.0,)"
            R"("order":1,"role":"master","serial":"TJV000001","state":"ok"})");
  EXPECT_EQ(snapshot["places"][1]["location"], "section-01");
  EXPECT_EQ(snapshot["places"][2]["serial"], nullptr);
  EXPECT_EQ(snapshot["places"][2]["state"], "empty");
  EXPECT_EQ(batcher.tick(dashboard_frame(table, {}), 40), std::nullopt);

  table.on_location(place("section-02", 3, 3, LOCATION_OK));  // a valve put there
  const auto update = batcher.tick(dashboard_frame(table, {}), 80);
  ASSERT_TRUE(update);
  ASSERT_EQ((*update)["places"].size(), 1u);
  EXPECT_EQ((*update)["places"][0]["serial"], "TJV000003");
  EXPECT_EQ((*update)["places"][0]["state"], "ok");
}

}  // namespace
}  // namespace teejet::web
