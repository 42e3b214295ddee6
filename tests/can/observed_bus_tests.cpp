// ObservedBus: every frame that crosses the bus reaches the observer, in order, with the right
// direction and stamp; nothing else about the bus changes.

#include <gtest/gtest.h>

#include <mutex>
#include <vector>

#include "teejet/can/observed_bus.hpp"
#include "teejet/can/virtual_bus.hpp"
#include "teejet/codec/codec.hpp"

namespace teejet::can {
namespace {

using namespace std::chrono_literals;

struct Seen {
  codec::CanFrame frame;
  FrameDirection direction;
  Timestamp stamp;
  friend bool operator==(const Seen&, const Seen&) = default;
};

class Recorder final : public FrameObserver {
 public:
  void on_frame(const codec::CanFrame& frame, FrameDirection direction, Timestamp stamp) override {
    std::lock_guard lock(mutex_);
    seen_.push_back({frame, direction, stamp});
  }
  std::vector<Seen> seen() const {
    std::lock_guard lock(mutex_);
    return seen_;
  }

 private:
  mutable std::mutex mutex_;
  std::vector<Seen> seen_;
};

// The frames of the sheet, with their bytes written out so that the test does not trust the
// codec: I'm Here of serial 1 at 0xD8, and Target Degrees 45.0 at 100 % opening to 0xD8.
const codec::CanFrame kImHere{
    .id = 0x18EFD5D8, .dlc = 8, .data = {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x01, 0x00}};
const codec::CanFrame kTargetDegrees{
    .id = 0x18EFD8D5, .dlc = 8, .data = {0x02, 0x64, 0x01, 0x01, 0xC2, 0xFF, 0xFF, 0xFF}};
const codec::CanFrame kStop{.id = 0x18EFD9D5, .dlc = 1, .data = {0x00}};

class ObservedBusTest : public ::testing::Test {
 protected:
  // A unique bus per test: parallel ctest runs share the process-wide registry of names.
  std::string bus_name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
  // The peer's clock stamps what the observed bus receives; the observed bus's own clock
  // stamps what it sends. Different values tell the two apart.
  std::shared_ptr<ManualClock> bus_clock =
      std::make_shared<ManualClock>(Timestamp{Duration{1'700'000'000'000'000'000}});
  std::shared_ptr<ManualClock> send_clock =
      std::make_shared<ManualClock>(Timestamp{Duration{1'800'000'000'000'000'000}});
  Recorder recorder;

