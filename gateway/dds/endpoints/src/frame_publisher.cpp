#include "teejet/dds/frame_publisher.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <atomic>
#include <span>

#include "teejet/dds/topics.hpp"

namespace teejet::dds {

namespace fdds = eprosima::fastdds::dds;

BusFrame to_bus_frame(const codec::CanFrame& frame, can::FrameDirection direction, Timestamp stamp,
                      const std::string& gateway, const std::string& can_interface) {
  BusFrame sample;
  sample.gateway(gateway);
  sample.can_interface(can_interface);
  sample.id(frame.id);
  sample.extended(frame.extended);
  // A remote frame's dlc asks for bytes that it does not carry; no classic frame carries more
  // than eight, whatever a driver put in dlc.
  const std::size_t length = frame.remote ? 0 : std::min<std::size_t>(frame.dlc, 8);
  const std::span<const std::uint8_t> payload(frame.data.data(), length);
  sample.dlc(frame.dlc);
  sample.data().assign(payload.begin(), payload.end());
  sample.direction(direction == can::FrameDirection::kSent ? teejet::FRAME_SENT
                                                           : teejet::FRAME_RECEIVED);
  sample.stamp_ns(unix_nanoseconds(stamp));
  return sample;
}

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
  auto sample = to_bus_frame(frame, direction, stamp, gateway_, can_interface_);
  const std::uint64_t ns = sample.stamp_ns();
  const eprosima::fastrtps::Time_t source(static_cast<std::int32_t>(ns / 1'000'000'000),
                                          static_cast<std::uint32_t>(ns % 1'000'000'000));
  const auto result = writer_->write_w_timestamp(&sample, fdds::HANDLE_NIL, source);
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
