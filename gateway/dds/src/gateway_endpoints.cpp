#include "teejet/dds/gateway_endpoints.hpp"

#include <fastdds/rtps/common/Guid.h>
#include <spdlog/spdlog.h>

#include <atomic>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <sstream>

#include "teejet/dds/topics.hpp"
#include "teejet/valvePubSubTypes.h"

namespace teejet::dds {

using namespace eprosima::fastdds::dds;

namespace {

template <class PubSubType>
DataWriter* state_writer(Participant& participant, const char* name) {
  return participant.writer(participant.topic<PubSubType>(name), topics::state_writer_qos());
}

// A failed write loses a sample that consumers expect: say so, without flooding the log.
void report(DataWriter* writer, const ReturnCode_t& result) {
  if (result == ReturnCode_t::RETCODE_OK) return;
  static std::atomic<std::uint64_t> failures{0};
  const auto count = ++failures;
  if (count == 1 || count % 1000 == 0) {
    spdlog::error("DDS write on {} failed (code {}); {} failed write(s) so far",
                  writer->get_topic()->get_name(), result(), count);
  }
}

// Samples carry the CAN receive time as their DDS source timestamp too.
template <class Sample>
void write_stamped(DataWriter* writer, Sample sample, std::uint64_t stamp_ns) {
  const eprosima::fastrtps::Time_t stamp(static_cast<std::int32_t>(stamp_ns / 1'000'000'000),
                                         static_cast<std::uint32_t>(stamp_ns % 1'000'000'000));
  report(writer, writer->write_w_timestamp(&sample, HANDLE_NIL, stamp));
}

}  // namespace

GatewayPublisher::GatewayPublisher(Participant& participant)
    : presence_(state_writer<ValvePresencePubSubType>(participant, topics::kPresence)),
      version_(state_writer<ValveVersionPubSubType>(participant, topics::kVersion)),
      position_(state_writer<ValvePositionPubSubType>(participant, topics::kPosition)),
      temperature_(state_writer<ValveTemperaturePubSubType>(participant, topics::kTemperature)),
      voltage_(state_writer<ValveVoltagePubSubType>(participant, topics::kVoltage)),
      current_(state_writer<ValveCurrentPubSubType>(participant, topics::kCurrent)),
      dps_(state_writer<ValveDegreesPerSecondPubSubType>(participant, topics::kDegreesPerSecond)),
      speed_(state_writer<ValveSpeedDirectionPubSubType>(participant, topics::kSpeedDirection)),
      run_time_(state_writer<ValveRunTimePubSubType>(participant, topics::kRunTime)),
      cycle_count_(state_writer<ValveCycleCountPubSubType>(participant, topics::kCycleCount)),
      baud_rate_(state_writer<ValveBaudRatePubSubType>(participant, topics::kBaudRate)),
      error_(state_writer<ValveErrorPubSubType>(participant, topics::kError)),
      command_status_(
          participant.writer(participant.topic<CommandStatusPubSubType>(topics::kCommandStatus),
                             topics::status_writer_qos())),
      gateway_status_(state_writer<GatewayStatusPubSubType>(participant, topics::kGatewayStatus)) {}

void GatewayPublisher::presence(const ValvePresence& sample) {
  write_stamped(presence_, sample, sample.last_seen_ns());
}

void GatewayPublisher::telemetry(const bridge::TelemetrySample& sample) {
  std::visit(
      [this](const auto& s) {
        using T = std::decay_t<decltype(s)>;
        DataWriter* writer = nullptr;
        if constexpr (std::is_same_v<T, ValveVersion>) writer = version_;
        if constexpr (std::is_same_v<T, ValvePosition>) writer = position_;
        if constexpr (std::is_same_v<T, ValveTemperature>) writer = temperature_;
        if constexpr (std::is_same_v<T, ValveVoltage>) writer = voltage_;
        if constexpr (std::is_same_v<T, ValveCurrent>) writer = current_;
        if constexpr (std::is_same_v<T, ValveDegreesPerSecond>) writer = dps_;
        if constexpr (std::is_same_v<T, ValveSpeedDirection>) writer = speed_;
        if constexpr (std::is_same_v<T, ValveRunTime>) writer = run_time_;
        if constexpr (std::is_same_v<T, ValveCycleCount>) writer = cycle_count_;
        if constexpr (std::is_same_v<T, ValveBaudRate>) writer = baud_rate_;
        if constexpr (std::is_same_v<T, ValveError>) writer = error_;
        write_stamped(writer, s, s.received_ns());
      },
      sample);
}

void GatewayPublisher::error_cleared(std::uint32_t serial, ErrorKind kind) {
  ValveError key;
  key.serial(serial);
  key.kind(kind);
  report(error_, error_->dispose(&key, HANDLE_NIL));
}

void GatewayPublisher::command_status(const CommandStatus& status) {
  CommandStatus copy = status;
  report(command_status_,
         command_status_->write(&copy) ? ReturnCode_t::RETCODE_OK : ReturnCode_t::RETCODE_ERROR);
}

void GatewayPublisher::gateway_status(const GatewayStatus& status) {
  GatewayStatus copy = status;
  report(gateway_status_,
         gateway_status_->write(&copy) ? ReturnCode_t::RETCODE_OK : ReturnCode_t::RETCODE_ERROR);
}

std::string writer_id(const eprosima::fastrtps::rtps::InstanceHandle_t& handle) {
  std::ostringstream text;
  text << eprosima::fastrtps::rtps::iHandle2GUID(handle);
  return text.str();
}

CommandSubscription::CommandSubscription(Participant& participant, CommandHandler on_command,
                                         WriterLostHandler on_writer_lost)
    : on_command_(std::move(on_command)), on_writer_lost_(std::move(on_writer_lost)) {
  participant.reader(participant.topic<ValveCommandPubSubType>(topics::kCommand),
                     topics::command_reader_qos(), this);
}

void CommandSubscription::on_data_available(DataReader* reader) {
  ValveCommand command;
  SampleInfo info;
  while (reader->take_next_sample(&command, &info) == ReturnCode_t::RETCODE_OK) {
    if (info.valid_data) on_command_(command, writer_id(info.publication_handle));
  }
}

void CommandSubscription::on_liveliness_changed(DataReader*,
                                                const LivelinessChangedStatus& status) {
  if (status.not_alive_count_change > 0) on_writer_lost_(writer_id(status.last_publication_handle));
}

}  // namespace teejet::dds
