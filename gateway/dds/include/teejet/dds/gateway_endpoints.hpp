#pragma once

// The gateway's DDS side: the Sink the bridge publishes through, and the command subscription
// that feeds it. Listeners only take samples and hand them on.

#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <functional>
#include <string>

#include "teejet/bridge/bridge.hpp"
#include "teejet/dds/participant.hpp"

namespace teejet::dds {

class GatewayPublisher final : public bridge::Sink {
 public:
  explicit GatewayPublisher(Participant& participant);

  void presence(const ValvePresence& sample) override;
  void telemetry(const bridge::TelemetrySample& sample) override;
  void error_cleared(std::uint32_t serial, ErrorKind kind) override;
  void command_status(const CommandStatus& status) override;
  void gateway_status(const GatewayStatus& status) override;

 private:
  using Writer = eprosima::fastdds::dds::DataWriter*;
  Writer presence_, version_, position_, temperature_, voltage_, current_, dps_, speed_, run_time_,
      cycle_count_, baud_rate_, error_, command_status_, gateway_status_;
};

// Identifies a command's writer in logs and in the fail-safe ("01.0f.ab...|0.0.1.3").
std::string writer_id(const eprosima::fastrtps::rtps::InstanceHandle_t& handle);

class CommandSubscription final : public eprosima::fastdds::dds::DataReaderListener {
 public:
  using CommandHandler = std::function<void(const ValveCommand&, const std::string& writer)>;
  using WriterLostHandler = std::function<void(const std::string& writer)>;

  CommandSubscription(Participant& participant, CommandHandler on_command,
                      WriterLostHandler on_writer_lost);

  void on_data_available(eprosima::fastdds::dds::DataReader* reader) override;
  void on_liveliness_changed(
      eprosima::fastdds::dds::DataReader* reader,
      const eprosima::fastdds::dds::LivelinessChangedStatus& status) override;

 private:
  CommandHandler on_command_;
  WriterLostHandler on_writer_lost_;
};

}  // namespace teejet::dds
