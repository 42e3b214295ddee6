#pragma once

// A content filter on a valve's serial, so that a reader of a telemetry topic keeps the samples of
// the valves it names and no others: the rest are dropped as they arrive, before they are
// deserialized, stored or handed to a listener. Every participant made by dds::Participant
// registers it. Fast DDS 2.9.1 filters on the writer's side only for writers without a liveliness
// lease, and the gateway's state writers have one (3 s, how a dead gateway is noticed): a gateway
// still sends a filtered reader every sample, and the reader's host still receives them.
//
// Filter class kSerialFilterClass; its expression is the serials in decimal, separated by spaces
// ("1 200005"). It reads the serial where every keyed valve type of the contract has it: its
// first member, `@key uint32 serial`, right after the CDR encapsulation (tests/dds check that for
// presence and every telemetry type). A sample in another representation passes.

#include <cstdint>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/topic/IContentFilter.hpp>
#include <fastdds/dds/topic/IContentFilterFactory.hpp>
#include <optional>
#include <set>
#include <string>
#include <string_view>

namespace teejet::dds {

inline constexpr const char* kSerialFilterClass = "TEEJET_SERIALS";

// "1 200005" for {1, 200005}.
std::string serial_filter_expression(const std::set<std::uint32_t>& serials);
// The serials of an expression; nullopt for anything but decimal serials separated by spaces.
std::optional<std::set<std::uint32_t>> parse_serial_filter(std::string_view expression);

// The serial a serialized sample of the contract's keyed valve types carries; nullopt when the
// payload is shorter or in a representation other than plain CDR.
std::optional<std::uint32_t> serial_of(
    const eprosima::fastrtps::rtps::SerializedPayload_t& payload);

// Fast DDS's filter interfaces have no virtual destructor; ours are final and deleted as
// themselves (SerialFilterFactory::delete_content_filter).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wnon-virtual-dtor"
class SerialFilter final : public eprosima::fastdds::dds::IContentFilter {
 public:
  explicit SerialFilter(std::set<std::uint32_t> serials) : serials_(std::move(serials)) {}
  bool evaluate(const SerializedPayload& payload, const FilterSampleInfo& sample_info,
                const GUID_t& reader_guid) const override;

 private:
  std::set<std::uint32_t> serials_;
};

class SerialFilterFactory final : public eprosima::fastdds::dds::IContentFilterFactory {
 public:
  ReturnCode_t create_content_filter(const char* filter_class_name, const char* type_name,
                                     const eprosima::fastdds::dds::TopicDataType* data_type,
                                     const char* filter_expression,
                                     const ParameterSeq& filter_parameters,
                                     eprosima::fastdds::dds::IContentFilter*& filter) override;
  ReturnCode_t delete_content_filter(const char* filter_class_name,
                                     eprosima::fastdds::dds::IContentFilter* filter) override;
};

#pragma GCC diagnostic pop

// Registers the filter with `participant` (once per participant; the factory lives as long as
// the process).
bool register_serial_filter(eprosima::fastdds::dds::DomainParticipant& participant);

}  // namespace teejet::dds
