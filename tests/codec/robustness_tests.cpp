// The decoder never crashes and never invents data: every payload either fails with a typed
// error or decodes into a message that encodes back to the same bytes.

#include <gtest/gtest.h>

#include <random>

#include "teejet/codec/codec.hpp"

namespace teejet::codec {
namespace {

template <class Decoded>
void expect_reencodes(const Decoded& message, const CanFrame& original, std::uint8_t valve) {
  auto again = encode(valve, message, EncodeOptions{.pad_to_eight = false});
  if (!again) {
    // Only telemetry outside the sheet's ranges decodes but does not encode.
    EXPECT_EQ(again.error().code, ErrorCode::kOutOfRange) << again.error().reason;
    return;
  }
  ASSERT_LE(again->dlc, original.dlc);
  for (std::size_t i = 0; i < again->dlc; ++i) {
    ASSERT_EQ(again->data[i], original.data[i]) << "byte " << i;
  }
}

TEST(Robustness, RandomFramesOfEveryLengthAndIdByte) {
  std::mt19937 random(20261121);  // fixed seed: a failure reproduces
  std::uniform_int_distribution<int> byte(0, 255);
  int decoded_count = 0;
  for (int id_byte = 0; id_byte < 256; ++id_byte) {
    for (std::uint8_t dlc = 0; dlc <= 8; ++dlc) {
      for (int round = 0; round < 40; ++round) {
        CanFrame frame{.id = round % 2 ? 0x18EFD5D9u : 0x18EFD9D5u, .dlc = dlc};
        for (auto& b : frame.data) b = static_cast<std::uint8_t>(byte(random));
        if (dlc > 0) frame.data[0] = static_cast<std::uint8_t>(id_byte);
        auto decoded = decode(frame);
        if (!decoded) {
          EXPECT_FALSE(decoded.error().reason.empty());
          continue;
        }
        ++decoded_count;
        std::visit([&](const auto& m) { expect_reencodes(m, frame, 0xD9); }, decoded->message);
      }
    }
  }
  EXPECT_GT(decoded_count, 1000);  // the loop must exercise real decodes, not only rejections
}

TEST(Robustness, EveryTwoBytePositionPayloadRoundTrips) {
  for (int raw = 0; raw <= 0xFFFF; ++raw) {
    CanFrame frame{.id = 0x18EFD5E1, .dlc = 3};
    frame.data[0] = 0x02;
    frame.data[1] = static_cast<std::uint8_t>(raw >> 8);
    frame.data[2] = static_cast<std::uint8_t>(raw);
    auto decoded = decode(frame);
    ASSERT_TRUE(decoded);
    const auto& position = std::get<Position>(std::get<1>(decoded->message));
    ASSERT_DOUBLE_EQ(position.degrees, raw / 10.0);
    if (raw <= 3599) expect_reencodes(std::get<1>(decoded->message), frame, 0xE1);
  }
}

}  // namespace
}  // namespace teejet::codec
