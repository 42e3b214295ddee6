#pragma once

// A DDS participant playing an ECU, a bench or a logger in tests: reads any topic of the contract,
// writes commands once a gateway listens, follows their statuses. Its command endpoints exist
// from its first command on, so a peer that only reads is a reader only. A refusal of DDS fails
// the test.

#include <chrono>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "teejet/dds/participant.hpp"
#include "teejet/dds/topics.hpp"

namespace teejet::testing {

class DdsPeer {
 public:
  DdsPeer(int domain, const std::string& name);  // ADD_FAILURE()s when DDS refuses

  dds::Participant& participant() { return *participant_; }

  // A reader of Sample's topic (state QoS by default); nullptr after a failure.
  template <class Sample>
  eprosima::fastdds::dds::DataReader* reader(
      const eprosima::fastdds::dds::DataReaderQos& qos = dds::topics::state_reader_qos(),
      eprosima::fastdds::dds::DataReaderListener* listener = nullptr) {
    auto topic = dds::topics::topic_of<Sample>(*participant_);
    if (!topic) return refused(topic.error());
    auto made = participant_->reader(*topic, qos, listener);
    if (!made) return refused(made.error());
    return *made;
  }

  // Writes `command` with the next command_id and this peer's origin once at least one
  // gateway's command reader matched; returns the id.
  std::uint32_t send(ValveCommand command);
  // The same without waiting for a gateway: for racing one. False when the write failed.
  bool write(ValveCommand command);

  // The statuses of command `id`, in order, once one is final (or when `deadline` passes).
  std::vector<CommandStatus> follow(std::uint32_t id,
                                    std::chrono::milliseconds deadline = std::chrono::seconds(15));

  static std::vector<CommandState> states(const std::vector<CommandStatus>& statuses);

 private:
  static std::nullptr_t refused(const Error& error);  // fails the test
  bool command_endpoints();                           // made on first use; false after a failure

  const std::string origin_;  // "test-peer:<name>:<n>", unique in the process
  std::unique_ptr<dds::Participant> participant_;
  eprosima::fastdds::dds::DataWriter* commands_ = nullptr;
  eprosima::fastdds::dds::DataReader* statuses_ = nullptr;
  std::vector<CommandStatus> all_statuses_;
  std::uint32_t next_id_ = 0;
};

// Takes every sample `reader` has and keeps the newest per key_of(sample) in `seen`; returns
// `seen`.
template <class Key, class Sample, class KeyOf>
std::map<Key, Sample>& latest_by(eprosima::fastdds::dds::DataReader* reader,
                                 std::map<Key, Sample>& seen, KeyOf key_of) {
  Sample sample;
  eprosima::fastdds::dds::SampleInfo info;
  while (reader->take_next_sample(&sample, &info) ==
         eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK) {
    if (info.valid_data) seen[key_of(sample)] = sample;
  }
  return seen;
}

template <class Sample>
std::map<std::uint32_t, Sample>& latest_by_serial(eprosima::fastdds::dds::DataReader* reader,
                                                  std::map<std::uint32_t, Sample>& seen) {
  return latest_by(reader, seen, [](const Sample& sample) { return sample.serial(); });
}

}  // namespace teejet::testing
