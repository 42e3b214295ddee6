#include "teejet/dds/frame_publisher.hpp"

#include <spdlog/spdlog.h>

#include <atomic>

#include "teejet/bus_frame/bus_frame.hpp"
#include "teejet/dds/participant.hpp"
#include "teejet/dds/topics.hpp"

namespace teejet::dds {

namespace fdds = eprosima::fastdds::dds;

Result<std::unique_ptr<FramePublisher>> FramePublisher::create(Participant& participant,
                                                               std::string gateway,
                                                               std::string can_interface) {
  auto topic = topics::topic_of<BusFrame>(participant);
  if (!topic) return topic.error();
  auto writer = participant.writer(*topic, topics::frame_writer_qos());
  if (!writer) return writer.error();
  return std::unique_ptr<FramePublisher>(
      new FramePublisher(*writer, std::move(gateway), std::move(can_interface)));
}

FramePublisher::FramePublisher(fdds::DataWriter* writer, std::string gateway,
                               std::string can_interface)
    : writer_(writer), gateway_(std::move(gateway)), can_interface_(std::move(can_interface)) {}

void FramePublisher::on_frame(const codec::CanFrame& frame, can::FrameDirection direction,
                              Timestamp stamp) {
  auto sample = bus_frame::from_can_frame(
      frame, gateway_, can_interface_,
      direction == can::FrameDirection::kSent ? FRAME_SENT : FRAME_RECEIVED,
      unix_nanoseconds(stamp));
  // Best effort: a reader drops a frame older than the last it got, never files it late, so
  // the stamp stays the frame's own even where a received frame follows a later sent one.
  const auto result =
      writer_->write_w_timestamp(&sample, fdds::HANDLE_NIL, to_dds_time(sample.stamp_ns()));
  if (result == eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK) return;
  // Best effort loses frames under load by design; a write that fails says something is wrong
  // with the writer itself. Once, then every thousandth, so that a full bus never floods the log.
  static std::atomic<std::uint64_t> failures{0};
  const auto count = ++failures;
  if (count == 1 || count % 1000 == 0) {
    spdlog::error("DDS write on {} failed (code {}); {} frame(s) not published so far",
                  topics::kBusFrame, result(), count);
  }
}

}  // namespace teejet::dds
