// teejet-web's Foxglove protocol and each Foxglove client's state, without a socket: the bytes it
// sends, what it makes of what a client sends, the bounded outbox, and a published command
// checked by the page's rules before anything reaches DDS.

#include <fastdds/rtps/common/SerializedPayload.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "foxglove_protocol.hpp"
#include "foxglove_session.hpp"
#include "teejet/recording/catalog.hpp"
#include "teejet/valvePubSubTypes.h"
#include "web_fixture.hpp"

namespace teejet::web::foxglove {
namespace {

using nlohmann::json;
using testing::RecordingSender;

std::vector<std::uint8_t> cdr(ValveCommand command) {
  ValveCommandPubSubType type;
  eprosima::fastrtps::rtps::SerializedPayload_t payload(type.getSerializedSizeProvider(&command)());
  EXPECT_TRUE(type.serialize(&command, &payload));
  return {payload.data, payload.data + payload.length};
}

ValveCommand move(std::uint32_t serial, float degrees) {
  ValveCommand command;
  command.serial(serial);
  command.kind(COMMAND_TARGET_DEGREES);
  command.speed_percent(100);
  command.direction(DIRECTION_OPEN);
  command.degrees(degrees);
  return command;
}

std::string text_of(const std::string& status_text) {
  return json::parse(status_text).at("message").get<std::string>();
}

TEST(FoxgloveProtocol, SpeaksBothSubprotocolNamesInTheClientsOrder) {
  EXPECT_EQ(choose_subprotocol("foxglove.websocket.v1"), "foxglove.websocket.v1");
  EXPECT_EQ(choose_subprotocol("chat, foxglove.sdk.v1"), "foxglove.sdk.v1");
  EXPECT_EQ(choose_subprotocol(" foxglove.sdk.v1 ,foxglove.websocket.v1"), "foxglove.sdk.v1");
  EXPECT_EQ(choose_subprotocol("chat, foxglove.websocket.v2"), std::nullopt);
  EXPECT_EQ(choose_subprotocol(""), std::nullopt);
}

TEST(FoxgloveProtocol, ChannelsAreTheRecordingsTopicsWithDisposalChannelsOfStateTopics) {
  const auto& all = channels();
  ASSERT_FALSE(all.empty());
  for (std::size_t i = 0; i < all.size(); ++i) EXPECT_EQ(all[i].id, i + 1);
  const Channel* position = find_channel("teejet/valve/position");
  ASSERT_NE(position, nullptr);
  const Channel* disposed = find_channel(position->id + 1);
  ASSERT_NE(disposed, nullptr);
  EXPECT_EQ(disposed->name, "teejet/valve/position/disposed");
  EXPECT_TRUE(disposed->disposed);
  EXPECT_EQ(disposed->topic, position->topic);
  EXPECT_EQ(channel_id(position->topic, false), position->id);
  EXPECT_EQ(channel_id(position->topic, true), disposed->id);
  // Commands are events: no disposal channel, as in a recording.
  ASSERT_NE(find_channel("teejet/valve/command"), nullptr);
  EXPECT_EQ(find_channel("teejet/valve/command/disposed"), nullptr);
  EXPECT_EQ(channel_id(find_channel("teejet/valve/command")->topic, true), 0u);
  EXPECT_EQ(find_channel(0), nullptr);
  EXPECT_EQ(find_channel(static_cast<std::uint32_t>(all.size() + 1)), nullptr);
}

TEST(FoxgloveProtocol, ServerInfoAnnouncesClientPublishOnlyWhenAClientMayPublish) {
  const json read_only = json::parse(server_info("teejet-web", false, "42"));
  EXPECT_EQ(read_only.at("op"), "serverInfo");
  EXPECT_EQ(read_only.at("capabilities"), json::array());
  EXPECT_FALSE(read_only.contains("supportedEncodings"));
  EXPECT_EQ(read_only.at("sessionId"), "42");
  const json publishing = json::parse(server_info("teejet-web", true, "42"));
  EXPECT_EQ(publishing.at("capabilities"), json::array({"clientPublish"}));
  EXPECT_EQ(publishing.at("supportedEncodings"), json::array({"cdr"}));
}

TEST(FoxgloveProtocol, AdvertiseCarriesTheRecordingsEncodingsAndTheWholeIdl) {
  const json message = json::parse(advertise({*find_channel("teejet/valve/position")}));
  ASSERT_EQ(message.at("channels").size(), 1u);
  const json& channel = message.at("channels")[0];
  EXPECT_EQ(channel.at("topic"), "teejet/valve/position");
  EXPECT_EQ(channel.at("encoding"), "cdr");
  EXPECT_EQ(channel.at("schemaEncoding"), "omgidl");
  EXPECT_EQ(channel.at("schemaName"), "teejet::ValvePosition");
  EXPECT_EQ(channel.at("schema"), std::string(recording::valve_idl()));
}

TEST(FoxgloveProtocol, MessageDataIsOpcodeSubscriptionAndTimestampLittleEndianThenThePayload) {
  const std::vector<std::uint8_t> payload{0x00, 0x01, 0x00, 0x00, 0xAB};
  const std::string frame = message_data(0x01020304, 0x1122334455667788, payload);
  const std::string expected(
      "\x01\x04\x03\x02\x01\x88\x77\x66\x55\x44\x33\x22\x11\x00\x01\x00\x00\xAB", 18);
  EXPECT_EQ(frame, expected);
}

TEST(FoxgloveProtocol, ParsesSubscribeAndRefusesWhatIsMalformedWithAReason) {
  const auto subscribe =
      parse_client_text(R"({"op":"subscribe","subscriptions":[{"id":7,"channelId":5}]})");
  ASSERT_TRUE(subscribe) << subscribe.error().reason;
  const auto& entries = std::get<Subscribe>(*subscribe).subscriptions;
  ASSERT_EQ(entries.size(), 1u);
  EXPECT_EQ(entries[0].id, 7u);
  EXPECT_EQ(entries[0].channel, 5u);

  const auto reason = [](std::string_view text) {
    const auto parsed = parse_client_text(text);
    return parsed ? std::string("accepted") : parsed.error().reason;
  };
  EXPECT_EQ(reason("{"), "malformed JSON");
  EXPECT_EQ(reason("[1]"), "a message must be a JSON object with a string \"op\"");
  EXPECT_EQ(reason(R"({"op":"subscribe","subscriptions":[{"id":-1,"channelId":5}]})"),
            "subscribe: \"id\" must be an integer from 0 to 4294967295");
  EXPECT_EQ(reason(R"({"op":"subscribe","subscriptions":[{"id":1}]})"),
            "subscribe: missing \"channelId\"");
  EXPECT_EQ(reason(R"({"op":"unsubscribe","subscriptionIds":"all"})"),
            "unsubscribe: \"subscriptionIds\" must be an array");
  EXPECT_EQ(reason(R"({"op":"getParameters","parameterNames":[]})"),
            "op \"getParameters\" is not served: teejet-web serves subscribe, unsubscribe and, "
            "when it announces clientPublish, advertise and unadvertise");
  EXPECT_EQ(reason(R"({"op":"subscribe","subscriptions":[[[[[]]]]]})"),
            "JSON nested deeper than 4 levels");
  EXPECT_EQ(reason(std::string(kMaxClientMessageBytes + 1, ' ')),
            "message of 262145 bytes is over the limit of 262144");
}

TEST(FoxgloveProtocol, ParsesClientMessageDataAndRefusesOtherOpcodes) {
  const std::vector<std::uint8_t> frame{0x01, 0x02, 0x01, 0x00, 0x00, 0xAA, 0xBB};
  const auto data = parse_client_binary(frame);
  ASSERT_TRUE(data) << data.error().reason;
  EXPECT_EQ(data->channel, 0x0102u);
  EXPECT_EQ(std::vector<std::uint8_t>(data->payload.begin(), data->payload.end()),
            (std::vector<std::uint8_t>{0xAA, 0xBB}));
  const std::vector<std::uint8_t> service_call{0x02, 0x00};
  EXPECT_EQ(parse_client_binary(service_call).error().reason,
            "binary message with opcode 2: teejet-web takes only Client Message Data (1)");
  const std::vector<std::uint8_t> short_frame{0x01, 0x00};
  EXPECT_EQ(parse_client_binary(short_frame).error().reason,
            "Client Message Data of 2 bytes: shorter than its 5-byte header");
}

TEST(FoxgloveProtocol, ReadsTheTokenFromTheQueryDecoded) {
  EXPECT_EQ(query_parameter("/?token=abc%21", "token"), "abc!");
  EXPECT_EQ(query_parameter("/x?a=1&token=two+words&b", "token"), "two words");
  EXPECT_EQ(query_parameter("/?tokens=1&token", "token"), "");
  EXPECT_EQ(query_parameter("/?token=%zz", "token"), std::nullopt);
  EXPECT_EQ(query_parameter("/?token=%4", "token"), std::nullopt);
  EXPECT_EQ(query_parameter("/", "token"), std::nullopt);
}

TEST(FoxgloveOutbox, DropsAndCountsMessagesBeyondItsBoundButKeepsControlMessages) {
  Outbox outbox(100);
  EXPECT_TRUE(outbox.post_data(std::string(60, 'a')));
  EXPECT_TRUE(outbox.post_data(std::string(40, 'b')));
  EXPECT_FALSE(outbox.post_data(std::string(1, 'c')));
  EXPECT_EQ(outbox.dropped(), 1u);
  outbox.post_text("advertise");
  ASSERT_EQ(outbox.start_write(), (Outbox::Write{Outbox::Kind::kBinary, std::string(60, 'a')}));
  EXPECT_EQ(outbox.start_write(), std::nullopt);  // one write at a time
  outbox.write_done();
  // What was written makes room again.
  EXPECT_TRUE(outbox.post_data(std::string(50, 'd')));
  EXPECT_EQ(outbox.queued_data_bytes(), 90u);
  EXPECT_EQ(outbox.start_write()->bytes, std::string(40, 'b'));
  outbox.write_done();
  EXPECT_EQ(outbox.start_write(), (Outbox::Write{Outbox::Kind::kText, "advertise"}));
}

TEST(FoxgloveOutbox, HoldsABoundedNumberOfStatuses) {
  Outbox outbox;
  for (std::size_t i = 0; i < kMaxQueuedStatuses; ++i) EXPECT_TRUE(outbox.post_status("s"));
  EXPECT_FALSE(outbox.post_status("one too many"));
  // A status written makes room for one more.
  ASSERT_EQ(outbox.start_write(), (Outbox::Write{Outbox::Kind::kText, "s"}));
  outbox.write_done();
  EXPECT_TRUE(outbox.post_status("again"));
  EXPECT_FALSE(outbox.post_status("one too many"));
}

TEST(FoxgloveSession, KeepsSubscriptionsByChannelAndRefusesBadOnesWithAStatus) {
  Session session(std::nullopt);
  const std::uint32_t position = find_channel("teejet/valve/position")->id;
  auto reaction = session.on_text(R"({"op":"subscribe","subscriptions":[{"id":1,"channelId":)" +
                                  std::to_string(position) + R"(},{"id":2,"channelId":)" +
                                  std::to_string(position) +
                                  R"(},{"id":1,"channelId":1},{"id":3,"channelId":999}]})");
  ASSERT_EQ(reaction.subscribed.size(), 2u);
  ASSERT_EQ(reaction.statuses.size(), 2u);
  EXPECT_EQ(text_of(reaction.statuses[0]), "subscribe: subscription id 1 is in use");
  EXPECT_EQ(text_of(reaction.statuses[1]), "subscribe: no channel 999 is advertised");
  EXPECT_EQ(json::parse(reaction.statuses[1]).at("level"), 2);
  EXPECT_EQ(std::vector<std::uint32_t>(session.subscriptions(position).begin(),
                                       session.subscriptions(position).end()),
            (std::vector<std::uint32_t>{1, 2}));
  reaction = session.on_text(R"({"op":"unsubscribe","subscriptionIds":[1,8]})");
  ASSERT_EQ(reaction.statuses.size(), 1u);
  EXPECT_EQ(text_of(reaction.statuses[0]), "unsubscribe: no subscription 8");
  EXPECT_EQ(session.subscriptions(position).size(), 1u);
}

TEST(FoxgloveSession, AClientMayPublishCommandsInCdrOnly) {
  Session read_only(std::string("commands are disabled"));
  auto reaction = read_only.on_text(
      R"({"op":"advertise","channels":[{"id":1,"topic":"teejet/valve/command","encoding":"cdr","schemaName":"teejet::ValveCommand"}]})");
  ASSERT_EQ(reaction.statuses.size(), 1u);
  EXPECT_EQ(text_of(reaction.statuses[0]), "advertise refused: commands are disabled");

  Session session(std::nullopt);
  reaction = session.on_text(
      R"({"op":"advertise","channels":[
        {"id":1,"topic":"teejet/valve/command","encoding":"cdr","schemaName":"teejet::ValveCommand"},
        {"id":2,"topic":"teejet/valve/presence","encoding":"cdr","schemaName":"teejet::ValvePresence"},
        {"id":3,"topic":"teejet/valve/command","encoding":"json","schemaName":"teejet::ValveCommand"},
        {"id":4,"topic":"teejet/valve/command","encoding":"cdr","schemaName":"teejet::ValvePresence"}]})");
  ASSERT_EQ(reaction.statuses.size(), 3u);
  EXPECT_EQ(text_of(reaction.statuses[0]),
            "advertise of channel 2 (teejet/valve/presence) refused: only teejet/valve/command "
            "takes messages from clients");
  EXPECT_EQ(text_of(reaction.statuses[1]),
            "advertise of channel 3 (teejet/valve/command) refused: encoding \"json\": only "
            "\"cdr\"");
  EXPECT_EQ(text_of(reaction.statuses[2]),
            "advertise of channel 4 (teejet/valve/command) refused: schema "
            "\"teejet::ValvePresence\": only \"teejet::ValveCommand\"");

