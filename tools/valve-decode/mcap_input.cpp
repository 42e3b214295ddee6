#include "mcap_input.hpp"

#include <optional>
#include <set>

#include "teejet/bus_frame/bus_frame.hpp"
#include "teejet/frame_json/frame_json.hpp"
#include "teejet/mcap/reader.hpp"

namespace teejet::valve_decode {

using frame_json::decode_record;
using frame_json::message_error_json_line;
namespace {

constexpr std::string_view kBusFrameSchema = "teejet::BusFrame";
constexpr std::string_view kCdr = "cdr";

std::set<std::uint16_t> frame_channels(const mcap::Contents& contents) {
  std::set<std::uint16_t> ids;
  for (const auto& [id, channel] : contents.channels) {
    const auto schema = contents.schemas.find(channel.schema_id);
    if (schema != contents.schemas.end() && schema->second.name == kBusFrameSchema) ids.insert(id);
  }
  return ids;
}

// Whether the frames come from more than one gateway: only then does each line need "gw", since
// their interfaces (can0 on every gateway) no longer tell the buses apart. Decided for the whole
// file, so that its lines all have the same members.
bool several_gateways(mcap::Source& file, const std::set<std::uint16_t>& channels) {
  std::set<std::string> gateways;
  const auto read =
      mcap::read_messages(file, [&](const mcap::Channel& channel, const mcap::Message& message) {
        if (gateways.size() > 1 || !channels.contains(channel.id)) return;
        if (const auto sample = bus_frame::deserialize(message.data)) {
          gateways.insert(sample->gateway().to_string());
        }
      });
  return read && gateways.size() > 1;
}

std::string message_line(const mcap::Channel& channel, const mcap::Message& message,
                         bool name_gateway) {
  const auto error = [&](const std::string& reason) {
    return message_error_json_line(reason, channel.topic, message.sequence, message.log_time);
  };
  if (channel.message_encoding != kCdr) {
    return error("message encoding \"" + channel.message_encoding + "\" is not cdr");
  }
  const auto sample = bus_frame::deserialize(message.data);
  if (!sample) return error(sample.error().reason);
  const auto record = bus_frame::to_log_record(*sample);
  if (!record) return error(record.error().reason);
  std::optional<std::string> gateway;
  if (name_gateway) gateway = sample->gateway().to_string();
  return decode_record(*record, gateway);
}

}  // namespace

bool decode_mcap(mcap::Source& file, const std::string& path, std::ostream& out,
                 std::ostream& err) {
  const std::string prefix = "valve-decode: " + path + ": ";
  // A first pass checks the whole file and learns the schemas (the reader's visitor sees only a
  // message's channel), so that a damaged file prints nothing rather than half its frames.
  const auto contents = mcap::read_messages(file, {});
  if (!contents) {
    err << prefix << contents.error().reason << '\n';
    return false;
  }
  const auto warn_if_incomplete = [&] {
    if (contents->incomplete.empty()) return;
    err << prefix
        << "warning: incomplete recording, decoded up to where it ends: " << contents->incomplete
        << '\n';
  };
  const auto channels = frame_channels(*contents);
  if (channels.empty()) {
    err << prefix << "no teejet/can/frame channel (record with teejet-gateway --record-frames)\n";
    warn_if_incomplete();
    return false;
  }
  const bool name_gateway = several_gateways(file, channels);
  const auto printed =
      mcap::read_messages(file, [&](const mcap::Channel& channel, const mcap::Message& message) {
        if (channels.contains(channel.id))
          out << message_line(channel, message, name_gateway) << '\n';
      });
  // The first pass read these bytes without an error; kept so that a reader that ever reads
  // differently the second time is reported, not silently cut short.
  if (!printed) {
    err << prefix << printed.error().reason << '\n';
    return false;
  }
  warn_if_incomplete();
  return true;
}

bool decode_mcap(std::span<const std::uint8_t> file, const std::string& path, std::ostream& out,
                 std::ostream& err) {
  mcap::MemorySource source(file);
  return decode_mcap(source, path, out, err);
}

}  // namespace teejet::valve_decode
