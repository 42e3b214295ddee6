#include "teejet/dds/participant.hpp"

#include <cstdlib>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <filesystem>
#include <mutex>
#include <set>
#include <sstream>

namespace teejet::dds {

using namespace eprosima::fastdds::dds;

class Participant::DiscoveryListener final : public DomainParticipantListener {
 public:
  explicit DiscoveryListener(std::function<void(const std::string&)> on_dropped)
      : on_dropped_(std::move(on_dropped)) {}

  void on_participant_discovery(
      DomainParticipant*, eprosima::fastrtps::rtps::ParticipantDiscoveryInfo&& info) override {
    if (info.status != eprosima::fastrtps::rtps::ParticipantDiscoveryInfo::DROPPED_PARTICIPANT) {
      return;
    }
    std::ostringstream prefix;
    prefix << info.info.m_guid.guidPrefix;
    on_dropped_(prefix.str());
  }

 private:
  std::function<void(const std::string&)> on_dropped_;
};

namespace {

std::string canonical(const std::string& path) {
  std::error_code ignored;
  const auto resolved = std::filesystem::weakly_canonical(path, ignored);
  return resolved.empty() ? path : resolved.string();
}

// Fast DDS keeps profiles process-wide and refuses a file it has loaded before (duplicate
// transport ids), so each file is loaded once per process, the environment's default included.
void load_profiles_once(const std::string& file) {
  static std::mutex mutex;
  static std::set<std::string> loaded;
  std::lock_guard lock(mutex);
  auto* factory = DomainParticipantFactory::get_instance();
  if (loaded.empty()) {
    // Profiles load lazily: without this, default QoS would ignore the XML defaults.
    factory->load_profiles();
    if (const char* fallback = std::getenv("FASTRTPS_DEFAULT_PROFILES_FILE")) {
      loaded.insert(canonical(fallback));
    }
    loaded.insert("");
  }
  if (loaded.contains(canonical(file))) return;
  if (factory->load_XML_profiles_file(file) != ReturnCode_t::RETCODE_OK) {
    throw DdsError("cannot load Fast DDS profiles from '" + file + "'");
  }
  loaded.insert(canonical(file));
}

}  // namespace

Participant::Participant(const ParticipantOptions& options) {
  auto* factory = DomainParticipantFactory::get_instance();
  load_profiles_once(options.profile_file);
  DomainParticipantQos qos = factory->get_default_participant_qos();
  qos.name(options.name);
  if (options.on_participant_dropped) {
    discovery_listener_ = std::make_unique<DiscoveryListener>(options.on_participant_dropped);
  }
  // Discovery callbacks ignore the mask; StatusMask::none() keeps the participant listener
  // from taking the readers' data-available callbacks.
  participant_ = factory->create_participant(static_cast<DomainId_t>(options.domain), qos,
                                             discovery_listener_.get(), StatusMask::none());
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
