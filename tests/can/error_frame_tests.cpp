// SocketCAN error frames decoded into controller state. Frames are built by hand with the bit
// values of linux/can/error.h written out; the static_asserts pin them to the header.
#include <gtest/gtest.h>
#include <linux/can.h>
#include <linux/can/error.h>

#include "error_frame.hpp"

namespace teejet::can {
namespace {

static_assert(CAN_ERR_FLAG == 0x20000000U);
static_assert(CAN_ERR_MASK == 0x1FFFFFFFU);
static_assert(CAN_ERR_CRTL == 0x04U);
static_assert(CAN_ERR_BUSOFF == 0x40U);
static_assert(CAN_ERR_RESTARTED == 0x100U);
static_assert(CAN_ERR_CNT == 0x200U);
static_assert(CAN_ERR_PROT == 0x08U);
static_assert(CAN_ERR_CRTL_RX_OVERFLOW == 0x01);
static_assert(CAN_ERR_CRTL_RX_WARNING == 0x04);
static_assert(CAN_ERR_CRTL_TX_WARNING == 0x08);
static_assert(CAN_ERR_CRTL_RX_PASSIVE == 0x10);
static_assert(CAN_ERR_CRTL_TX_PASSIVE == 0x20);
static_assert(CAN_ERR_CRTL_ACTIVE == 0x40);

using Data = std::array<std::uint8_t, 8>;

TEST(ErrorFrameTest, RecognisesTheErrorFlagOnly) {
  EXPECT_TRUE(is_error_frame(0x20000040));
  EXPECT_FALSE(is_error_frame(0x98EFD5D8));  // CAN_EFF_FLAG | 0x18EFD5D8: a data frame
  EXPECT_FALSE(is_error_frame(0x000000D5));
}

TEST(ErrorFrameTest, TxWarningWithCounters) {
  // CAN_ERR_FLAG | CAN_ERR_CRTL | CAN_ERR_CNT, data[1] = CAN_ERR_CRTL_TX_WARNING, TEC 96, REC 3
  const auto report = decode_error_frame(0x20000204, Data{0, 0x08, 0, 0, 0, 0, 96, 3});
  EXPECT_EQ(report.error_classes, 0x204u);
  EXPECT_EQ(report.state, BusState::kErrorWarning);
  EXPECT_EQ(report.controller_problems, 0x08u);
  EXPECT_EQ(report.tx_errors, 96);
  EXPECT_EQ(report.rx_errors, 3);
}

TEST(ErrorFrameTest, RxWarningIsAWarningToo) {
  const auto report = decode_error_frame(0x20000004, Data{0, 0x04, 0, 0, 0, 0, 0, 0});
  EXPECT_EQ(report.state, BusState::kErrorWarning);
  EXPECT_FALSE(report.tx_errors);  // no CAN_ERR_CNT: counters unknown
  EXPECT_FALSE(report.rx_errors);
}

TEST(ErrorFrameTest, PassiveWinsOverWarning) {
  // data[1] = CAN_ERR_CRTL_TX_PASSIVE | CAN_ERR_CRTL_RX_WARNING
  const auto report = decode_error_frame(0x20000204, Data{0, 0x24, 0, 0, 0, 0, 130, 100});
  EXPECT_EQ(report.state, BusState::kErrorPassive);
  EXPECT_EQ(report.controller_problems, 0x24u);
  EXPECT_EQ(report.tx_errors, 130);
  EXPECT_EQ(report.rx_errors, 100);
}

TEST(ErrorFrameTest, RxPassive) {
  const auto report = decode_error_frame(0x20000004, Data{0, 0x10, 0, 0, 0, 0, 0, 0});
  EXPECT_EQ(report.state, BusState::kErrorPassive);
}

TEST(ErrorFrameTest, BusOff) {
  const auto report = decode_error_frame(0x20000040, Data{});
  EXPECT_EQ(report.error_classes, 0x40u);
  EXPECT_EQ(report.state, BusState::kBusOff);
  EXPECT_FALSE(report.controller_problems);
}

TEST(ErrorFrameTest, BusOffWinsOverControllerBitsInTheSameFrame) {
  const auto report = decode_error_frame(0x20000044, Data{0, 0x20, 0, 0, 0, 0, 0, 0});
  EXPECT_EQ(report.state, BusState::kBusOff);
  EXPECT_EQ(report.controller_problems, 0x20u);
}

TEST(ErrorFrameTest, RestartedMeansErrorActiveWithClearedCounters) {
  const auto report = decode_error_frame(0x20000100, Data{});
  EXPECT_EQ(report.state, BusState::kErrorActive);
  EXPECT_EQ(report.controller_problems, 0u);
  EXPECT_EQ(report.tx_errors, 0);
  EXPECT_EQ(report.rx_errors, 0);
}

TEST(ErrorFrameTest, RestartedWithCountersKeepsTheCounters) {
  const auto report = decode_error_frame(0x20000300, Data{0, 0, 0, 0, 0, 0, 5, 6});
  EXPECT_EQ(report.state, BusState::kErrorActive);
  EXPECT_EQ(report.tx_errors, 5);
  EXPECT_EQ(report.rx_errors, 6);
}

TEST(ErrorFrameTest, BackToErrorActiveIsNotAProblem) {
  // data[1] = CAN_ERR_CRTL_ACTIVE: recovered, so no problem bits remain
  const auto report = decode_error_frame(0x20000204, Data{0, 0x40, 0, 0, 0, 0, 12, 0});
  EXPECT_EQ(report.state, BusState::kErrorActive);
  EXPECT_EQ(report.controller_problems, 0u);
  EXPECT_EQ(report.tx_errors, 12);
}

TEST(ErrorFrameTest, OverflowIsAProblemWithoutAStateChange) {
  const auto report = decode_error_frame(0x20000004, Data{0, 0x01, 0, 0, 0, 0, 0, 0});
  EXPECT_FALSE(report.state);
  EXPECT_EQ(report.controller_problems, 0x01u);
}

TEST(ErrorFrameTest, ProtocolAndAckErrorsCarryNoState) {
  // CAN_ERR_PROT | CAN_ERR_ACK with a bit error (data[2] = CAN_ERR_PROT_BIT): a bus error only
  const auto report = decode_error_frame(0x20000028, Data{0, 0, 0x01, 0x19, 0, 0, 0, 0});
  EXPECT_EQ(report.error_classes, 0x28u);
  EXPECT_FALSE(report.state);
  EXPECT_FALSE(report.controller_problems);
  EXPECT_FALSE(report.tx_errors);
}

TEST(ErrorFrameTest, ApplyFoldsReportsAndSaysWhenTheStateChanged) {
  ControllerStatus status;
  EXPECT_TRUE(apply(decode_error_frame(0x20000204, Data{0, 0x08, 0, 0, 0, 0, 100, 0}), status));
  EXPECT_EQ(status.state, BusState::kErrorWarning);
  EXPECT_EQ(status.tx_errors, 100);
  // the same state again with other counters: not a change, counters follow
  EXPECT_FALSE(apply(decode_error_frame(0x20000204, Data{0, 0x08, 0, 0, 0, 0, 110, 1}), status));
  EXPECT_EQ(status.tx_errors, 110);
  EXPECT_EQ(status.rx_errors, 1);
  // a bus error without state keeps everything but counts the frame
  EXPECT_FALSE(apply(decode_error_frame(0x20000080, Data{}), status));
  EXPECT_EQ(status.state, BusState::kErrorWarning);
  EXPECT_EQ(status.controller_problems, 0x08u);
  EXPECT_TRUE(apply(decode_error_frame(0x20000040, Data{}), status));
  EXPECT_EQ(status.state, BusState::kBusOff);
  EXPECT_TRUE(apply(decode_error_frame(0x20000100, Data{}), status));
  EXPECT_EQ(status.state, BusState::kErrorActive);
  EXPECT_EQ(status.tx_errors, 0);
  EXPECT_EQ(status.rx_errors, 0);
  EXPECT_EQ(status.controller_problems, 0u);
  EXPECT_EQ(status.error_frames, 5u);
}

}  // namespace
}  // namespace teejet::can
