// The commands teejet-web accepts from the page: checked with valvectl's rules, refused with a
// reason, and never handed to DDS when refused.

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "page_command.hpp"
#include "web_fixture.hpp"

namespace teejet::web {
namespace {

using nlohmann::json;

using testing::RecordingSender;

const CommandPolicy kAllow{true, ""};

// The reason a message is refused with, with commands allowed; "" when it was sent. Refused
// messages must reach no valve.
std::string refusal(std::string_view text, const CommandPolicy& policy = kAllow,
                    const client::ValveTable& table = testing::three_valves()) {
  RecordingSender sender;
  const json answer = handle_page_message(text, table, policy, sender);
  if (answer["type"] == "sent") return "";
  EXPECT_EQ(answer["type"], "refused");
  EXPECT_TRUE(sender.sent.empty()) << text;
  EXPECT_TRUE(sender.changes.empty()) << text;
  return answer["reason"].get<std::string>();
}
std::string refusal_on_the_boom(std::string_view text) {
  return refusal(text, kAllow, testing::three_valves_on_a_boom());
}

TEST(WebCommands, AMoveIsSentWithItsValuesAndTheAnswerNamesTheCommandId) {
  RecordingSender sender;
  const json answer = handle_page_message(
      R"({"id":5,"command":"move","serial":"TJV000002","degrees":90.5,"speed_percent":80,)"
      R"("direction":"shortest"})",
      testing::three_valves(), kAllow, sender);
  EXPECT_EQ(answer,
            (json{{"type", "sent"},
                  {"id", 5},
                  {"commands", json::array({{{"serial", "TJV000002"}, {"command_id", 100}}})}}));
  ASSERT_EQ(sender.sent.size(), 1u);
  const ValveCommand& command = sender.sent[0];
  EXPECT_EQ(command.serial(), 2u);
  EXPECT_EQ(command.kind(), COMMAND_TARGET_DEGREES);
  EXPECT_EQ(command.degrees(), 90.5f);
  EXPECT_EQ(command.speed_percent(), 80);
  EXPECT_EQ(command.direction(), DIRECTION_SHORTEST);
}

TEST(WebCommands, EveryCommandOfThePageBuildsItsValveCommand) {
  const auto table = testing::three_valves();
  const auto parse = [&](std::string_view text) {
    auto command = parse_page_command(text, table);
    EXPECT_TRUE(command) << text << ": " << (command ? "" : command.error().reason);
    return command ? command->command : ValveCommand{};
  };
  EXPECT_EQ(parse(R"({"command":"stop","serial":"TJV000001"})").kind(), COMMAND_STOP);
  EXPECT_EQ(parse(R"({"command":"clear_errors","serial":"1"})").kind(), COMMAND_CLEAR_ERRORS);
  const ValveCommand manual =
      parse(R"({"command":"manual","serial":"TJV000001","speed_percent":30,"direction":"close"})");
  EXPECT_EQ(manual.kind(), COMMAND_MANUAL);
  EXPECT_EQ(manual.speed_percent(), 30);
  EXPECT_EQ(manual.direction(), DIRECTION_CLOSE);
  const ValveCommand jog =
      parse(R"({"command":"jog","serial":"TJV000001","milliseconds":65535,"speed_percent":100,)"
            R"("direction":"open"})");
  EXPECT_EQ(jog.kind(), COMMAND_MILLISECONDS_TO_RUN);
  EXPECT_EQ(jog.milliseconds(), 65535);
  EXPECT_EQ(jog.direction(), DIRECTION_OPEN);
  const ValveCommand request = parse(
      R"({"command":"request","serial":"TJV000001","telemetry":"run-time","resend_tenths":5})");
  EXPECT_EQ(request.kind(), COMMAND_REQUEST);
  EXPECT_EQ(request.telemetry(), TELEMETRY_RUN_TIME);
  EXPECT_EQ(request.resend_tenths(), 5);
}

TEST(WebCommands, StopAllStopsEveryOnlineValveAndNoOther) {
  RecordingSender sender;
  const json answer =
      handle_page_message(R"({"command":"stop_all"})", testing::three_valves(), kAllow, sender);
  EXPECT_EQ(answer["commands"].size(), 2u);
  ASSERT_EQ(sender.sent.size(), 2u);
  EXPECT_EQ(sender.sent[0].serial(), 1u);
  EXPECT_EQ(sender.sent[1].serial(), 2u);
  EXPECT_EQ(sender.sent[1].kind(), COMMAND_STOP);
  EXPECT_EQ(answer["id"], nullptr);
}

TEST(WebCommands, ACommandDdsDidNotTakeSaysWhy) {
  RecordingSender sender;
  sender.failing = true;
  const json answer = handle_page_message(R"({"command":"stop","serial":"TJV000001"})",
                                          testing::three_valves(), kAllow, sender);
  EXPECT_EQ(answer["type"], "sent");
  EXPECT_EQ(
      answer["commands"],
      json::array({{{"serial", "TJV000001"}, {"error", "no gateway subscribes to commands"}}}));
}

TEST(WebCommands, OutOfRangeValuesAreRefusedWithTheCodecsRules) {
  EXPECT_EQ(refusal(R"({"command":"move","serial":"TJV000001","degrees":360,)"
                    R"("speed_percent":100,"direction":"open"})"),
            "move: degrees 360 is outside 0 to 359.9");
  EXPECT_EQ(refusal(R"({"command":"move","serial":"TJV000001","degrees":-0.1,)"
                    R"("speed_percent":100,"direction":"open"})"),
            "move: degrees -0.1 is outside 0 to 359.9");
  EXPECT_EQ(refusal(R"({"command":"manual","serial":"TJV000001","speed_percent":101,)"
                    R"("direction":"open"})"),
            "manual: speed_percent 101 is outside 0 to 100");
  EXPECT_EQ(refusal(R"({"command":"manual","serial":"TJV000001","speed_percent":-5,)"
                    R"("direction":"open"})"),
            "manual: speed_percent -5 is outside 0 to 100");
  EXPECT_EQ(refusal(R"({"command":"manual","serial":"TJV000001","speed_percent":2.5,)"
                    R"("direction":"open"})"),
            "manual: speed_percent 2.5 is not a whole number");
  EXPECT_EQ(refusal(R"({"command":"jog","serial":"TJV000001","milliseconds":65536,)"
                    R"("speed_percent":100,"direction":"open"})"),
            "jog: milliseconds 65536 is outside 0 to 65535");
  EXPECT_EQ(refusal(R"({"command":"manual","serial":"TJV000001","speed_percent":10,)"
                    R"("direction":"shortest"})"),
            "manual: direction \"shortest\" is not one of close, open");
  EXPECT_EQ(refusal(R"({"command":"request","serial":"TJV000001","telemetry":"version",)"
                    R"("resend_tenths":5})"),
            "request: resend_tenths must be 0: a valve sends its version once");
  EXPECT_EQ(refusal(R"({"command":"request","serial":"TJV000001","telemetry":"position",)"
                    R"("resend_tenths":256})"),
            "request: resend_tenths 256 is outside 0 to 255");
  EXPECT_EQ(refusal(R"({"command":"request","serial":"TJV000001","telemetry":"pressure",)"
                    R"("resend_tenths":0})"),
            "request: telemetry \"pressure\" is not one of version position temperature voltage "
            "current degrees_per_second speed_direction run_time cycle_counts");
}

TEST(WebCommands, UnknownOrInvalidSerialsAreRefused) {
  EXPECT_EQ(refusal(R"({"command":"stop","serial":"TJV000009"})"),
            "unknown serial TJV000009: no gateway knows it");
  EXPECT_EQ(refusal(R"({"command":"stop","serial":1})"),
            "serial must be a string like \"TJV000001\"");
  EXPECT_EQ(refusal(R"({"command":"stop","serial":"TJX1"})").substr(0, 16), "invalid serial: ");
}

TEST(WebCommands, MalformedUnknownAndIncompleteMessagesAreRefused) {
  EXPECT_EQ(refusal(R"({"command":"stop",)"), "malformed JSON");
  EXPECT_EQ(refusal(""), "malformed JSON");
  EXPECT_EQ(refusal("[1,2]"), "a command must be a JSON object");
  EXPECT_EQ(refusal(R"({"serial":"TJV000001"})"),
            "missing \"command\": one of move, stop, stop_all, manual, jog, request, clear_errors, "
            "assign, unassign");
  EXPECT_EQ(refusal(R"({"command":"fly","serial":"TJV000001"})"),
            "unknown command \"fly\": one of move, stop, stop_all, manual, jog, request, "
            "clear_errors, assign, unassign");
  EXPECT_EQ(refusal(R"({"command":"move","serial":"TJV000001","degrees":10})"),
            "move: missing \"speed_percent\"");
  EXPECT_EQ(refusal(R"({"command":"stop","serial":"TJV000001","degrees":10})"),
            "stop: unknown field \"degrees\"");
  EXPECT_EQ(refusal(R"({"command":"move","serial":"TJV000001","degrees":"10",)"
                    R"("speed_percent":100,"direction":"open"})"),
            "move: degrees \"10\" is not a number");
}

TEST(WebCommands, AMessageOverFourKibibytesIsRefusedUnread) {
  const std::string padding(kMaxCommandBytes, ' ');
  EXPECT_EQ(refusal(R"({"command":"stop","serial":"TJV000001"})" + padding),
            "message of 4135 bytes is over the limit of 4096");
  // Exactly at the limit is still read.
  const std::string command = R"({"command":"stop","serial":"TJV000001"})";
  EXPECT_EQ(refusal(command + std::string(kMaxCommandBytes - command.size(), ' ')), "");
}

TEST(WebCommands, AReadOnlyServerRefusesEveryCommandButEchoesItsId) {
  RecordingSender sender;
  const json answer =
      handle_page_message(R"({"id":"a1","command":"stop","serial":"TJV000001"})",
                          testing::three_valves(), CommandPolicy{false, ""}, sender);
  EXPECT_EQ(answer, (json{{"type", "refused"},
                          {"id", "a1"},
                          {"reason",
                           "commands are disabled: teejet-web runs read-only (start it "
                           "with --allow-commands)"}}));
  EXPECT_TRUE(sender.sent.empty());
  EXPECT_EQ(refusal(R"({"command":"stop_all"})", CommandPolicy{false, ""}),
            "commands are disabled: teejet-web runs read-only (start it with --allow-commands)");
}

TEST(WebCommands, WithATokenOnlyCommandsCarryingItAreSent) {
  const CommandPolicy policy{true, "s3cret"};
  EXPECT_EQ(refusal(R"({"command":"stop","serial":"TJV000001"})", policy),
            "missing or wrong \"token\"");
  EXPECT_EQ(refusal(R"({"command":"stop","serial":"TJV000001","token":"guess"})", policy),
            "missing or wrong \"token\"");
  EXPECT_EQ(refusal(R"({"command":"stop","serial":"TJV000001","token":"s3cret"})", policy), "");
  EXPECT_EQ(refusal(R"({"command":"stop",)", policy), "malformed JSON");
  EXPECT_EQ(refusal("[]", policy), "a command must be a JSON object");
}

// {"id":[[[...]]]}: 500 levels in 1 KB once took down a CivetWeb worker (its 100 KiB stack) in
// the dump() of the answer that echoed the id.
TEST(WebCommands, DeeplyNestedJsonIsRefusedUnparsedAndNotEchoed) {
  const std::string bomb = R"({"id":)" + std::string(500, '[') + std::string(500, ']') + "}";
  RecordingSender sender;
  EXPECT_EQ(
      handle_page_message(bomb, testing::three_valves(), kAllow, sender),
      (json{{"type", "refused"}, {"id", nullptr}, {"reason", "JSON nested deeper than 4 levels"}}));
  EXPECT_EQ(handle_page_message(bomb, testing::three_valves(), CommandPolicy{false, ""}, sender),
            (json{{"type", "refused"},
                  {"id", nullptr},
                  {"reason",
                   "commands are disabled: teejet-web runs read-only (start it with "
                   "--allow-commands)"}}));
  EXPECT_TRUE(sender.sent.empty());
  EXPECT_EQ(refusal(R"({"command":"stop","serial":"TJV000001","x":[[[[1]]]]})"),
            "JSON nested deeper than 4 levels");
  // Brackets inside strings are text, not nesting.
  EXPECT_EQ(refusal(R"({"id":"[[[[[\"[[","command":"stop","serial":"TJV000001"})"), "");
  EXPECT_EQ(refusal(R"({"command":"stop","serial":"TJV000001","x":[[[1]]]})"),
            "stop: unknown field \"x\"");
}

TEST(WebCommands, OnlyANumberOrAShortStringIdIsEchoed) {
  const auto id_of = [](const std::string& id) {
    RecordingSender sender;
    return handle_page_message(R"({"command":"stop","serial":"TJV000001","id":)" + id + "}",
                               testing::three_valves(), kAllow, sender)["id"];
  };
  EXPECT_EQ(id_of("7"), 7);
  EXPECT_EQ(id_of("-2.5"), -2.5);
  EXPECT_EQ(id_of('"' + std::string(kMaxIdBytes, 'a') + '"'), std::string(kMaxIdBytes, 'a'));
  EXPECT_EQ(id_of('"' + std::string(kMaxIdBytes + 1, 'a') + '"'), nullptr);
  EXPECT_EQ(id_of(R"({"a":1})"), nullptr);
  EXPECT_EQ(id_of("[1]"), nullptr);
  EXPECT_EQ(id_of("true"), nullptr);
  EXPECT_EQ(id_of("null"), nullptr);
}

TEST(WebCommands, AValveNamedByItsPlaceIsCommandedByTheSerialThatSitsThere) {
  RecordingSender sender;
  const json answer = handle_page_message(R"({"id":1,"command":"stop","location":"section-02"})",
                                          testing::three_valves_on_a_boom(), kAllow, sender);
  EXPECT_EQ(answer["commands"], json::array({{{"serial", "TJV000002"}, {"command_id", 100}}}));
  ASSERT_EQ(sender.sent.size(), 1u);
  EXPECT_EQ(sender.sent[0].serial(), 2u);
  EXPECT_EQ(sender.sent[0].kind(), COMMAND_STOP);
}

TEST(WebCommands, APlaceThatNamesNoKnownValveOrTwoGatewaysClaimIsRefused) {
  EXPECT_EQ(refusal_on_the_boom(R"({"command":"stop","location":"section-09"})"),
            "unknown location \"section-09\": no gateway's layout has it");
  EXPECT_EQ(refusal_on_the_boom(R"({"command":"stop","location":"section-03"})"),
            "location \"section-03\" on gw is empty: no valve sits there");
  EXPECT_EQ(refusal_on_the_boom(R"({"command":"stop","location":"section-04"})"),
            "location \"section-04\" holds TJV000009, which no gateway knows");
  EXPECT_EQ(refusal_on_the_boom(R"({"command":"stop","location":"twice"})"),
            "location \"twice\" is in the layouts of 2 gateways (gw, gw2): a name belongs to one");
  EXPECT_EQ(refusal_on_the_boom(R"({"command":"stop","location":"section-01","serial":"1"})"),
            "stop: name the valve by \"serial\" or by \"location\", not both");
  EXPECT_EQ(refusal_on_the_boom(R"({"command":"stop","location":7})"),
            "location must be a string like \"section-01\"");
  EXPECT_EQ(refusal_on_the_boom(R"({"command":"stop_all","location":"section-01"})"),
            "stop_all: unknown field \"location\"");
}

TEST(WebCommands, AnAssignmentGoesToTheGatewayWhoseLayoutHoldsThePlace) {
  RecordingSender sender;
  const json answer = handle_page_message(
      R"({"id":"a","command":"assign","location":"section-03","serial":"TJV000003","move":true})",
      testing::three_valves_on_a_boom(), kAllow, sender);
  EXPECT_EQ(
      answer,
      (json{{"type", "sent"},
            {"id", "a"},
            {"changes",
             json::array({{{"location", "section-03"}, {"gateway", "gw"}, {"change_id", 100}}})}}));
  ASSERT_EQ(sender.changes.size(), 1u);
  const auto& [change, participant] = sender.changes[0];
  EXPECT_EQ(participant, "01.0f.aa");
  EXPECT_EQ(change.location().to_string(), "section-03");
  EXPECT_EQ(change.gateway().to_string(), "gw");
  EXPECT_EQ(change.kind(), LAYOUT_ASSIGN);
  EXPECT_EQ(change.serial(), 3u);
  EXPECT_TRUE(change.move());
  EXPECT_TRUE(sender.sent.empty());

  RecordingSender unassigning;
  handle_page_message(R"({"command":"unassign","location":"section-01"})",
                      testing::three_valves_on_a_boom(), kAllow, unassigning);
  ASSERT_EQ(unassigning.changes.size(), 1u);
  EXPECT_EQ(unassigning.changes[0].first.kind(), LAYOUT_UNASSIGN);
  EXPECT_EQ(unassigning.changes[0].first.location().to_string(), "section-01");
  EXPECT_FALSE(unassigning.changes[0].first.move());
}

TEST(WebCommands, ALayoutChangeIsRefusedWithItsReasonAndReachesNoGateway) {
  EXPECT_EQ(refusal_on_the_boom(R"({"command":"assign","location":"section-09","serial":"3"})"),
            "assign: unknown location \"section-09\": no gateway's layout has it");
  EXPECT_EQ(refusal_on_the_boom(R"({"command":"assign","location":"twice","serial":"3"})"),
            "assign: location \"twice\" is in the layouts of 2 gateways (gw, gw2): a name "
            "belongs to one");
  EXPECT_EQ(refusal_on_the_boom(R"({"command":"assign","location":"section-03"})"),
            "assign: missing \"serial\"");
  EXPECT_EQ(refusal_on_the_boom(R"({"command":"assign","location":"section-03","serial":3})"),
            "assign: serial must be a string like \"TJV000001\"");
  EXPECT_EQ(refusal_on_the_boom(R"({"command":"assign","location":"section-03","serial":"TJX1"})")
                .substr(0, 24),
            "assign: invalid serial: ");
  EXPECT_EQ(refusal_on_the_boom(
                R"({"command":"assign","location":"section-03","serial":"3","move":"yes"})"),
            "assign: move must be true or false");
  EXPECT_EQ(refusal_on_the_boom(R"({"command":"unassign","location":"section-01","serial":"1"})"),
            "unassign: unknown field \"serial\"");
  EXPECT_EQ(refusal(R"({"command":"unassign","location":"section-01"})", CommandPolicy{false, ""},
                    testing::three_valves_on_a_boom()),
            "commands are disabled: teejet-web runs read-only (start it with --allow-commands)");
  EXPECT_EQ(refusal(R"({"command":"unassign","location":"section-01"})", CommandPolicy{true, "k"},
                    testing::three_valves_on_a_boom()),
            "missing or wrong \"token\"");
}

TEST(WebCommands, ALayoutChangeDdsDidNotTakeSaysWhy) {
  RecordingSender sender;
  sender.failing = true;
  const json answer = handle_page_message(R"({"command":"unassign","location":"section-01"})",
                                          testing::three_valves_on_a_boom(), kAllow, sender);
  EXPECT_EQ(answer["changes"], json::array({{{"location", "section-01"},
                                             {"gateway", "gw"},
                                             {"error", "gateway gw did not subscribe"}}}));
}

TEST(WebCommands, ThePolicyTellsThePageWhetherCommandsAndATokenAreNeededButNotTheToken) {
  EXPECT_EQ(command_policy_json({}), (json{{"allowed", false}, {"token_required", false}}));
  EXPECT_EQ(command_policy_json({true, ""}), (json{{"allowed", true}, {"token_required", false}}));
  const json with_token = command_policy_json({true, "s3cret"});
  EXPECT_EQ(with_token, (json{{"allowed", true}, {"token_required", true}}));
  EXPECT_EQ(with_token.dump().find("s3cret"), std::string::npos);
}

}  // namespace
}  // namespace teejet::web
