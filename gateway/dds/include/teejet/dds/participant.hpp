#pragma once

// One DomainParticipant with one publisher and one subscriber, set up as in eProsima's
// examples (factory -> participant -> register type -> topic -> writer/reader) and torn down in
// reverse. Shared by the gateway, valvectl and the tests.

#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <functional>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>

namespace teejet::dds {

struct ParticipantOptions {
  int domain = 0;
  std::string profile_file;  // Fast DDS XML profiles, loaded before any default QoS is read
  std::string name = "teejet";
  // Called with a remote participant's GUID prefix ("01.0f.…") when its lease expired: the
  // process died or became unreachable. A participant that leaves in order is not reported.
  std::function<void(const std::string& guid_prefix)> on_participant_dropped;
};

class DdsError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class Participant {
 public:
  explicit Participant(const ParticipantOptions& options);  // throws DdsError with the reason
  ~Participant();
  Participant(const Participant&) = delete;
  Participant& operator=(const Participant&) = delete;

  // The topic of `name`, registering the type on first use. PubSubType is a fastddsgen
  // <Type>PubSubType.
  template <class PubSubType>
  eprosima::fastdds::dds::Topic* topic(const std::string& name) {
    return topic(name, eprosima::fastdds::dds::TypeSupport(new PubSubType()));
  }

  eprosima::fastdds::dds::DataWriter* writer(
      eprosima::fastdds::dds::Topic* topic, const eprosima::fastdds::dds::DataWriterQos& qos,
      eprosima::fastdds::dds::DataWriterListener* listener = nullptr);
  eprosima::fastdds::dds::DataReader* reader(
      eprosima::fastdds::dds::Topic* topic, const eprosima::fastdds::dds::DataReaderQos& qos,
      eprosima::fastdds::dds::DataReaderListener* listener = nullptr);

  eprosima::fastdds::dds::DomainParticipant* get() const { return participant_; }

 private:
  eprosima::fastdds::dds::Topic* topic(const std::string& name,
                                       eprosima::fastdds::dds::TypeSupport type);

  class DiscoveryListener;
  std::unique_ptr<DiscoveryListener> discovery_listener_;
  eprosima::fastdds::dds::DomainParticipant* participant_ = nullptr;
  eprosima::fastdds::dds::Publisher* publisher_ = nullptr;
  eprosima::fastdds::dds::Subscriber* subscriber_ = nullptr;
  std::map<std::string, eprosima::fastdds::dds::Topic*> topics_;
};

}  // namespace teejet::dds
