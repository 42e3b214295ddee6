// What valvectl prints: the table, the JSON list and the status, position and reply lines.

#include <gtest/gtest.h>

#include <cstdio>

#include "render.hpp"

namespace teejet::valvectl {
namespace {

std::vector<ValveRow> two_valves() {
  ValveRow moving;
  moving.serial = 1;
  moving.address = 0xD8;
  moving.online = true;
  moving.gateway = "boom";
  moving.position_degrees = 45.0;
  moving.temperature_c = 25;
  moving.volts = 12.3;
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
R"(SERIAL     ADDR  ONLINE  POS_DEG  TEMP_C  VOLTS  ERRORS                               GATEWAY
TJV000001  0xD8  yes        45.0      25   12.3  -                                    boom
TJV123456  0xF7  no            -       -      -  high_voltage,min_degrees_per_second  boom
)";
  // clang-format on
  EXPECT_EQ(render_table(two_valves()), expected);
}

TEST(ValvectlRender, EmptyTableIsItsHeader) {
  EXPECT_EQ(render_table({}), "SERIAL  ADDR  ONLINE  POS_DEG  TEMP_C  VOLTS  ERRORS  GATEWAY\n");
}

TEST(ValvectlRender, BootModeShowsInTheOnlineColumn) {
  auto rows = two_valves();
  rows[0].boot_mode = true;
  EXPECT_NE(render_table(rows).find("0xD8  boot"), std::string::npos);
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
  const Reply reply{1'700'000'000'000'000'000, {{"volts", 12.1}}};
  EXPECT_EQ(reply_text(6, "voltage", reply), "TJV000006 voltage volts=12.1");
  const Reply version{1, {{"application", "1.02e"}, {"bootloader", "1.00"}}};
  EXPECT_EQ(reply_text(6, "version", version),
            "TJV000006 version application=1.02e bootloader=1.00");
  const auto json = reply_json(6, "voltage", reply);
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
            "decode errors\n");
}

// --json printed 74.60000000000001 for the 74.6 a valve sent. Every value of the wire's grid,
// as the float DDS carries it, prints as the decimal the valve sent.
TEST(ValvectlRender, JsonPrintsEveryPositionOfTheSheetAsTheValveSentIt) {
  EXPECT_EQ(position_json(1, at_resolution(74.6f, 10)).dump(),
            R"({"degrees":74.6,"event":"position","serial":"TJV000001"})");
  int wrong = 0;
  for (int tenths = 0; tenths <= 3599; ++tenths) {
    char expected[16];
    std::snprintf(expected, sizeof expected, "%d.%d", tenths / 10, tenths % 10);
    const auto sent = static_cast<float>(tenths) / 10.0f;
    const std::string printed = nlohmann::json(at_resolution(sent, 10)).dump();
    if (printed != expected) {
      ++wrong;
      ADD_FAILURE() << "sent " << expected << ", printed " << printed;
    }
  }
  EXPECT_EQ(wrong, 0);
}

TEST(ValvectlRender, JsonPrintsHundredthsAsTheValveSentThem) {
  for (const auto& [sent, expected] : std::vector<std::pair<float, std::string>>{
           {0.35f, "0.35"}, {1.07f, "1.07"}, {12.29f, "12.29"}, {655.35f, "655.35"}}) {
    EXPECT_EQ(nlohmann::json(at_resolution(sent, 100)).dump(), expected);
  }
  ValveRow row;
  row.serial = 2;
  row.volts = at_resolution(13.7f, 10);
  EXPECT_EQ(to_json(row)["volts"].dump(), "13.7");
}

}  // namespace
}  // namespace teejet::valvectl
