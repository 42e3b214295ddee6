// Conversions between our frames and the kernel's structures, with the kernel's bit values
// written out; the static_asserts pin them to linux/can.h.
#include <gtest/gtest.h>

#include <array>
#include <vector>

#include "kernel_frame.hpp"

namespace teejet::can {
namespace {

static_assert(CAN_EFF_FLAG == 0x80000000U);
static_assert(CAN_RTR_FLAG == 0x40000000U);
static_assert(CAN_EFF_MASK == 0x1FFFFFFFU);
static_assert(CAN_SFF_MASK == 0x000007FFU);

using Bytes = std::array<std::uint8_t, 8>;

Bytes data_of(const can_frame& frame) {
  Bytes out{};
  std::copy_n(frame.data, out.size(), out.begin());
  return out;
}

can_frame kernel(canid_t can_id, std::uint8_t len, Bytes data = {}) {
  can_frame out{};
  out.can_id = can_id;
  out.len = len;
  std::copy(data.begin(), data.end(), out.data);
  return out;
}

// The kernel's CAN_RAW filter rule (net/can/af_can.c): a frame passes when its can_id, flags
// included, matches the filter's id under the filter's mask.
bool kernel_accepts(const can_filter& filter, canid_t can_id) {
  return (can_id & filter.can_mask) == (filter.can_id & filter.can_mask);
}

// ---- to the kernel -------------------------------------------------------------------------

TEST(KernelFrameTest, ExtendedIdGetsTheEffFlag) {
  const can_frame out = to_kernel({.id = 0x18EFD8D5, .dlc = 3, .data = {0x02, 0x03, 0x84}});
  EXPECT_EQ(out.can_id, 0x98EFD8D5u);
  EXPECT_EQ(out.len, 3);
  EXPECT_EQ(data_of(out), (Bytes{0x02, 0x03, 0x84, 0, 0, 0, 0, 0}));
}

TEST(KernelFrameTest, LargestExtendedId) {
  EXPECT_EQ(to_kernel({.id = 0x1FFFFFFF, .dlc = 0}).can_id, 0x9FFFFFFFu);
  EXPECT_EQ(to_kernel({.id = 0x00000000, .dlc = 0}).can_id, 0x80000000u);
}

TEST(KernelFrameTest, StandardIdHasNoFlags) {
  const can_frame out = to_kernel({.id = 0x0D5, .extended = false, .dlc = 1, .data = {0x11}});
  EXPECT_EQ(out.can_id, 0x0D5u);
  EXPECT_EQ(out.len, 1);
  EXPECT_EQ(data_of(out), (Bytes{0x11, 0, 0, 0, 0, 0, 0, 0}));
  EXPECT_EQ(to_kernel({.id = 0x7FF, .extended = false}).can_id, 0x7FFu);
}

TEST(KernelFrameTest, RemoteRequestGetsTheRtrFlag) {
  EXPECT_EQ(to_kernel({.id = 0x18EFD5D9, .remote = true}).can_id, 0xD8EFD5D9u);
  EXPECT_EQ(to_kernel({.id = 0x123, .extended = false, .remote = true}).can_id, 0x40000123u);
}

TEST(KernelFrameTest, IdsAreMaskedToTheirWidth) {
  // send() refuses such frames first; the conversion still never sets a flag by accident.
  EXPECT_EQ(to_kernel({.id = 0xFFFFFFFF}).can_id, 0x9FFFFFFFu);
  EXPECT_EQ(to_kernel({.id = 0x0FFF, .extended = false}).can_id, 0x7FFu);
}

TEST(KernelFrameTest, EightBytesAndALargerDlcClampedToEight) {
  const codec::CanFrame full{.id = 1, .dlc = 8, .data = {1, 2, 3, 4, 5, 6, 7, 8}};
  EXPECT_EQ(to_kernel(full).len, 8);
  EXPECT_EQ(data_of(to_kernel(full)), (Bytes{1, 2, 3, 4, 5, 6, 7, 8}));
  codec::CanFrame too_long = full;
  too_long.dlc = 9;
  EXPECT_EQ(to_kernel(too_long).len, 8);
  EXPECT_EQ(data_of(to_kernel(too_long)), (Bytes{1, 2, 3, 4, 5, 6, 7, 8}));
}

TEST(KernelFrameTest, ClassicFrameLimits) {
  EXPECT_TRUE(is_classic_frame({.id = 0x1FFFFFFF, .dlc = 8}));
  EXPECT_FALSE(is_classic_frame({.id = 0x20000000, .dlc = 8}));
  EXPECT_FALSE(is_classic_frame({.id = 0x18EFD8D5, .dlc = 9}));
  EXPECT_TRUE(is_classic_frame({.id = 0x7FF, .extended = false}));
  EXPECT_FALSE(is_classic_frame({.id = 0x800, .extended = false}));
}

// ---- from the kernel -----------------------------------------------------------------------

TEST(KernelFrameTest, ExtendedFrameFromTheKernel) {
  const codec::CanFrame out = from_kernel(kernel(0x98EFD5D8, 3, {0x02, 0x01, 0xC2, 0xFF}));
  EXPECT_EQ(out, (codec::CanFrame{.id = 0x18EFD5D8, .dlc = 3, .data = {0x02, 0x01, 0xC2}}));
}

TEST(KernelFrameTest, StandardFrameFromTheKernel) {
  EXPECT_EQ(from_kernel(kernel(0x0D5, 2, {0x02, 0x03})),
            (codec::CanFrame{.id = 0x0D5, .extended = false, .dlc = 2, .data = {0x02, 0x03}}));
  // Bits above the 11 of a standard id are not part of it.
  EXPECT_EQ(from_kernel(kernel(0x0000FFFF, 0)).id, 0x7FFu);
}

TEST(KernelFrameTest, RemoteFramesFromTheKernel) {
  EXPECT_EQ(from_kernel(kernel(0xD8EFD5D9, 0)),
            (codec::CanFrame{.id = 0x18EFD5D9, .remote = true}));
  EXPECT_EQ(from_kernel(kernel(0x40000123, 0)),
            (codec::CanFrame{.id = 0x123, .extended = false, .remote = true}));
}

TEST(KernelFrameTest, LengthAboveEightIsClampedToEight) {
  const codec::CanFrame out = from_kernel(kernel(0x98EFD5D8, 15, {1, 2, 3, 4, 5, 6, 7, 8}));
  EXPECT_EQ(out.dlc, 8);
  EXPECT_EQ(out.data, (Bytes{1, 2, 3, 4, 5, 6, 7, 8}));
}

TEST(KernelFrameTest, RoundTrip) {
  for (const codec::CanFrame& frame :
       std::vector<codec::CanFrame>{{.id = 0x18EFD8D5, .dlc = 8, .data = {9, 8, 7, 6, 5, 4, 3, 2}},
                                    {.id = 0x1FFFFFFF, .dlc = 0},
                                    {.id = 0x7FF, .extended = false, .dlc = 1, .data = {0xAA}},
                                    {.id = 0x18EFD5D9, .remote = true},
                                    {.id = 0x001, .extended = false, .remote = true}}) {
    EXPECT_EQ(from_kernel(to_kernel(frame)), frame) << std::hex << frame.id;
  }
}

// ---- filters -------------------------------------------------------------------------------

TEST(KernelFrameTest, FilterKeepsExtendedDataFramesOnly) {
  // The gateway's filter, 0x18EFD5xx.
  const can_filter out = kernel_filter({0x18EFD500, 0xFFFFFF00});
  EXPECT_EQ(out.can_id, 0x98EFD500u);
  EXPECT_EQ(out.can_mask, 0xDFFFFF00u);           // CAN_EFF_FLAG | CAN_RTR_FLAG | 0x1FFFFF00
  EXPECT_TRUE(kernel_accepts(out, 0x98EFD5D8));   // valve 0xD8 to the controller
  EXPECT_TRUE(kernel_accepts(out, 0x98EFD5F7));   // valve 0xF7
  EXPECT_FALSE(kernel_accepts(out, 0x98EFD8D5));  // the other direction
  EXPECT_FALSE(kernel_accepts(out, 0xD8EFD5D8));  // RTR with a matching id
  EXPECT_FALSE(kernel_accepts(out, 0x000000D5));  // 11-bit
  EXPECT_FALSE(kernel_accepts(out, 0x18EFD5D8));  // the same bits without CAN_EFF_FLAG
}

TEST(KernelFrameTest, ValveSideFilter) {
  const can_filter out = kernel_filter({0x18EF00D5, 0xFFFF00FF});
  EXPECT_EQ(out.can_id, 0x98EF00D5u);
  EXPECT_EQ(out.can_mask, 0xDFFF00FFu);
  EXPECT_TRUE(kernel_accepts(out, 0x98EFD8D5));
  EXPECT_FALSE(kernel_accepts(out, 0x98EFD8D4));  // from another source
}

TEST(KernelFrameTest, FlagBitsInOurIdAndMaskAreIgnored) {
  const can_filter out = kernel_filter({0xF8EFD500, 0xFFFFFFFF});
  EXPECT_EQ(out.can_id, 0x98EFD500u);
  EXPECT_EQ(out.can_mask, 0xDFFFFFFFu);
}

TEST(KernelFrameTest, NoFiltersMeansEveryExtendedDataFrame) {
  const std::vector<can_filter> out = kernel_filters({});
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].can_id, 0x80000000u);
  EXPECT_EQ(out[0].can_mask, 0xC0000000u);
  EXPECT_TRUE(kernel_accepts(out[0], 0x98FEF100));
  EXPECT_TRUE(kernel_accepts(out[0], 0x80000001));
  EXPECT_FALSE(kernel_accepts(out[0], 0x00000123));  // 11-bit
  EXPECT_FALSE(kernel_accepts(out[0], 0xD8FEF100));  // RTR
}

