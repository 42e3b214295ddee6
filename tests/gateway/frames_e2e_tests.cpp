// --record-frames through the whole gateway: every frame it receives and sends on its bus
// reaches a DDS reader of teejet/can/frame with the bytes of the protocol sheet; without the
// option no frame writer exists. Runs inside a private network namespace (tests/netns/isolated).
//
// Not a TSan suite: its reader shares the gateway's process, so Fast DDS delivers intra-process
// from a shared payload pool, and at this suite's frame rate TSan sees (1 run in 9) the pool's
// own race between a writer's serialize and a reader's deserialize (Fast DDS issue 6340,
// TopicPayloadPool, inside libfastcdr/libfastrtps). A recorder is a process of its own.

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <fastdds/dds/core/status/SubscriptionMatchedStatus.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <vector>

#include "gateway_fixture.hpp"
#include "support/dds_peer.hpp"
#include "support/eventually.hpp"
#include "support/test_domain.hpp"
#include "teejet/bus_frame/bus_frame.hpp"
#include "teejet/dds/frame_publisher.hpp"
#include "teejet/dds/topics.hpp"
#include "teejet/gateway/config.hpp"

namespace teejet::gateway {
namespace {

using namespace std::chrono_literals;
using eprosima::fastdds::dds::DataReader;
using eprosima::fastdds::dds::SampleInfo;
using ReturnCode = eprosima::fastrtps::types::ReturnCode_t;

using fixture::make_gateway;
using fixture::sim_config;
using fixture::start_and_wait_online;
using teejet::testing::eventually;
using teejet::testing::move_to;
using teejet::testing::test_domain;
using Ecu = teejet::testing::DdsPeer;

std::uint64_t now_ns() { return unix_nanoseconds(system_clock()->wall()); }

// A frame as a reader of teejet/can/frame got it, with the sample's DDS source timestamp.
struct Received {
  BusFrame frame;
  std::uint64_t source_ns;
};

// Takes what `reader` holds and appends it to `all`; returns `all`.
std::vector<Received>& take_frames(DataReader* reader, std::vector<Received>& all) {
  BusFrame sample;
  SampleInfo info;
  while (reader->take_next_sample(&sample, &info) == ReturnCode::RETCODE_OK) {
    if (!info.valid_data) continue;
    const auto& source = info.source_timestamp;
    all.push_back(
        {sample, static_cast<std::uint64_t>(source.seconds()) * 1'000'000'000 + source.nanosec()});
  }
  return all;
}

const Received* find(const std::vector<Received>& all, std::uint32_t id, FrameDirection direction,
                     std::uint8_t first_byte) {
  for (const auto& r : all) {
    if (r.frame.id() == id && r.frame.direction() == direction && !r.frame.data().empty() &&
        r.frame.data()[0] == first_byte) {
      return &r;
    }
  }
  return nullptr;
}

TEST(RecordFrames, EveryFrameOfTheBusReachesTheTopicWithTheBytesOfTheSheet) {
  const std::uint64_t before = now_ns();
  auto config = sim_config("gw-frames", 2);
  config.record_frames = true;
  Ecu recorder(test_domain(), "frame-recorder");
  DataReader* frames = recorder.reader<BusFrame>(dds::topics::frame_reader_qos());
  ASSERT_NE(frames, nullptr);
  auto gateway_owner = make_gateway(config);
  Gateway& gateway = *gateway_owner;
  ASSERT_NO_FATAL_FAILURE(start_and_wait_online(gateway, 2));

  // (a) I'm Here, once a second from each valve: serial 1 took 0xD8, serial 2 0xD9. Part number
  // 0 in bytes 1-3, the serial in bytes 4-6, run mode 0 (application code) in byte 7.
  std::vector<Received> all;
  ASSERT_TRUE(eventually(
      [&] {
        take_frames(frames, all);
        return find(all, 0x18EFD5D8, FRAME_RECEIVED, 0x00) &&
               find(all, 0x18EFD5D9, FRAME_RECEIVED, 0x00);
      },
      15s))
      << all.size() << " frames, no I'm Here of both valves among them";
  const auto* here_1 = find(all, 0x18EFD5D8, FRAME_RECEIVED, 0x00);
  const auto* here_2 = find(all, 0x18EFD5D9, FRAME_RECEIVED, 0x00);
  EXPECT_EQ(here_1->frame.data(), (std::vector<std::uint8_t>{0, 0, 0, 0, 0x00, 0x00, 0x01, 0}));
  EXPECT_EQ(here_2->frame.data(), (std::vector<std::uint8_t>{0, 0, 0, 0, 0x00, 0x00, 0x02, 0}));
  EXPECT_EQ(here_1->frame.dlc(), 8);
  EXPECT_TRUE(here_1->frame.extended());

  // (b) Target Degrees 45.0 at 100 % opening, to 0xD8 from the controller 0xD5: speed 0x64,
  // direction open 1, 450 = 0x01C2 MSB first, padded to eight bytes with 0xFF.
  const auto id = recorder.send(move_to(1, 45.0f));
  EXPECT_EQ(Ecu::states(recorder.follow(id)), (std::vector{COMMAND_ACCEPTED, COMMAND_COMPLETED}));
  ASSERT_TRUE(eventually(
      [&] { return find(take_frames(frames, all), 0x18EFD8D5, FRAME_SENT, 0x02) != nullptr; }, 5s))
      << "no Target Degrees frame sent to 0xD8 among " << all.size() << " frames";
  const auto* target = find(all, 0x18EFD8D5, FRAME_SENT, 0x02);
  EXPECT_EQ(target->frame.data(),
            (std::vector<std::uint8_t>{0x02, 0x64, 0x01, 0x01, 0xC2, 0xFF, 0xFF, 0xFF}));
  EXPECT_EQ(target->frame.dlc(), 8);
  // The valves answer the gateway's polls on their own every 100 ms: Position (0x02) back.
  EXPECT_NE(find(all, 0x18EFD5D9, FRAME_RECEIVED, 0x02), nullptr);

  // The Stop the gateway sends every valve on its way out (stop_valves_on_exit) is published
  // before its writer goes: Stop is the message id alone, padded.
  gateway.stop();
  const std::uint64_t after = now_ns();
  ASSERT_TRUE(eventually(
      [&] { return find(take_frames(frames, all), 0x18EFD9D5, FRAME_SENT, 0x00) != nullptr; }, 5s))
      << "no Stop to 0xD9 among " << all.size() << " frames";
  EXPECT_EQ(find(all, 0x18EFD9D5, FRAME_SENT, 0x00)->frame.data(),
            (std::vector<std::uint8_t>{0x00, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF}));

  // (c) Every frame names this gateway and its interface, and is stamped inside the test,
  // with the same time as its DDS source timestamp.
  std::size_t received = 0, sent = 0;
  for (const auto& r : all) {
    ASSERT_EQ(r.frame.gateway().to_string(), "gw-frames");
    ASSERT_EQ(r.frame.can_interface().to_string(), "sim:2");
    ASSERT_GE(r.frame.stamp_ns(), before);
    ASSERT_LE(r.frame.stamp_ns(), after);
    ASSERT_EQ(r.source_ns, r.frame.stamp_ns());
    ASSERT_EQ(r.frame.data().size(), r.frame.dlc());
    // Valve traffic both ways, and the gateway's address claim (a request for claims from the
    // null address and its claim, 0x18EAFFFE and 0x18EEFFD5) when the reader matched in time.
    ASSERT_TRUE((r.frame.id() & 0xFFFFFF00) == 0x18EFD500 ||
                (r.frame.id() & 0xFFFF00FF) == 0x18EF00D5 || r.frame.id() == 0x18EAFFFE ||
                r.frame.id() == 0x18EEFFD5)
        << std::hex << r.frame.id();
    (r.frame.direction() == FRAME_SENT ? sent : received)++;
  }
  EXPECT_GT(received, 0u);
  EXPECT_GT(sent, 0u);
}

TEST(RecordFrames, WithoutTheOptionNoFrameWriterExists) {
  auto config = sim_config("gw-no-frames", 2);
  ASSERT_FALSE(config.record_frames);  // off by default
  Ecu peer(test_domain(), "frame-watcher");
  DataReader* frames = peer.reader<BusFrame>(dds::topics::frame_reader_qos());
  DataReader* presence = peer.reader<ValvePresence>();
  ASSERT_NE(frames, nullptr);
  auto gateway_owner = make_gateway(config);
  Gateway& gateway = *gateway_owner;
  ASSERT_NO_FATAL_FAILURE(start_and_wait_online(gateway, 2));

  // The gateway is discovered and its endpoints matched: presence arrives and a command
  // completes. The frame reader still matched nothing and holds nothing.
  std::map<std::uint32_t, ValvePresence> seen;
  ASSERT_TRUE(eventually(
      [&] { return teejet::testing::latest_by_serial(presence, seen).size() == 2; }, 15s));
  EXPECT_EQ(Ecu::states(peer.follow(peer.send(move_to(2, 30.0f)))),
            (std::vector{COMMAND_ACCEPTED, COMMAND_COMPLETED}));
  eprosima::fastdds::dds::SubscriptionMatchedStatus matched;
  ASSERT_EQ(frames->get_subscription_matched_status(matched), ReturnCode::RETCODE_OK);
  EXPECT_EQ(matched.total_count, 0);
  EXPECT_EQ(matched.current_count, 0);
  std::vector<Received> all;
  EXPECT_TRUE(take_frames(frames, all).empty());
}

// What the gateway publishes reads back, through DDS and bus_frame::to_can_frame() as every
// reader of recordings does, as the frame that was on the bus: remote frames included.
TEST(FramePublisher, EveryFrameReadsBackAsTheFrameThatWasOnTheBus) {
  Ecu gateway_side(test_domain(), "frame-publisher");
  Ecu recorder(test_domain(), "frame-reader");
  DataReader* frames = recorder.reader<BusFrame>(dds::topics::frame_reader_qos());
  ASSERT_NE(frames, nullptr);
  auto publisher = dds::FramePublisher::create(gateway_side.participant(), "gw", "can0");
  ASSERT_TRUE(publisher) << publisher.error().reason;

  const std::vector<codec::CanFrame> on_the_bus{
      {.id = 0x18EFD9D5, .dlc = 1, .data = {0x00}},
      {.id = 0x123, .extended = false, .remote = true, .dlc = 4},
      {.id = 0x18EFD5D8, .remote = true, .dlc = 0},
  };
  // Frame i is stamped base + i ns, which tells it apart when it arrives.
  constexpr std::uint64_t base = 1'700'000'000'123'456'789;
  std::vector<Received> all;
  const auto arrived = [&](std::size_t i) {
    return std::any_of(all.begin(), all.end(),
                       [&](const Received& r) { return r.frame.stamp_ns() == base + i; });
  };
  // Best effort drops what is written before the writer has matched the reader: the frames go
  // out again until each of them arrived.
  ASSERT_TRUE(eventually(
      [&] {
        for (std::size_t i = 0; i < on_the_bus.size(); ++i) {
          (*publisher)
              ->on_frame(on_the_bus[i], can::FrameDirection::kReceived,
                         from_unix_nanoseconds(base + i));
        }
        take_frames(frames, all);
        return arrived(0) && arrived(1) && arrived(2);
      },
      15s))
      << all.size() << " frames arrived, not one of each";
  for (const auto& r : all) {
    const std::uint64_t i = r.frame.stamp_ns() - base;
    ASSERT_LT(i, on_the_bus.size()) << r.frame.stamp_ns();
    const auto frame = bus_frame::to_can_frame(r.frame);
    ASSERT_TRUE(frame) << i << ": " << frame.error().reason;
    EXPECT_EQ(*frame, on_the_bus[i]) << i;
    EXPECT_EQ(r.frame.direction(), FRAME_RECEIVED);
    EXPECT_EQ(r.frame.gateway().to_string(), "gw");
    EXPECT_EQ(r.frame.can_interface().to_string(), "can0");
    EXPECT_EQ(r.source_ns, r.frame.stamp_ns());
  }
}

TEST(RecordFramesConfig, OffByDefaultAndReadFromTheGatewaySection) {
  EXPECT_FALSE(GatewayConfig{}.record_frames);
  const auto on = parse_config("gateway: {record_frames: true}\n", "test.yaml", {});
  ASSERT_TRUE(on) << on.error().reason;
  EXPECT_TRUE(on->record_frames);
  const auto off = parse_config("gateway: {record_frames: false}\n", "test.yaml", {});
  ASSERT_TRUE(off) << off.error().reason;
  EXPECT_FALSE(off->record_frames);
}

TEST(RecordFramesConfig, ANonBooleanValueNamesTheKey) {
  const auto bad = parse_config("gateway:\n  record_frames: sometimes\n", "test.yaml", {});
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().reason.find("test.yaml:2"), std::string::npos) << bad.error().reason;
  EXPECT_NE(bad.error().reason.find("gateway.record_frames"), std::string::npos)
      << bad.error().reason;
}

}  // namespace
}  // namespace teejet::gateway