  std::unique_ptr<ObservedBus> observed() {
    auto bus = std::make_unique<ObservedBus>(
        std::make_unique<VirtualBus>(bus_name, VirtualBusOptions{.clock = bus_clock}), recorder,
        send_clock);
    EXPECT_TRUE(bus->open());
    return bus;
  }
};

TEST_F(ObservedBusTest, ReportsSentFramesWithTheWallClockAndDeliversThemUnchanged) {
  auto bus = observed();
  VirtualBus peer(bus_name);
  ASSERT_TRUE(peer.open());

  ASSERT_TRUE(bus->send(kTargetDegrees));
  send_clock->advance(5ms);
  const std::vector burst{kStop, kTargetDegrees};
  const auto sent = bus->send_batch(burst);
  ASSERT_TRUE(sent.status);
  EXPECT_EQ(sent.sent, 2u);

  const Timestamp first{Duration{1'800'000'000'000'000'000}};
  EXPECT_EQ(recorder.seen(),
            (std::vector<Seen>{{kTargetDegrees, FrameDirection::kSent, first},
                               {kStop, FrameDirection::kSent, first + 5ms},
                               {kTargetDegrees, FrameDirection::kSent, first + 5ms}}));
  std::vector<TimedFrame> wire;
  EXPECT_EQ(peer.receive_batch(wire, 8, 1s), 3u);
  ASSERT_EQ(wire.size(), 3u);
  EXPECT_EQ(wire[0].frame, kTargetDegrees);
  EXPECT_EQ(wire[1].frame, kStop);
  EXPECT_EQ(wire[2].frame, kTargetDegrees);
  EXPECT_EQ(bus->statistics().frames_out, 3u);
}

TEST_F(ObservedBusTest, ReportsReceivedFramesWithTheirReceiveStampInOrder) {
  auto bus = observed();
  VirtualBus peer(bus_name);
  ASSERT_TRUE(peer.open());
  const Timestamp start{Duration{1'700'000'000'000'000'000}};

  ASSERT_TRUE(peer.send(kImHere));
  auto one = bus->receive(1s);
  ASSERT_TRUE(one);
  EXPECT_EQ(one->frame, kImHere);
  EXPECT_EQ(one->received, start);

  bus_clock->advance(10ms);
  const std::vector burst{kImHere, kStop, kTargetDegrees};
  ASSERT_TRUE(peer.send_batch(burst).status);
  std::vector<TimedFrame> got{TimedFrame{}};  // what the caller had before is not reported
  EXPECT_EQ(bus->receive_batch(got, 8, 1s), 3u);
  ASSERT_EQ(got.size(), 4u);
  EXPECT_EQ(got[3].frame, kTargetDegrees);

  EXPECT_EQ(recorder.seen(),
            (std::vector<Seen>{{kImHere, FrameDirection::kReceived, start},
                               {kImHere, FrameDirection::kReceived, start + 10ms},
                               {kStop, FrameDirection::kReceived, start + 10ms},
                               {kTargetDegrees, FrameDirection::kReceived, start + 10ms}}));
  EXPECT_EQ(bus->statistics().frames_in, 4u);
}

TEST_F(ObservedBusTest, BothDirectionsInterleaveInTheOrderTheyHappened) {
  auto bus = observed();
  VirtualBus peer(bus_name);
  ASSERT_TRUE(peer.open());
  ASSERT_TRUE(bus->send(kTargetDegrees));
  ASSERT_TRUE(peer.send(kImHere));
  ASSERT_TRUE(bus->receive(1s));
  ASSERT_TRUE(bus->send(kStop));

  const auto seen = recorder.seen();
  ASSERT_EQ(seen.size(), 3u);
  EXPECT_EQ(seen[0].frame, kTargetDegrees);
  EXPECT_EQ(seen[0].direction, FrameDirection::kSent);
  EXPECT_EQ(seen[1].frame, kImHere);
  EXPECT_EQ(seen[1].direction, FrameDirection::kReceived);
  EXPECT_EQ(seen[2].frame, kStop);
  EXPECT_EQ(seen[2].direction, FrameDirection::kSent);
}

TEST_F(ObservedBusTest, FailedSendsAreNotReported) {
  auto bus = observed();
  VirtualBus::set_link_up(bus_name, false);
  EXPECT_FALSE(bus->send(kStop));
  const std::vector burst{kStop, kTargetDegrees};
  const auto sent = bus->send_batch(burst);
  EXPECT_FALSE(sent.status);
  EXPECT_EQ(sent.sent, 0u);
  EXPECT_TRUE(recorder.seen().empty());
  // The failures are the inner bus's, as without the wrapper.
  EXPECT_EQ(bus->statistics().tx_failed, 2u);
  EXPECT_EQ(bus->statistics().state, BusState::kDown);
  VirtualBus::set_link_up(bus_name, true);
}

// A bus that accepts a given number of frames, then refuses: a batch cut short.
class AcceptsOnly final : public Bus {
 public:
  explicit AcceptsOnly(std::size_t frames) : left_(frames) {}
  const std::string& name() const override { return name_; }
  Status open() override { return {}; }
  void close() override {}
  Status send(const codec::CanFrame&) override {
    if (left_ == 0) return Error{ErrorCode::kUnavailable, "full"};
    --left_;
    return {};
  }
  std::optional<TimedFrame> receive(std::chrono::milliseconds) override { return std::nullopt; }
  BusStatistics statistics() const override { return {}; }

 private:
  std::string name_ = "accepts-only";
  std::size_t left_;
};

TEST_F(ObservedBusTest, ABatchCutShortReportsOnlyTheFramesHandedOver) {
  ObservedBus bus(std::make_unique<AcceptsOnly>(2), recorder, send_clock);
  const std::vector burst{kStop, kTargetDegrees, kImHere};
  const auto sent = bus.send_batch(burst);
  EXPECT_EQ(sent.sent, 2u);
  EXPECT_FALSE(sent.status);
  const auto seen = recorder.seen();
  ASSERT_EQ(seen.size(), 2u);
  EXPECT_EQ(seen[0].frame, kStop);
  EXPECT_EQ(seen[1].frame, kTargetDegrees);
  EXPECT_EQ(bus.name(), "accepts-only");
}

TEST_F(ObservedBusTest, ATimeoutOrAClosedBusReportsNothing) {
  auto bus = observed();
  EXPECT_FALSE(bus->receive(0ms));
  std::vector<TimedFrame> got;
  EXPECT_EQ(bus->receive_batch(got, 8, 0ms), 0u);
  bus->close();
  EXPECT_FALSE(bus->send(kStop));
  EXPECT_TRUE(recorder.seen().empty());
}

TEST_F(ObservedBusTest, ReleaseHandsBackTheSameBusUnobserved) {
  auto bus = observed();
  VirtualBus peer(bus_name);
  ASSERT_TRUE(peer.open());
  std::unique_ptr<Bus> inner = bus->release();
  bus.reset();
  ASSERT_TRUE(inner->send(kStop));  // still open: releasing changes nothing on the bus
  ASSERT_TRUE(peer.send(kImHere));
  EXPECT_TRUE(inner->receive(1s));
  EXPECT_TRUE(peer.receive(1s));
  EXPECT_TRUE(recorder.seen().empty());
}

}  // namespace
}  // namespace teejet::can