TEST(KernelFrameTest, OneKernelFilterPerFilterInOrder) {
  const std::vector<can_filter> out =
      kernel_filters({{0x18EFD500, 0xFFFFFF00}, {0x18EF00D5, 0xFFFF00FF}});
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[0].can_id, 0x98EFD500u);
  EXPECT_EQ(out[0].can_mask, 0xDFFFFF00u);
  EXPECT_EQ(out[1].can_id, 0x98EF00D5u);
  EXPECT_EQ(out[1].can_mask, 0xDFFF00FFu);
}

// ---- stamps and the drop counter -------------------------------------------------------------

TEST(KernelFrameTest, KernelStampIsNanosecondsSinceTheEpoch) {
  EXPECT_EQ(to_timestamp({1'700'000'000, 123'456'789}),
            Timestamp{Duration{1'700'000'000'123'456'789}});
  EXPECT_EQ(to_timestamp({0, 0}), Timestamp{});
}

TEST(KernelFrameTest, DropsSinceCountsForward) {
  EXPECT_EQ(drops_since(0, 0), 0u);
  EXPECT_EQ(drops_since(5, 12), 7u);
  EXPECT_EQ(drops_since(0, 1997), 1997u);
  EXPECT_EQ(drops_since(0, 0x7FFFFFFF), 0x7FFFFFFFu);
}

TEST(KernelFrameTest, DropsSinceAcrossTheWrapAround) {
  EXPECT_EQ(drops_since(0xFFFFFFF0, 0x00000010), 0x20u);
  EXPECT_EQ(drops_since(0xFFFFFFFF, 0x00000000), 1u);
  EXPECT_EQ(drops_since(0xFFFFFF00, 0x000000FF), 0x1FFu);
}

TEST(KernelFrameTest, OlderReadingsAddNothing) {
  EXPECT_EQ(drops_since(12, 5), 0u);
  EXPECT_EQ(drops_since(0x00000010, 0xFFFFFFF0), 0u);  // an older reading across the wrap
  EXPECT_EQ(drops_since(0, 0x80000000), 0u);           // half the range away: taken as older
}

TEST(KernelFrameTest, DropCountTotalsAcrossReadingsWrapsAndSockets) {
  DropCount drops;
  drops.note(1722);
  EXPECT_EQ(drops.total, 1722u);
  drops.note(1700);  // an older cmsg value after SO_MEMINFO
  EXPECT_EQ(drops.total, 1722u);
  EXPECT_EQ(drops.socket_counter, 1722u);

  // Past 2^32 the socket's counter wraps, the total does not.
  for (std::uint32_t reading : {0x70000000U, 0xE0000000U, 0xFFFFFFF0U, 0x00000010U}) {
    drops.note(reading);
  }
  EXPECT_EQ(drops.socket_counter, 0x10u);
  EXPECT_EQ(drops.total, 0x100000010u);

  drops.new_socket();  // its counter starts at 0
  drops.note(3);
  EXPECT_EQ(drops.socket_counter, 3u);
  EXPECT_EQ(drops.total, 0x100000013u);
}

}  // namespace
}  // namespace teejet::can
