#pragma once

// The raw bus on DDS (teejet-gateway --record-frames): every frame the gateway sends or receives
// as a teejet::BusFrame on topics::kBusFrame, best effort, stamped with the frame's own time.
// codec::CanFrame (the codec's frame) and teejet::BusFrame (the IDL's) meet only in
// bus_frame::from_can_frame() and to_can_frame(), which the readers of recordings use too.

#include <fastdds/dds/publisher/DataWriter.hpp>
#include <memory>
#include <string>

#include "teejet/can/observed_bus.hpp"
#include "teejet/dds/participant.hpp"

namespace teejet::dds {

// Thread-safe: the bus reader and the command thread both call on_frame(). The writer belongs
// to `participant`, which must outlive every on_frame() call.
class FramePublisher final : public can::FrameObserver {
 public:
  static Result<std::unique_ptr<FramePublisher>> create(Participant& participant,
                                                        std::string gateway,
                                                        std::string can_interface);

  // Writes the frame with `stamp` as the sample's source timestamp. A failed write is logged
  // (rarely), never returned: a frame recorder must not disturb the bus it records.
  void on_frame(const codec::CanFrame& frame, can::FrameDirection direction,
                Timestamp stamp) override;

 private:
  FramePublisher(eprosima::fastdds::dds::DataWriter* writer, std::string gateway,
                 std::string can_interface);

  eprosima::fastdds::dds::DataWriter* const writer_;
  const std::string gateway_;
  const std::string can_interface_;
};

}  // namespace teejet::dds
