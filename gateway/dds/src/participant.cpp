#include "teejet/dds/participant.hpp"

#include <fastdds/dds/domain/DomainParticipantFactory.hpp>

namespace teejet::dds {

using namespace eprosima::fastdds::dds;

Participant::Participant(const ParticipantOptions& options) {
  auto* factory = DomainParticipantFactory::get_instance();
  if (!options.profile_file.empty() &&
      factory->load_XML_profiles_file(options.profile_file) != ReturnCode_t::RETCODE_OK) {
    throw DdsError("cannot load Fast DDS profiles from '" + options.profile_file + "'");
  }
  // Profiles load lazily: without this, the default QoS below ignores the XML defaults.
  factory->load_profiles();
  DomainParticipantQos qos = factory->get_default_participant_qos();
  qos.name(options.name);
  participant_ = factory->create_participant(static_cast<DomainId_t>(options.domain), qos);
  if (participant_ == nullptr) {
    throw DdsError("cannot create a DDS participant in domain " + std::to_string(options.domain));
  }
  publisher_ = participant_->create_publisher(participant_->get_default_publisher_qos());
  subscriber_ = participant_->create_subscriber(participant_->get_default_subscriber_qos());
  if (publisher_ == nullptr || subscriber_ == nullptr) {
    factory->delete_participant(participant_);
    throw DdsError("cannot create a DDS publisher or subscriber");
  }
}

Participant::~Participant() {
  participant_->delete_contained_entities();
  DomainParticipantFactory::get_instance()->delete_participant(participant_);
}

Topic* Participant::topic(const std::string& name, TypeSupport type) {
  if (auto it = topics_.find(name); it != topics_.end()) return it->second;
  if (type.register_type(participant_) != ReturnCode_t::RETCODE_OK &&
      participant_->find_type(type.get_type_name()).empty()) {
    throw DdsError("cannot register DDS type " + type.get_type_name());
  }
  Topic* topic =
      participant_->create_topic(name, type.get_type_name(), participant_->get_default_topic_qos());
  if (topic == nullptr) throw DdsError("cannot create DDS topic " + name);
  topics_.emplace(name, topic);
  return topic;
}

DataWriter* Participant::writer(Topic* topic, const DataWriterQos& qos,
                                DataWriterListener* listener) {
  DataWriter* writer = publisher_->create_datawriter(topic, qos, listener);
  if (writer == nullptr) throw DdsError("cannot create a writer for " + topic->get_name());
  return writer;
}

DataReader* Participant::reader(Topic* topic, const DataReaderQos& qos,
                                DataReaderListener* listener) {
  // A narrow mask: the listener gets only what it overrides, never swallowing data callbacks.
  const StatusMask mask = listener == nullptr
                              ? StatusMask::none()
                              : StatusMask::data_available() << StatusMask::liveliness_changed();
  DataReader* reader = subscriber_->create_datareader(topic, qos, listener, mask);
  if (reader == nullptr) throw DdsError("cannot create a reader for " + topic->get_name());
  return reader;
}

}  // namespace teejet::dds
