// BusFrame samples <-> CAN frames, candump lines and serialized payloads: pure conversions.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "teejet/bus_frame/bus_frame.hpp"

namespace {

namespace bus_frame = teejet::bus_frame;
using Bytes = std::vector<std::uint8_t>;

// The sheet's I Am Here from valve 0xD8 with serial 123 (as in tools/demo-data's sample log).
teejet::BusFrame i_am_here() {
  teejet::BusFrame sample;
  sample.gateway("gw-1");
  sample.can_interface("can0");
  sample.id(0x18EFD5D8);
  sample.extended(true);
  sample.dlc(8);
  sample.data({0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x7B, 0x00});
  sample.direction(teejet::FRAME_RECEIVED);
  sample.stamp_ns(1'700'000'000'000'123'456ULL);
  return sample;
}

// A remote frame asking 0x123 for four bytes: a dlc and no data.
teejet::BusFrame remote_request() {
  auto sample = i_am_here();
  sample.id(0x123);
  sample.extended(false);
  sample.remote(true);
  sample.dlc(4);
  sample.data({});
  return sample;
}

TEST(BusFrameStamp, DropsTheSubMicrosecondPartInsteadOfRounding) {
  EXPECT_EQ(bus_frame::split_stamp(0), (bus_frame::Timestamp{0, 0}));
  EXPECT_EQ(bus_frame::split_stamp(1'700'000'000'000'123'456ULL),
            (bus_frame::Timestamp{1'700'000'000, 123}));
  EXPECT_EQ(bus_frame::split_stamp(1'700'000'000'999'999'999ULL),
            (bus_frame::Timestamp{1'700'000'000, 999'999}));
  EXPECT_EQ(bus_frame::split_stamp(1'700'000'001'000'000'000ULL),
            (bus_frame::Timestamp{1'700'000'001, 0}));
}

TEST(BusFrameCandump, IAmHereIsTheLineCandumpWrites) {
  const auto line = bus_frame::to_candump_line(i_am_here());
  ASSERT_TRUE(line.ok()) << line.error().reason;
  EXPECT_EQ(*line, "(1700000000.000123) can0 18EFD5D8#0000000000007B00");
}

TEST(BusFrameCandump, StandardIdentifiersAndShortFrames) {
  auto sample = i_am_here();
  sample.id(0x123);
  sample.extended(false);
  sample.dlc(2);
  sample.data({0xAB, 0x01});
  sample.stamp_ns(7'000);
  const auto line = bus_frame::to_candump_line(sample);
  ASSERT_TRUE(line.ok()) << line.error().reason;
  EXPECT_EQ(*line, "(0000000000.000007) can0 123#AB01");
  sample.dlc(0);
  sample.data({});
  EXPECT_EQ(*bus_frame::to_candump_line(sample), "(0000000000.000007) can0 123#");
}

TEST(BusFrameCandump, ARemoteFrameIsRAndItsLength) {
  EXPECT_EQ(*bus_frame::to_candump_line(remote_request()), "(1700000000.000123) can0 123#R4");
  const auto record = bus_frame::to_log_record(remote_request());
  ASSERT_TRUE(record.ok()) << record.error().reason;
  const auto parsed = teejet::candump::parse_log_line("(1700000000.000123) can0 123#R4");
  ASSERT_TRUE(parsed.ok());
  EXPECT_EQ(*record, *parsed);
}

TEST(BusFrameCandump, ALogRecordEqualsTheOneParsedFromItsLine) {
  const auto record = bus_frame::to_log_record(i_am_here());
  ASSERT_TRUE(record.ok()) << record.error().reason;
  const auto parsed =
      teejet::candump::parse_log_line("(1700000000.000123) can0 18EFD5D8#0000000000007B00");
  ASSERT_TRUE(parsed.ok());
  EXPECT_EQ(*record, *parsed);
}

TEST(BusFrameCandump, RefusesInterfaceNamesALogCannotHold) {
  for (const char* name : {"", "can 0", "can\t0"}) {
    auto sample = i_am_here();
    sample.can_interface(name);
    const auto line = bus_frame::to_candump_line(sample);
    ASSERT_FALSE(line.ok()) << '"' << name << '"';
    EXPECT_EQ(line.error().reason, "interface name \"" + std::string(name) +
                                       "\" cannot be written to a candump log (empty, or blanks "
                                       "or control characters)");
  }
}

TEST(BusFrameCanFrame, RefusesSamplesThatAreNotAFrame) {
  struct Case {
    std::uint32_t id;
    bool extended;
    bool remote;
    std::uint8_t dlc;
    Bytes data;
    std::uint32_t direction;
    std::string reason;
  };
  const std::vector<Case> cases{
      {0x18EFD5D8, true, false, 9, Bytes(9, 0), 0, "dlc 9 is above 8"},
      {0x18EFD5D8, true, true, 9, {}, 0, "dlc 9 is above 8"},
      {0x18EFD5D8, true, false, 3, Bytes(2, 0), 0, "dlc 3 but 2 data bytes"},
      {0x18EFD5D8, true, false, 0, Bytes(1, 0), 0, "dlc 0 but 1 data bytes"},
      {0x18EFD5D8, true, true, 2, Bytes(2, 0), 0,
       "a remote frame with 2 data bytes (it carries none)"},
      {0x800, false, false, 0, {}, 0, "identifier 0x800 is wider than 11 bits"},
      {0x20000000, true, false, 0, {}, 0, "identifier 0x20000000 is wider than 29 bits"},
      {0x123,
       false,
       false,
       0,
       {},
       2,
       "direction 2 is neither FRAME_RECEIVED (0) nor FRAME_SENT (1)"},
  };
  for (const auto& c : cases) {
    auto sample = i_am_here();
    sample.id(c.id);
    sample.extended(c.extended);
    sample.remote(c.remote);
    sample.dlc(c.dlc);
    sample.data(c.data);
    sample.direction(static_cast<teejet::FrameDirection>(c.direction));
    const auto frame = bus_frame::to_can_frame(sample);
    ASSERT_FALSE(frame.ok()) << c.reason;
    EXPECT_EQ(frame.error().reason, c.reason);
    EXPECT_EQ(frame.error().code, teejet::ErrorCode::kInvalidValue);
    EXPECT_FALSE(bus_frame::to_candump_line(sample).ok()) << c.reason;
  }
}

TEST(BusFrameCanFrame, ADataFrameGoesSampleFrameSampleUnchanged) {
  const auto frame = bus_frame::to_can_frame(i_am_here());
  ASSERT_TRUE(frame.ok()) << frame.error().reason;
  EXPECT_EQ(*frame, (teejet::codec::CanFrame{.id = 0x18EFD5D8,
                                             .extended = true,
                                             .remote = false,
                                             .dlc = 8,
                                             .data = {0, 0, 0, 0, 0, 0, 0x7B, 0}}));
  const auto back = bus_frame::from_can_frame(*frame, "gw-1", "can0", teejet::FRAME_RECEIVED,
                                              1'700'000'000'000'123'456ULL);
  EXPECT_EQ(back, i_am_here());
}

TEST(BusFrameCanFrame, ARemoteFrameGoesSampleFrameSampleUnchanged) {
  const auto frame = bus_frame::to_can_frame(remote_request());
  ASSERT_TRUE(frame.ok()) << frame.error().reason;
  EXPECT_EQ(*frame,
            (teejet::codec::CanFrame{.id = 0x123, .extended = false, .remote = true, .dlc = 4}));
  const auto back = bus_frame::from_can_frame(*frame, "gw-1", "can0", teejet::FRAME_RECEIVED,
                                              1'700'000'000'000'123'456ULL);
  EXPECT_EQ(back, remote_request());
  // A remote frame asking for nothing stays a remote frame, not a data frame of no bytes.
  auto empty_request = remote_request();
  empty_request.dlc(0);
  const auto zero = bus_frame::to_can_frame(empty_request);
  ASSERT_TRUE(zero.ok()) << zero.error().reason;
  EXPECT_TRUE(zero->remote);
  EXPECT_EQ(bus_frame::from_can_frame(*zero, "gw-1", "can0", teejet::FRAME_RECEIVED,
                                      1'700'000'000'000'123'456ULL),
            empty_request);
}

TEST(BusFrameCanFrame, AFrameGoesFrameSampleFrameUnchanged) {
  const std::vector<teejet::codec::CanFrame> frames{
      {.id = 0x18EFD9D5, .dlc = 1, .data = {0x00}},
      {.id = 0x7FF, .extended = false, .dlc = 8, .data = {1, 2, 3, 4, 5, 6, 7, 8}},
      {.id = 0x1FFFFFFF, .remote = true, .dlc = 8},
      {.id = 0x000, .extended = false, .remote = true, .dlc = 0},
  };
  for (const auto& frame : frames) {
    const auto sample = bus_frame::from_can_frame(frame, "gw", "can0", teejet::FRAME_SENT, 1);
    const auto back = bus_frame::to_can_frame(sample);
    ASSERT_TRUE(back.ok()) << back.error().reason;
    EXPECT_EQ(*back, frame) << std::hex << frame.id;
  }
}

TEST(BusFrameCanFrame, FromCanFrameCarriesTheWireAndNothingElse) {
  teejet::codec::CanFrame frame;
  frame.id = 0x18EFD8D5;
  frame.dlc = 2;
  frame.data = {0x11, 0x05, 0xAA, 0xAA, 0xAA, 0xAA, 0xAA, 0xAA};
  const auto sample = bus_frame::from_can_frame(frame, "gw", "vcan0", teejet::FRAME_SENT, 7);
  EXPECT_EQ(sample.gateway().to_string(), "gw");
  EXPECT_EQ(sample.can_interface().to_string(), "vcan0");
  EXPECT_EQ(sample.id(), 0x18EFD8D5u);
  EXPECT_TRUE(sample.extended());
  EXPECT_FALSE(sample.remote());
  EXPECT_EQ(sample.data(), (Bytes{0x11, 0x05}));  // dlc bytes, not the array
  EXPECT_EQ(sample.dlc(), 2);
  EXPECT_EQ(sample.direction(), teejet::FRAME_SENT);
  EXPECT_EQ(sample.stamp_ns(), 7u);

  // A remote frame's array holds nothing it carries, whatever is left in it.
  frame.remote = true;
  const auto request = bus_frame::from_can_frame(frame, "gw", "vcan0", teejet::FRAME_SENT, 7);
  EXPECT_TRUE(request.remote());
  EXPECT_EQ(request.dlc(), 2);
  EXPECT_TRUE(request.data().empty());
}

TEST(BusFrameCanFrame, FromCanFrameKeepsWhatTheIdlCanHold) {
  // No classic frame carries more than eight bytes, whatever a driver put in dlc.
  const teejet::codec::CanFrame long_dlc{
      .id = 0x18EFD8D5, .dlc = 15, .data = {1, 2, 3, 4, 5, 6, 7, 8}};
  const auto sample = bus_frame::from_can_frame(long_dlc, "gw", "can0", teejet::FRAME_SENT, 1);
  EXPECT_EQ(sample.dlc(), 8);
  EXPECT_EQ(sample.data(), (Bytes{1, 2, 3, 4, 5, 6, 7, 8}));
  // Names are cut at the IDL's bounds, string<64> and string<32>.
  const auto cut = bus_frame::from_can_frame(long_dlc, std::string(100, 'g'), std::string(40, 'c'),
                                             teejet::FRAME_SENT, 1);
  EXPECT_EQ(cut.gateway().to_string(), std::string(64, 'g'));
  EXPECT_EQ(cut.can_interface().to_string(), std::string(32, 'c'));
}

TEST(BusFrameSerialization, StartsWithTheLittleEndianCdrHeaderAndRoundTrips) {
  const auto payload = bus_frame::serialize(i_am_here());
  ASSERT_GE(payload.size(), 4u);
  EXPECT_EQ(Bytes(payload.begin(), payload.begin() + 4), (Bytes{0x00, 0x01, 0x00, 0x00}));
  const auto back = bus_frame::deserialize(payload);
  ASSERT_TRUE(back.ok()) << back.error().reason;
  EXPECT_EQ(*back, i_am_here());
  const auto request = bus_frame::deserialize(bus_frame::serialize(remote_request()));
  ASSERT_TRUE(request.ok()) << request.error().reason;
  EXPECT_EQ(*request, remote_request());
}

TEST(BusFrameSerialization, ExactBytesOfTheCdrBody) {
  // gateway "gw-1": length 5 with the NUL; can0 likewise; id, two booleans, dlc, the sequence's
  // length (aligned to 4) and bytes, the enum, stamp_ns (aligned to 8 from the body's start,
  // which it already is).
  const Bytes expected{
      0x00, 0x01, 0x00, 0x00,                                // encapsulation
      0x05, 0x00, 0x00, 0x00, 'g',  'w',  '-',  '1',  0x00,  // gateway
      0x00, 0x00, 0x00,                                      // pad to 4
      0x05, 0x00, 0x00, 0x00, 'c',  'a',  'n',  '0',  0x00,  // can_interface
      0x00, 0x00, 0x00,                                      // pad to 4
      0xD8, 0xD5, 0xEF, 0x18,                                // id
      0x01,                                                  // extended
      0x00,                                                  // remote
      0x08,                                                  // dlc
      0x00,                                                  // pad to 4
      0x08, 0x00, 0x00, 0x00,                                // data length
      0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x7B, 0x00,        // data
      0x00, 0x00, 0x00, 0x00,                                // direction FRAME_RECEIVED
      0x40, 0xE2, 0x2B, 0x36, 0xFE, 0x9C, 0x97, 0x17,        // stamp_ns, at 48
  };
  EXPECT_EQ(bus_frame::serialize(i_am_here()), expected);
}

TEST(BusFrameSerialization, ASampleRecordedBeforeRemoteExistedIsRefusedNotMisread) {
  // The I Am Here of ExactBytesOfTheCdrBody as recordings held it before `remote`: extended,
  // dlc, two bytes of padding. Its dlc now stands where `remote` is, and 8 is no boolean.
  auto earlier = bus_frame::serialize(i_am_here());
  earlier[33] = 0x08;
  earlier[34] = 0x00;
  const auto refused = bus_frame::deserialize(earlier);
  ASSERT_FALSE(refused.ok());
  EXPECT_TRUE(refused.error().reason.starts_with("the BusFrame sample does not deserialize: "))
      << refused.error().reason;
  // One data byte: `remote` reads 1 and the padding a dlc of 0, and a remote frame carries none.
  auto one_byte = i_am_here();
  one_byte.dlc(1);
  one_byte.data({0x05});
  auto earlier_one = bus_frame::serialize(one_byte);
  earlier_one[33] = 0x01;
  earlier_one[34] = 0x00;
  const auto misfit = bus_frame::deserialize(earlier_one);
  ASSERT_TRUE(misfit.ok()) << misfit.error().reason;
  EXPECT_EQ(bus_frame::to_can_frame(*misfit).error().reason,
            "a remote frame with 1 data bytes (it carries none)");
}

TEST(BusFrameSerialization, DamagedPayloadsAreErrorsNotExceptions) {
  const auto good = bus_frame::serialize(i_am_here());
  EXPECT_EQ(bus_frame::deserialize({}).error().reason,
            "the BusFrame sample does not deserialize: it ends early (0 bytes)");
  // Every cut of a good payload ends early.
  for (std::size_t size = 0; size < good.size(); ++size) {
    const auto cut = bus_frame::deserialize(std::span(good).first(size));
    EXPECT_FALSE(cut.ok()) << size << " bytes";
  }
  for (const std::size_t boolean_at : {32u, 33u}) {  // extended, remote
    auto bad_bool = good;
    bad_bool[boolean_at] = 0x07;
    const auto refused = bus_frame::deserialize(bad_bool);
    ASSERT_FALSE(refused.ok()) << boolean_at;
    EXPECT_TRUE(refused.error().reason.starts_with("the BusFrame sample does not deserialize: "))
        << refused.error().reason;
  }
  auto bad_encapsulation = good;
  bad_encapsulation[1] = 0x7F;
  EXPECT_FALSE(bus_frame::deserialize(bad_encapsulation).ok());
  // Every single-byte flip either deserializes or is refused: never a crash or an exception.
  for (std::size_t at = 0; at < good.size(); ++at) {
    for (const std::uint8_t value : Bytes{0x00, 0x01, 0x7F, 0xFF}) {
      auto flipped = good;
      flipped[at] = value;
      (void)bus_frame::deserialize(flipped);
    }
  }
}

}  // namespace
