// Which reply answers which request and which commands are run commands: facts of the sheet
// that the message table holds, so that the gateway never writes them again.

#include <gtest/gtest.h>

#include "teejet/codec/codec.hpp"

namespace teejet::codec {
namespace {

TEST(MessageRoles, EachRequestIsAnsweredByItsMessage) {
  EXPECT_EQ(reply_id(RequestVersion{}), 0x01);  // Version Information
  EXPECT_EQ(reply_id(RequestPosition{}), 0x02);
  EXPECT_EQ(reply_id(RequestTemperature{}), 0x03);
  EXPECT_EQ(reply_id(RequestVoltage{}), 0x04);
  EXPECT_EQ(reply_id(RequestCurrent{}), 0x05);  // Run Current
  EXPECT_EQ(reply_id(RequestDegreesPerSecond{}), 0x06);
  EXPECT_EQ(reply_id(RequestSpeedDirection{}), 0x07);
  EXPECT_EQ(reply_id(RequestRunTime{}), 0x08);
  EXPECT_EQ(reply_id(RequestCycleCounts{}), 0x09);
  EXPECT_EQ(reply_id(BaudRate{BaudAction::kSet, kBitRate500k}), 0x93);  // CAN Baud Rate Reply
  EXPECT_EQ(reply_id(BaudRate{BaudAction::kRequest, kBitRate250k}), 0x93);
}

TEST(MessageRoles, TheReplyIdNamesAValveToControllerMessageOfTheRightKind) {
  EXPECT_EQ(message_id(FromValveMessage{Position{}}), *reply_id(RequestPosition{}));
  EXPECT_EQ(message_id(FromValveMessage{RunCurrent{}}), *reply_id(RequestCurrent{}));
  EXPECT_EQ(message_id(FromValveMessage{BaudRateReply{}}), *reply_id(BaudRate{}));
}

TEST(MessageRoles, RunCommandsAreTheSixThatMoveOrStopTheValve) {
  for (const ToValveMessage& run :
       {ToValveMessage{Stop{}}, ToValveMessage{Manual{}}, ToValveMessage{TargetDegrees{}},
        ToValveMessage{DegreesFromPosition{}}, ToValveMessage{ClearErrors{}},
        ToValveMessage{MillisecondsToRun{}}}) {
    EXPECT_TRUE(is_run_command(run)) << message_name(run);
    EXPECT_FALSE(reply_id(run)) << message_name(run);
  }
  for (const ToValveMessage& request :
       {ToValveMessage{RequestVersion{}}, ToValveMessage{RequestPosition{1}},
        ToValveMessage{RequestCycleCounts{50}}, ToValveMessage{BaudRate{}}}) {
    EXPECT_FALSE(is_run_command(request)) << message_name(request);
    EXPECT_TRUE(reply_id(request)) << message_name(request);
  }
}

}  // namespace
}  // namespace teejet::codec
