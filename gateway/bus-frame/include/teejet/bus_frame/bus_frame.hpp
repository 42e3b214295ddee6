#pragma once

// teejet::BusFrame (the IDL's raw CAN frame, topic teejet/can/frame) to and from what the rest of
// the tools speak: codec::CanFrame, candump -L lines, and the serialized DDS payload that an MCAP
// recording holds. Pure conversions: no participant, no files.
//
// teejet::BusFrame is the IDL type, codec::CanFrame the codec's: the names are kept qualified
// because valve.h and the codec both live in namespace teejet.

#include <teejet/valve.h>

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "teejet/candump/log_line.hpp"
#include "teejet/codec/frame.hpp"
#include "teejet/core/result.hpp"

namespace teejet::bus_frame {

// A stamp in ns since the Unix epoch as candump writes it: the sub-microsecond part is dropped
// (candump -L has six digits), never rounded, so that a frame never moves into the next second.
struct Timestamp {
  std::uint64_t seconds = 0;
  std::uint32_t microseconds = 0;  // 0 .. 999999
  friend bool operator==(const Timestamp&, const Timestamp&) = default;
};
Timestamp split_stamp(std::uint64_t stamp_ns);

// The frame of a sample. Refused (ErrorCode::kInvalidValue, the reason names the value): a dlc
// above 8, a data frame whose data is not dlc bytes, a remote frame with data, an identifier
// wider than its format (11 or 29 bits), a direction that is neither FRAME_RECEIVED nor
// FRAME_SENT.
Result<codec::CanFrame> to_can_frame(const teejet::BusFrame& sample);

// The sample of `frame`, which to_can_frame() turns back into `frame`: a data frame with its
// first dlc bytes, a remote frame with its dlc and no data. A dlc above 8 (whatever a driver put
// there) is 8, the most a classic frame carries. Names longer than the IDL's bounds (gateway 64,
// interface 32) are cut there.
teejet::BusFrame from_can_frame(const codec::CanFrame& frame, std::string_view gateway,
                                std::string_view can_interface, teejet::FrameDirection direction,
                                std::uint64_t stamp_ns);

// The sample as a candump log record: the time from stamp_ns, the interface from can_interface.
// The same refusals as to_can_frame.
Result<candump::LogRecord> to_log_record(const teejet::BusFrame& sample);

// The sample as one `candump -L` line (no newline), as canplayer and python-can read it. Also
// refuses an interface name that is empty or holds blanks or control characters, which would
// make the line unreadable.
Result<std::string> to_candump_line(const teejet::BusFrame& sample);

// The DDS serialized payload, as BusFramePubSubType::serialize writes it: the 4-byte
// encapsulation header (00 01 00 00, CDR little-endian) and the CDR body. This is the message
// data of a teejet/can/frame channel in an MCAP recording.
std::vector<std::uint8_t> serialize(const teejet::BusFrame& sample);

// The reverse, by BusFramePubSubType::deserialize. Any byte string is safe: a payload that is cut
// short, has an unknown encapsulation or a value CDR refuses (a boolean that is not 0 or 1) is
// an Error, never an exception. The values are not checked: to_can_frame does that.
Result<teejet::BusFrame> deserialize(std::span<const std::uint8_t> payload);

}  // namespace teejet::bus_frame
