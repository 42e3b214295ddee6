#include "support/dds_peer.hpp"

#include <gtest/gtest.h>

#include <atomic>

#include "support/eventually.hpp"

namespace teejet::testing {

using eprosima::fastdds::dds::PublicationMatchedStatus;
using eprosima::fastdds::dds::SampleInfo;
using ReturnCode = eprosima::fastrtps::types::ReturnCode_t;

std::nullptr_t DdsPeer::refused(const Error& error) {
  ADD_FAILURE() << "DDS refused: " << error.reason;
  return nullptr;
}

namespace {

// Statuses are TRANSIENT_LOCAL: each peer has an origin of its own, so that a peer never takes
// an earlier peer's statuses (same command ids) for its own.
std::string unique_origin(const std::string& name) {
  static std::atomic<int> peers{0};
  return "test-peer:" + name + ":" + std::to_string(++peers);
}

}  // namespace

DdsPeer::DdsPeer(int domain, const std::string& name) : origin_(unique_origin(name)) {
  auto made = dds::Participant::create({.domain = domain, .name = name});
  if (!made) {
    ADD_FAILURE() << "DDS refused: " << made.error().reason;
    return;
  }
  participant_ = std::move(*made);
}

bool DdsPeer::command_endpoints() {
  if (commands_ != nullptr) return true;
  if (!participant_) return false;
  const auto refused = [](const Error& error) {
    ADD_FAILURE() << "DDS refused: " << error.reason;
    return false;
  };
  auto commands = participant_->topic<ValveCommandPubSubType>(dds::topics::kCommand);
  if (!commands) return refused(commands.error());
  auto statuses = participant_->topic<CommandStatusPubSubType>(dds::topics::kCommandStatus);
  if (!statuses) return refused(statuses.error());
  // The status reader first: a gateway that matched the command writer has matched it too.
  auto reader = participant_->reader(*statuses, dds::topics::status_reader_qos());
  if (!reader) return refused(reader.error());
  statuses_ = *reader;
  auto writer = participant_->writer(*commands, dds::topics::command_writer_qos());
  if (!writer) return refused(writer.error());
  commands_ = *writer;
  return true;
}

bool DdsPeer::write(ValveCommand command) {
  command.command_id(++next_id_);
  command.origin(origin_);
  return command_endpoints() && commands_->write(&command);
}

std::uint32_t DdsPeer::send(ValveCommand command) {
  command.command_id(++next_id_);
  command.origin(origin_);
  if (!command_endpoints()) return command.command_id();
  EXPECT_TRUE(eventually(
      [&] {
        PublicationMatchedStatus matched;
        commands_->get_publication_matched_status(matched);
        return matched.current_count > 0;
      },
      std::chrono::seconds(15)))
      << "no gateway's command reader matched";
  EXPECT_TRUE(commands_->write(&command));
  return command.command_id();
}

std::vector<CommandStatus> DdsPeer::follow(std::uint32_t id, std::chrono::milliseconds deadline) {
  std::vector<CommandStatus> mine;
  if (statuses_ == nullptr) return mine;
  eventually(
      [&] {
        CommandStatus status;
        SampleInfo info;
        while (statuses_->take_next_sample(&status, &info) == ReturnCode::RETCODE_OK) {
          if (info.valid_data) all_statuses_.push_back(status);
        }
        mine.clear();
        for (const auto& s : all_statuses_) {
          if (s.command_id() == id && s.origin().to_string() == origin_) mine.push_back(s);
        }
        return !mine.empty() && mine.back().state() != COMMAND_ACCEPTED;
      },
      deadline);
  return mine;
}

std::vector<CommandState> DdsPeer::states(const std::vector<CommandStatus>& statuses) {
  std::vector<CommandState> out;
  for (const auto& s : statuses) out.push_back(s.state());
  return out;
}

}  // namespace teejet::testing