  const std::vector<std::uint8_t> on_refused{0x01, 0x02, 0x00, 0x00, 0x00, 0xAA};
  const auto refused = session.on_binary(on_refused);
  ASSERT_TRUE(std::holds_alternative<std::string>(refused));
  EXPECT_EQ(text_of(std::get<std::string>(refused)),
            "message on client channel 2, which this connection has not advertised: not sent");
  const std::vector<std::uint8_t> on_accepted{0x01, 0x01, 0x00, 0x00, 0x00, 0xAA};
  const auto accepted = session.on_binary(on_accepted);
  ASSERT_TRUE(std::holds_alternative<Publish>(accepted));
  EXPECT_EQ(std::get<Publish>(accepted).payload, std::vector<std::uint8_t>{0xAA});
}

TEST(FoxglovePublish, APublishedCommandPassesThePagesRulesBeforeItIsSent) {
  const client::ValveTable table = testing::three_valves();
  const CommandPolicy policy{true, "secret"};
  RecordingSender sender;
  const auto answer = [&](const std::vector<std::uint8_t>& payload,
                          std::optional<std::string_view> token) {
    return answer_publish({{1, "teejet/valve/command", "cdr", "teejet::ValveCommand"}, payload},
                          table, policy, token, sender, {});
  };
  EXPECT_EQ(answer(cdr(move(2, 90)), std::nullopt).message,
            "command not sent: missing or wrong \"token\"");
  EXPECT_EQ(answer(cdr(move(2, 90)), "guess").message,
            "command not sent: missing or wrong \"token\"");
  EXPECT_EQ(answer({0x00, 0x01, 0x00, 0x00, 0x01}, "secret")
                .message.rfind("command not sent: not a teejet::ValveCommand in CDR (", 0),
            0u);
  EXPECT_EQ(answer(cdr(move(2, 400)), "secret").message,
            "command not sent: target_degrees: degrees 400 is outside 0 to 359.9");
  EXPECT_EQ(answer(cdr(move(9, 90)), "secret").message,
            "command not sent: unknown serial TJV000009: no gateway knows it");
  EXPECT_TRUE(sender.sent.empty());

  const PublishAnswer sent = answer(cdr(move(2, 90)), "secret");
  EXPECT_EQ(sent.level, Level::kInfo);
  EXPECT_EQ(sent.message,
            "command #100 sent to TJV000002: its statuses follow on teejet/valve/command_status");
  ASSERT_EQ(sender.sent.size(), 1u);
  EXPECT_EQ(sender.sent[0].serial(), 2u);
  EXPECT_EQ(sender.sent[0].kind(), COMMAND_TARGET_DEGREES);
  EXPECT_FLOAT_EQ(sender.sent[0].degrees(), 90.0f);
  EXPECT_EQ(sender.sent[0].speed_percent(), 100);
}

}  // namespace
}  // namespace teejet::web::foxglove
