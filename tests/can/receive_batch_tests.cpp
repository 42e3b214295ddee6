// The control messages of a received frame, built by hand as the kernel lays them out.
#include <gtest/gtest.h>
#include <linux/can/raw.h>
#include <linux/errqueue.h>

#include <array>
#include <cstring>

#include "receive_batch.hpp"

namespace teejet::can {
namespace {

class Control {
 public:
  template <class T>
  Control& add(int level, int type, const T& value) {
    auto* header = reinterpret_cast<cmsghdr*>(buffer_.data() + used_);
    header->cmsg_level = level;
    header->cmsg_type = type;
    header->cmsg_len = CMSG_LEN(sizeof value);
    std::memcpy(CMSG_DATA(header), &value, sizeof value);
    used_ += CMSG_SPACE(sizeof value);
    return *this;
  }

  ReceiveControl read() {
    msghdr header{};
    header.msg_control = used_ ? buffer_.data() : nullptr;
    header.msg_controllen = used_;
    return read_control(header);
  }

 private:
  alignas(cmsghdr) std::array<unsigned char, 256> buffer_{};
  std::size_t used_ = 0;
};

scm_timestamping stamps(timespec software, timespec hardware = {}) {
  scm_timestamping out{};
  out.ts[0] = software;
  out.ts[2] = hardware;
  return out;
}

TEST(ReceiveControlTest, NoControlMessagesNoStampNoCounter) {
  const ReceiveControl out = Control().read();
  EXPECT_FALSE(out.stamp);
  EXPECT_FALSE(out.drop_counter);
}

TEST(ReceiveControlTest, SoftwareStampOfTimestamping) {
  const ReceiveControl out =
      Control().add(SOL_SOCKET, SCM_TIMESTAMPING, stamps({1'700'000'000, 5}, {9, 9})).read();
  EXPECT_EQ(out.stamp, Timestamp{Duration{1'700'000'000'000'000'005}});
  EXPECT_FALSE(out.drop_counter);
}

TEST(ReceiveControlTest, ZeroSoftwareStampIsNone) {
  // Only a hardware stamp (ts[2]): not the clock receive() promises.
  const ReceiveControl out =
      Control().add(SOL_SOCKET, SCM_TIMESTAMPING, stamps({0, 0}, {1'700'000'000, 1})).read();
  EXPECT_FALSE(out.stamp);
}

TEST(ReceiveControlTest, TimestampNsWhenTimestampingIsMissing) {
  const ReceiveControl out =
      Control().add(SOL_SOCKET, SCM_TIMESTAMPNS, timespec{1'700'000'001, 999'999'999}).read();
  EXPECT_EQ(out.stamp, Timestamp{Duration{1'700'000'001'999'999'999}});
}

TEST(ReceiveControlTest, DropCounterBesideTheStamp) {
  const ReceiveControl out = Control()
                                 .add(SOL_SOCKET, SCM_TIMESTAMPING, stamps({1'700'000'000, 0}))
                                 .add(SOL_SOCKET, SO_RXQ_OVFL, std::uint32_t{1997})
                                 .read();
  EXPECT_EQ(out.stamp, Timestamp{Duration{1'700'000'000'000'000'000}});
  EXPECT_EQ(out.drop_counter, 1997u);
}

TEST(ReceiveControlTest, OtherLevelsAreIgnored) {
  const ReceiveControl out = Control()
                                 .add(SOL_CAN_RAW, SO_RXQ_OVFL, std::uint32_t{7})
                                 .add(SOL_CAN_RAW, SCM_TIMESTAMPNS, timespec{1, 2})
                                 .read();
  EXPECT_FALSE(out.stamp);
  EXPECT_FALSE(out.drop_counter);
}

}  // namespace
}  // namespace teejet::can
