#include "teejet/dds/serial_filter.hpp"

#include <charconv>

namespace teejet::dds {

using ReturnCode = eprosima::fastrtps::types::ReturnCode_t;

std::string serial_filter_expression(const std::set<std::uint32_t>& serials) {
  std::string expression;
  for (const std::uint32_t serial : serials) {
    if (!expression.empty()) expression += ' ';
    expression += std::to_string(serial);
  }
  return expression;
}

std::optional<std::set<std::uint32_t>> parse_serial_filter(std::string_view expression) {
  std::set<std::uint32_t> serials;
  std::size_t at = 0;
  while (at < expression.size()) {
    if (expression[at] == ' ') {
      ++at;
      continue;
    }
    std::uint32_t serial = 0;
    const char* end = expression.data() + expression.size();
    const auto [stop, error] = std::from_chars(expression.data() + at, end, serial);
    if (error != std::errc{} || (stop != end && *stop != ' ')) return std::nullopt;
    serials.insert(serial);
    at = static_cast<std::size_t>(stop - expression.data());
  }
  if (serials.empty()) return std::nullopt;
  return serials;
}

std::optional<std::uint32_t> serial_of(
    const eprosima::fastrtps::rtps::SerializedPayload_t& payload) {
  // The encapsulation's first two bytes: 0x0000 plain CDR big-endian, 0x0001 little-endian.
  if (payload.data == nullptr || payload.length < 8 || payload.data[0] != 0 ||
      payload.data[1] > 1) {
    return std::nullopt;
  }
  const auto* bytes = payload.data + 4;
  if (payload.data[1] == 1) {
    return static_cast<std::uint32_t>(bytes[0]) | static_cast<std::uint32_t>(bytes[1]) << 8 |
           static_cast<std::uint32_t>(bytes[2]) << 16 | static_cast<std::uint32_t>(bytes[3]) << 24;
  }
  return static_cast<std::uint32_t>(bytes[3]) | static_cast<std::uint32_t>(bytes[2]) << 8 |
         static_cast<std::uint32_t>(bytes[1]) << 16 | static_cast<std::uint32_t>(bytes[0]) << 24;
}

bool SerialFilter::evaluate(const SerializedPayload& payload, const FilterSampleInfo&,
                            const GUID_t&) const {
  const auto serial = serial_of(payload);
  return !serial || serials_.contains(*serial);
}

ReturnCode SerialFilterFactory::create_content_filter(
    const char* filter_class_name, const char*, const eprosima::fastdds::dds::TopicDataType*,
    const char* filter_expression, const ParameterSeq&,
    eprosima::fastdds::dds::IContentFilter*& filter) {
  if (filter_class_name == nullptr || std::string_view(filter_class_name) != kSerialFilterClass) {
    return ReturnCode::RETCODE_BAD_PARAMETER;
  }
  // Fast DDS passes no expression when only the parameters of an existing filter change.
  if (filter_expression == nullptr) {
    return filter != nullptr ? ReturnCode::RETCODE_OK : ReturnCode::RETCODE_BAD_PARAMETER;
  }
  auto serials = parse_serial_filter(filter_expression);
  if (!serials) return ReturnCode::RETCODE_BAD_PARAMETER;
  delete_content_filter(filter_class_name, filter);
  filter = new SerialFilter(std::move(*serials));
  return ReturnCode::RETCODE_OK;
}

ReturnCode SerialFilterFactory::delete_content_filter(
    const char*, eprosima::fastdds::dds::IContentFilter* filter) {
  delete static_cast<SerialFilter*>(filter);
  return ReturnCode::RETCODE_OK;
}

bool register_serial_filter(eprosima::fastdds::dds::DomainParticipant& participant) {
  // Never destroyed: Fast DDS's own singleton, destroyed after this file's statics, may still
  // delete filters of a participant left to it at exit.
  static auto* const factory = new SerialFilterFactory();
  return participant.register_content_filter_factory(kSerialFilterClass, factory) ==
         ReturnCode::RETCODE_OK;
}

}  // namespace teejet::dds
