// What valvectl prints: the table, the JSON list and the status, position and reply lines.

#include <gtest/gtest.h>

#include "render.hpp"
#include "teejet/codec/table.hpp"

namespace teejet::valvectl {
namespace {

void tell(ValveRow& row, const codec::FromValveMessage& message) {
  row.telemetry.insert_or_assign(std::string(codec::subject(message)), Reply{1, message});
}

std::vector<ValveRow> two_valves() {
  ValveRow moving;
  moving.serial = 1;
  moving.address = 0xD8;
  moving.online = true;
  moving.gateway = "boom";
  moving.location = "section-01";
  tell(moving, codec::Position{45.0});
  tell(moving, codec::Temperature{25, 24});
  tell(moving, codec::Voltage{12.3});
  ValveRow faulty;
  faulty.serial = 123456;
  faulty.address = 0xF7;
  faulty.online = false;
  faulty.gateway = "boom";
  faulty.errors = {ERROR_HIGH_VOLTAGE, ERROR_MIN_DEGREES_PER_SECOND};
  return {moving, faulty};
}

TEST(ValvectlRender, TableAlignsColumnsAndShowsMissingValuesAsDashes) {
  // clang-format off
  const char* expected =
R"(SERIAL     ADDR  ONLINE  POS_DEG  TEMP_C  VOLTS  ERRORS                               GATEWAY  LOCATION
TJV000001  0xD8  yes        45.0      25   12.3  -                                    boom     section-01
TJV123456  0xF7  no            -       -      -  high_voltage,min_degrees_per_second  boom     -
)";
  // clang-format on
  EXPECT_EQ(render_table(two_valves()), expected);
}

TEST(ValvectlRender, EmptyTableIsItsHeader) {
  EXPECT_EQ(render_table({}),
            "SERIAL  ADDR  ONLINE  POS_DEG  TEMP_C  VOLTS  ERRORS  GATEWAY  LOCATION\n");
}

TEST(ValvectlRender, BootModeShowsInTheOnlineColumn) {
  auto rows = two_valves();
  rows[0].boot_mode = true;
  EXPECT_NE(render_table(rows).find("0xD8  boot"), std::string::npos);
}

TEST(ValvectlRender, ASerialOnlineOnTwoGatewaysGetsAWarningBelowTheTable) {
  auto rows = two_valves();
  rows[0].also_reported_by = {"rig-2"};
  const auto table = render_table(rows);
  EXPECT_NE(
      table.find("\nwarning: TJV000001 is online on boom and on rig-2: two valves carry this "
                 "serial, or something replays it; its gateways refuse commands to it but Stop "
                 "until only one reports it\n"),
      std::string::npos)
      << table;
  EXPECT_EQ(to_json(rows)[0]["also_reported_by"], (nlohmann::json{"rig-2"}));
  EXPECT_EQ(to_json(rows)[1]["also_reported_by"], nlohmann::json::array());
}

TEST(ValvectlRender, JsonListHasOneObjectPerValveWithNullsForMissingValues) {
  const auto json = to_json(two_valves());
  ASSERT_TRUE(json.is_array());
  ASSERT_EQ(json.size(), 2u);
  EXPECT_EQ(json[0]["serial"], "TJV000001");
  EXPECT_EQ(json[0]["address"], 216);
  EXPECT_EQ(json[0]["online"], true);
  EXPECT_DOUBLE_EQ(json[0]["position"].get<double>(), 45.0);
  EXPECT_EQ(json[0]["temperature_c"], 25);
  EXPECT_DOUBLE_EQ(json[0]["volts"].get<double>(), 12.3);
  EXPECT_EQ(json[0]["telemetry"]["temperature"],
            (nlohmann::json{{"valve_c", 25}, {"sensor_c", 24}}));
  EXPECT_EQ(json[0]["telemetry"]["position"].dump(), R"({"degrees":45.0})");
  EXPECT_EQ(json[1]["telemetry"], nlohmann::json::object());
  EXPECT_EQ(json[0]["errors"], nlohmann::json::array());
  EXPECT_EQ(json[0]["gateway"], "boom");
  EXPECT_TRUE(json[1]["position"].is_null());
  EXPECT_TRUE(json[1]["temperature_c"].is_null());
  EXPECT_TRUE(json[1]["volts"].is_null());
  EXPECT_EQ(json[1]["errors"], (nlohmann::json{"high_voltage", "min_degrees_per_second"}));
  EXPECT_EQ(to_json(std::vector<ValveRow>{}).dump(), "[]");
}

CommandStatus status(CommandState state, const std::string& reason = "") {
  CommandStatus s;
  s.serial(2);
  s.command_id(17);
  s.origin("valvectl@host:1");
  s.kind(COMMAND_TARGET_DEGREES);
  s.state(state);
  s.reason(reason);
  s.stamp_ns(1'700'000'000'000'000'000);
  return s;
}

TEST(ValvectlRender, StatusLineNamesValveKindIdStateAndReason) {
  EXPECT_EQ(status_text(status(COMMAND_ACCEPTED)), "TJV000002 target_degrees #17: ACCEPTED");
  EXPECT_EQ(status_text(status(COMMAND_REJECTED, "valve TJV000002 is offline")),
            "TJV000002 target_degrees #17: REJECTED: valve TJV000002 is offline");
  EXPECT_EQ(status_text(status(COMMAND_TIMED_OUT, "too slow")),
            "TJV000002 target_degrees #17: TIMED_OUT: too slow");
}

TEST(ValvectlRender, StatusJsonCarriesEveryField) {
  const auto json = status_json(status(COMMAND_SUPERSEDED, "replaced by command 18"));
  EXPECT_EQ(json["event"], "status");
  EXPECT_EQ(json["serial"], "TJV000002");
  EXPECT_EQ(json["command_id"], 17);
  EXPECT_EQ(json["origin"], "valvectl@host:1");
  EXPECT_EQ(json["kind"], "target_degrees");
  EXPECT_EQ(json["state"], "superseded");
  EXPECT_EQ(json["reason"], "replaced by command 18");
  EXPECT_EQ(json["stamp_ns"], 1'700'000'000'000'000'000u);
}

TEST(ValvectlRender, PositionAndReplyLines) {
  EXPECT_EQ(position_text(2, 45.25), "TJV000002 position 45.2");
  EXPECT_EQ(position_json(2, 45.3).dump(),
            R"({"degrees":45.3,"event":"position","serial":"TJV000002"})");
  const Reply reply{1'700'000'000'000'000'000, codec::Voltage{12.1}};
  EXPECT_EQ(reply_text(6, reply), "TJV000006 voltage volts=12.1");
  const Reply version{1, codec::VersionInfo{{1, 2, 'e'}, {1, 0, 0}}};
  EXPECT_EQ(reply_text(6, version), "TJV000006 version application=1.02e bootloader=1.00");
  // In the wire's order, whatever the message: the codec's table names the fields.
  const Reply speed{
      1, codec::SpeedDirection{40, codec::Direction::kOpen, codec::Rotation::kCounterclockwise}};
  EXPECT_EQ(reply_text(6, speed),
            "TJV000006 speed_direction speed_percent=40 direction=open "
            "opening_direction=counterclockwise");
  const auto json = reply_json(6, reply);
  EXPECT_EQ(json["event"], "reply");
  EXPECT_EQ(json["reply"], "voltage");
  EXPECT_DOUBLE_EQ(json["values"]["volts"].get<double>(), 12.1);
}

TEST(ValvectlRender, GatewayLine) {
  GatewaySummary gateway;
  gateway.name = "boom";
  gateway.can_interface = "can0";
  gateway.bus_state = BUS_ERROR_PASSIVE;
  gateway.valves_online = 3;
  gateway.valves_known = 4;
  gateway.frames_in = 100;
  gateway.frames_out = 20;
  EXPECT_EQ(render_gateways({gateway}),
            "gateway boom on can0: error_passive, 3/4 valves online, 100 frames in, 20 out, 0 "
            "decode errors; address claiming off\n");
}

TEST(ValvectlRender, TheGatewayLineSaysWhoHoldsItsAddressAndTheNeighboursAreATable) {
  GatewaySummary gateway;
  gateway.name = "boom";
  gateway.can_interface = "can0";
  gateway.valves_online = 3;
  gateway.valves_known = 3;
  gateway.address_claim = CLAIM_CLAIMED;
  gateway.source_address = 0xD5;
  gateway.isobus_name = 0x2008800000000000ULL;
  BusNeighbour terminal;
  terminal.address(0x26);
  terminal.name(0xA00C81045A20021BULL);
  terminal.last_seen_ns(unix_nanoseconds(Timestamp{std::chrono::seconds(1'700'000'000)}));
  gateway.neighbours = {terminal};
  EXPECT_EQ(render_gateways({gateway}),
            "gateway boom on can0: error_active, 3/3 valves online, 0 frames in, 0 out, 0 decode "
            "errors; holds 0xD5 as NAME 0x2008800000000000, 1 neighbour(s)\n");
  EXPECT_EQ(render_neighbours({gateway}, Timestamp{std::chrono::seconds(1'700'000'042)}),
            "GATEWAY  ADDR  NAME                INDUSTRY  DEVICE_CLASS  FUNCTION  MANUFACTURER  "
            "IDENTITY  LAST_SEEN\n"
            "boom     0x26  0xA00C81045A20021B         2             6       129           721  "
            "     539   42 s ago\n");
  gateway.address_claim = CLAIM_YIELDED;
  gateway.address_holder = 0x20087FFFFFFFFFFFULL;
  gateway.address_violations = 2;
  gateway.neighbours.clear();
  EXPECT_EQ(render_gateways({gateway}),
            "gateway boom on can0: error_active, 3/3 valves online, 0 frames in, 0 out, 0 decode "
            "errors; GAVE UP 0xD5 to NAME 0x20087FFFFFFFFFFF: sends nothing, refuses commands, 2 "
            "address violation(s)\n");
  EXPECT_EQ(render_neighbours({gateway}, Timestamp{}),
            "no ECU has claimed an address on boom (can0)\n");
  const auto json = neighbours_json({gateway});
  EXPECT_EQ(json[0]["address_claim"]["state"], "yielded");
  EXPECT_EQ(json[0]["address_claim"]["holder"]["name"], "0x20087FFFFFFFFFFF");
  EXPECT_EQ(json[0]["address_claim"]["name"]["industry_group"], 2);
  EXPECT_EQ(json[0]["address_claim"]["name"]["device_class"], 4);
}

TEST(ValvectlRender, LayoutListsThePlacesInMachineOrderAndTheValvesInNone) {
  ValveTable table;
  const auto place = [&](const char* name, unsigned order, std::optional<std::uint32_t> serial,
                         LocationState state, const char* gateway = "boom") {
    ValveLocation p;
    p.location(name);
    p.gateway(gateway);
    p.order(static_cast<std::uint16_t>(order));
    p.role(order == 1 ? ROLE_MASTER : ROLE_SECTION);
    p.assigned(serial.has_value());
    p.serial(serial.value_or(0));
    p.state(state);
    p.mechanics_known(true);
    p.opened_degrees(90);
    table.on_location(p);
  };
  place("section-01", 2, 1, LOCATION_OK);
  place("left-master", 1, 99, LOCATION_MISSING);
  place("section-02", 3, std::nullopt, LOCATION_EMPTY);
  place("section-02", 3, std::nullopt, LOCATION_EMPTY, "rig-2");
  ValvePresence one;
  one.serial(1);
  one.address(0xD8);
  one.online(true);
  one.gateway("boom");
  one.location("section-01");
  table.on_presence(one);
  table.on_telemetry(1, codec::Position{45.0}, 1);
  ValvePresence stray = one;
  stray.serial(6);
  stray.address(0xDD);
  stray.location("");
  table.on_presence(stray);
  // clang-format off
  const char* expected =
R"(ORDER  LOCATION     ROLE     SERIAL     STATE    POS_DEG  ADDR  GATEWAY
    1  left-master  master   TJV000099  missing        -  -     boom
    2  section-01   section  TJV000001  ok          45.0  0xD8  boom
    3  section-02   section  -          empty          -  -     boom
    3  section-02   section  -          empty          -  -     rig-2
warning: section-02 is a place in the layouts of boom and rig-2: one name for two places; rename one of them
unassigned: TJV000006 at 0xDD on boom is online and sits in no place
)";
  // clang-format on
  EXPECT_EQ(render_layout(table), expected);
  const auto json = layout_json(table);
  EXPECT_EQ(json["locations"][1].dump(),
            R"({"address":216,"closed_deg":0.0,"gateway":"boom","location":"section-01",)"
            R"("opened_deg":90.0,"order":2,"position":45.0,"role":"section","serial":"TJV000001",)"
            R"("state":"ok"})");
  EXPECT_EQ(json["locations"][0]["position"], nullptr);
  EXPECT_EQ(json["unassigned"].dump(), R"(["TJV000006"])");
}

}  // namespace
}  // namespace teejet::valvectl
