#include "teejet/dds/participant.hpp"

#include <fastdds/rtps/transport/TCPTransportDescriptor.h>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastrtps/xmlparser/XMLProfileManager.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <fastdds/dds/log/Log.hpp>
#include <fastdds/dds/log/StdoutErrConsumer.hpp>
#include <filesystem>
#include <mutex>
#include <optional>
#include <set>
#include <sstream>
#include <vector>

#include "teejet/dds/serial_filter.hpp"

#if TEEJET_DDS_TYPE_OBJECTS
#include "teejet/valveTypeObject.h"
#endif

namespace teejet::dds {

using namespace eprosima::fastdds::dds;

class Participant::DiscoveryListener final : public DomainParticipantListener {
 public:
  explicit DiscoveryListener(std::function<void(const std::string&)> on_dropped)
      : on_dropped_(std::move(on_dropped)) {}

  void on_participant_discovery(
      DomainParticipant*, eprosima::fastrtps::rtps::ParticipantDiscoveryInfo&& info) override {
    using Status = eprosima::fastrtps::rtps::ParticipantDiscoveryInfo;
    const std::string participant = participant_text(info.info.m_guid.guidPrefix);
    if (info.status == Status::DISCOVERED_PARTICIPANT ||
        info.status == Status::CHANGED_QOS_PARTICIPANT) {
      std::string role;
      for (const auto& property : info.info.m_properties) {
        if (property.first() == kRoleProperty) role = property.second();
      }
      std::lock_guard lock(mutex_);
      roles_[participant] = role;
      return;
    }
    {
      std::lock_guard lock(mutex_);
      roles_.erase(participant);
    }
    if (info.status == Status::DROPPED_PARTICIPANT && on_dropped_) on_dropped_(participant);
  }

  std::size_t count() const {
    std::lock_guard lock(mutex_);
    return roles_.size();
  }

  std::set<std::string> with_role(std::string_view role) const {
    std::lock_guard lock(mutex_);
    std::set<std::string> found;
    for (const auto& [participant, announced] : roles_) {
      if (announced == role) found.insert(participant);
    }
    return found;
  }

 private:
  std::function<void(const std::string&)> on_dropped_;
  mutable std::mutex mutex_;
  std::map<std::string, std::string> roles_;  // every remote participant alive, by GUID prefix
};

namespace {

std::string canonical(const std::string& path) {
  std::error_code ignored;
  const auto resolved = std::filesystem::weakly_canonical(path, ignored);
  return resolved.empty() ? path : resolved.string();
}

Error refused(std::string what) { return Error{ErrorCode::kDds, std::move(what)}; }

namespace xml = eprosima::fastrtps::xmlparser;

// What Fast DDS 2.x reads by itself: the file the environment names (nullptr: none)...
const char* environment_profiles_file() {
  const char* file = std::getenv(xml::DEFAULT_FASTRTPS_ENV_VARIABLE);
  return file != nullptr && *file != '\0' ? file : nullptr;
}

// ... and ./DEFAULT_FASTRTPS_PROFILES.xml, unless SKIP_DEFAULT_XML_FILE=1.
bool reads_working_directory_profiles() {
  const char* skip = std::getenv(xml::SKIP_DEFAULT_XML_FILE);
  std::error_code error;
  return (skip == nullptr || skip[0] != '1') &&
         std::filesystem::exists(xml::DEFAULT_FASTRTPS_PROFILES, error);
}

// The files Fast DDS loads by itself before any of ours: the environment's and the working
// directory's (measured with 2.9.1: both, in that order); and Fast DDS 3's variable, which the
// tests set to the same file.
std::vector<std::string> files_fast_dds_loads_itself() {
  std::vector<std::string> files;
  if (const char* file = environment_profiles_file()) files.push_back(canonical(file));
  const char* later = std::getenv("FASTDDS_DEFAULT_PROFILES_FILE");
  if (later != nullptr && *later != '\0' &&
      std::find(files.begin(), files.end(), canonical(later)) == files.end()) {
    files.push_back(canonical(later));
  }
  if (reads_working_directory_profiles()) {
    files.push_back(canonical(xml::DEFAULT_FASTRTPS_PROFILES));
  }
  return files;
}

// Fast DDS 2.x loads FASTRTPS_DEFAULT_PROFILES_FILE and ./DEFAULT_FASTRTPS_PROFILES.xml by
// itself, and when it cannot it runs on its defaults — every interface, multicast, no
// DDS-Security — with nothing but a log line (measured: a missing file, garbage, /dev/null, a
// directory). Loaded here first, under the name Fast DDS will use, so that it finds them parsed
// (it keeps each file it parsed) and a file that does not load stops the program instead.
Status load_profiles_fast_dds_would_ignore() {
  using eprosima::fastrtps::xmlparser::XMLP_ret;
  using eprosima::fastrtps::xmlparser::XMLProfileManager;
  const auto load = [](const std::string& file, const std::string& named_by) -> Status {
    constexpr const char* kWouldRun =
        ": the program would run on Fast DDS's defaults (every interface, multicast, no "
        "DDS-Security)";
    std::error_code error;
    if (!std::filesystem::is_regular_file(file, error)) {
      const bool exists = std::filesystem::exists(file, error);
      return refused(named_by + " names '" + file + "', which " +
                     (exists ? "is not a regular file" : "does not exist") + kWouldRun +
                     "; name the profiles file or unset it");
    }
    if (XMLProfileManager::loadXMLFile(file) != XMLP_ret::XML_OK) {
      Log::Flush();  // its reasons first
      return refused("Fast DDS cannot load the profiles of " + named_by + " ('" + file +
                     "', the lines above say why)" + kWouldRun + "; mend the file or unset it");
    }
    return {};
  };
  if (const char* file = environment_profiles_file()) {
    if (auto loaded = load(file, xml::DEFAULT_FASTRTPS_ENV_VARIABLE); !loaded) return loaded;
  }
  if (reads_working_directory_profiles()) {
    return load(xml::DEFAULT_FASTRTPS_PROFILES, std::string("the working directory's ") +
                                                    xml::DEFAULT_FASTRTPS_PROFILES +
                                                    " (Fast DDS reads it)");
  }
  return {};
}

// Fast DDS keeps profiles process-wide and refuses a file it has loaded before (duplicate
// transport ids), so each file is loaded once per process, the environment's default included.
Status load_profiles_once(const std::string& file) {
  using eprosima::fastrtps::xmlparser::XMLP_ret;
  using eprosima::fastrtps::xmlparser::XMLProfileManager;
  static std::mutex mutex;
  static std::set<std::string> loaded;
  static std::vector<std::string> loaded_by_fast_dds;
  std::lock_guard lock(mutex);
  auto* factory = DomainParticipantFactory::get_instance();
  if (loaded.empty()) {
    if (auto checked = load_profiles_fast_dds_would_ignore(); !checked) return checked;
    // Profiles load lazily: without this, default QoS would ignore the XML defaults.
    factory->load_profiles();
    loaded_by_fast_dds = files_fast_dds_loads_itself();
    loaded.insert(loaded_by_fast_dds.begin(), loaded_by_fast_dds.end());
    loaded.insert("");
  }
  if (loaded.contains(canonical(file))) return {};
  // Not DomainParticipantFactory::load_XML_profiles_file: it calls a file OK when some of its
  // profiles were refused. A profile or transport whose name an earlier file took is dropped,
  // and the earlier file's default profile stays in force: `--profile secure.xml` would run
  // without security, with nothing but a log line to show it (measured).
  switch (XMLProfileManager::loadXMLFile(file)) {
    case XMLP_ret::XML_OK:
      break;
    case XMLP_ret::XML_NOK: {
      std::string earlier;
      for (const auto& other : loaded_by_fast_dds) earlier += (earlier.empty() ? "" : ", ") + other;
      return refused("Fast DDS refused part of the profiles in '" + file +
                     "': a profile or transport name in it is taken by a file loaded before it (" +
                     (earlier.empty() ? "another --profile" : earlier) +
                     "), whose settings would apply instead; rename them, or leave "
                     "FASTRTPS_DEFAULT_PROFILES_FILE unset");
    }
    case XMLP_ret::XML_ERROR:
      return refused("cannot load Fast DDS profiles from '" + file + "'");
  }
  // Fast DDS 2.9 reads the default participant profile only in load_profiles(): without this
  // reset, a file's is_default_profile would apply only when it is also the environment's.
  factory->set_default_participant_qos(PARTICIPANT_QOS_DEFAULT);
  loaded.insert(canonical(file));
  return {};
}

// Where the profiles in force came from, in the order Fast DDS lets them win.
std::string profile_source(const std::string& profile_file) {
  if (!profile_file.empty()) return "profile " + profile_file;
  if (const char* file = environment_profiles_file()) {
    return std::string("profile ") + file + " (" + xml::DEFAULT_FASTRTPS_ENV_VARIABLE + ")";
  }
  if (reads_working_directory_profiles()) {
    return "profile " + canonical(xml::DEFAULT_FASTRTPS_PROFILES) + " (the working directory's)";
  }
  return "Fast DDS's defaults (no profile: every interface, multicast)";
}

// The DDS-Security plugins a participant's properties ask for; empty when none.
std::string security_plugins(const DomainParticipantQos& qos) {
  std::string plugins;
  for (const auto& property : qos.properties().properties()) {
    for (const char* kind :
         {"dds.sec.auth.plugin", "dds.sec.access.plugin", "dds.sec.crypto.plugin"}) {
      if (property.name() == kind) {
        plugins += (plugins.empty() ? "" : ", ") + property.value();
      }
    }
  }
  return plugins;
}

// Process-wide set-up before the first participant, while no Fast DDS thread runs yet.
void prepare_process() {
  static std::once_flag once;
  std::call_once(once, [] {
    // Fast DDS logs to stdout by default; our programs' stdout carries data (valvectl --json).
    auto to_stderr = std::make_unique<eprosima::fastdds::dds::StdoutErrConsumer>();
    to_stderr->stderr_threshold(Log::Kind::Info);
    Log::ClearConsumers();
    Log::RegisterConsumer(std::move(to_stderr));
#if TEEJET_DDS_TYPE_OBJECTS
    // A remote COMPLETE TypeObject makes a receive thread use TypeObjectFactory; its first
    // use (the singleton's construction) must not race that.
    registervalveTypes();
#endif
  });
}

// The first participant id whose ports the initial peers of `qos` do not reach: Fast DDS 2.9
// announces to ids 0 up to its UDP transport's maxInitialPeersRange at an initial peer given
// without a port. None when no such peer is given (multicast discovery, a discovery server,
// explicit ports) or the profile sets the id itself.
std::optional<std::int32_t> first_id_beyond_initial_peers(const DomainParticipantQos& qos) {
  using eprosima::fastrtps::rtps::Locator_t;
  if (qos.wire_protocol().participant_id >= 0) return std::nullopt;
  const auto& peers = qos.wire_protocol().builtin.initialPeersList;
  const bool ranged = std::any_of(peers.begin(), peers.end(), [](const Locator_t& peer) {
    return (peer.kind == LOCATOR_KIND_UDPv4 || peer.kind == LOCATOR_KIND_UDPv6) && peer.port == 0;
  });
  if (!ranged) return std::nullopt;
  std::uint32_t range = 0;
  for (const auto& transport : qos.transport().user_transports) {
    range = std::max(range, transport->maxInitialPeersRange);
  }
  if (qos.transport().use_builtin_transports) {
    range =
        std::max(range, eprosima::fastdds::rtps::UDPv4TransportDescriptor().maxInitialPeersRange);
  }
  return static_cast<std::int32_t>(range);
}

// A participant id beyond the initial peers' range for each such participant of this process:
// Fast DDS refuses two participants of one process with the same id (another process's
// participant on the id's ports moves this one to the next free id's ports).
std::int32_t next_id_from(std::int32_t first) {
  constexpr int kIdsPerProcess = 16;
  static std::atomic<int> made{0};
  return first + made.fetch_add(1) % kIdsPerProcess;
}

}  // namespace

std::string participant_text(const eprosima::fastrtps::rtps::GuidPrefix_t& prefix) {
  std::ostringstream text;
  text << prefix;
  return text.str();
}

std::string participant_of(const eprosima::fastrtps::rtps::InstanceHandle_t& endpoint) {
  return participant_text(eprosima::fastrtps::rtps::iHandle2GUID(endpoint).guidPrefix);
}

Result<std::unique_ptr<Participant>> Participant::create(const ParticipantOptions& options) {
  // Fast DDS 2.9 ends the process (exit(1)) for a domain its port formula cannot map.
  if (options.domain < 0 || options.domain > kMaxDomain) {
    return Error{ErrorCode::kOutOfRange, "DDS domain " + std::to_string(options.domain) +
                                             " is outside 0 to " + std::to_string(kMaxDomain)};
  }
  prepare_process();
  auto* factory = DomainParticipantFactory::get_instance();
  if (auto loaded = load_profiles_once(options.profile_file); !loaded) return loaded.error();
  DomainParticipantQos qos = factory->get_default_participant_qos();
  qos.name(options.name);
  auto& lease = qos.wire_protocol().builtin.discovery_config.leaseDuration;
  if (lease < to_dds_duration(options.minimum_lease)) {
    lease = to_dds_duration(options.minimum_lease);
  }
  auto& announcement =
      qos.wire_protocol().builtin.discovery_config.leaseDuration_announcementperiod;
  const auto profile_announcement = from_dds_duration(announcement);
  const auto& transports = qos.transport().user_transports;
  const bool uses_tcp =
      std::any_of(transports.begin(), transports.end(), [](const auto& transport) {
        return std::dynamic_pointer_cast<eprosima::fastdds::rtps::TCPTransportDescriptor>(
                   transport) != nullptr;
      });
  // Over TCP an announcement is also what connects to an initial peer not yet reached.
  if (!uses_tcp && options.least_announcement_period > profile_announcement &&
      to_dds_duration(options.least_announcement_period) < lease) {
    announcement = to_dds_duration(options.least_announcement_period);
  }
  if (options.outside_initial_peers) {
    if (const auto first = first_id_beyond_initial_peers(qos)) {
      qos.wire_protocol().participant_id = next_id_from(*first);
    }
  }
  if (!options.role.empty()) {
    // Propagated: sent in the participant's discovery data, where any participant reads it.
    qos.properties().properties().emplace_back(kRoleProperty, options.role, true);
  }
  std::unique_ptr<Participant> made(new Participant());
  made->profile_announcement_ = profile_announcement;
  made->discovery_listener_ = std::make_unique<DiscoveryListener>(options.on_participant_dropped);
  // Discovery callbacks ignore the mask; StatusMask::none() keeps the participant listener
  // from taking the readers' data-available callbacks.
  made->participant_ =
      factory->create_participant(static_cast<DomainId_t>(options.domain), qos,
                                  made->discovery_listener_.get(), StatusMask::none());
  made->uses_tcp_ = uses_tcp;
  const std::string security = security_plugins(qos);
  made->setup_ = profile_source(options.profile_file) + "; DDS-Security " +
                 (security.empty() ? "off" : "on (" + security + ")");
  if (made->participant_ == nullptr) {
    std::string why = "cannot create a DDS participant in domain " +
                      std::to_string(options.domain) + " (" + made->setup_ + ")";
    if (!security.empty()) {
      Log::Flush();  // Fast DDS's SECURITY lines first: they name the check that failed
      why +=
          ": with DDS-Security the likely causes are this participant's certificate revoked "
          "in the CRL, expired or not yet valid, a key that is not the certificate's, an "
          "unreadable CRL or CA file, or permissions that do not grant this domain "
          "(docs/security.md)";
    }
    return refused(why);
  }
  if (!register_serial_filter(*made->participant_)) {
    return refused("cannot register the serial content filter");
  }
  made->publisher_ =
      made->participant_->create_publisher(made->participant_->get_default_publisher_qos());
  made->subscriber_ =
      made->participant_->create_subscriber(made->participant_->get_default_subscriber_qos());
  if (made->publisher_ == nullptr || made->subscriber_ == nullptr) {
    return refused("cannot create a DDS publisher or subscriber");
  }
  return made;
}

std::set<std::string> Participant::participants_with_role(std::string_view role) const {
  return discovery_listener_->with_role(role);
}

std::size_t Participant::participants_met() const { return discovery_listener_->count(); }

bool Participant::discovery_settled() const {
  const auto quiet = std::min<std::chrono::steady_clock::duration>(2 * profile_announcement_,
                                                                   std::chrono::seconds(1));
  return std::chrono::steady_clock::now() - created_ >= quiet;
}

namespace {

// Fast DDS 2.9.1 deletes a writer by returning each sample of its history to the pool, the
// writer's lock taken and released for each, before it clears the history and stops its
// periodic heartbeat. A heartbeat that fires in between (its timer runs while a reader has not
// acknowledged everything) walks a history whose first samples now say sequence number 0 and
// looks for the holes between them forever, holding the writer's lock: the deletion waits for it
// and the participant's timers (announcements, heartbeats, lease checks) stop. Upstream moved
// the loop under the lock in 2.14. An empty history leaves the loop nothing to release.
void empty_history(DataWriter* writer) { (void)writer->clear_history(nullptr); }

}  // namespace

Participant::~Participant() {
  if (participant_ == nullptr) return;
  std::vector<DataWriter*> writers;
  if (publisher_ != nullptr && publisher_->get_datawriters(writers)) {
    for (DataWriter* writer : writers) empty_history(writer);
  }
  participant_->delete_contained_entities();
  DomainParticipantFactory::get_instance()->delete_participant(participant_);
}

Result<Topic*> Participant::topic(const std::string& name, TypeSupport type) {
  if (auto it = topics_.find(name); it != topics_.end()) return it->second;
  if (type.register_type(participant_) != ReturnCode_t::RETCODE_OK &&
      participant_->find_type(type.get_type_name()).empty()) {
    return refused("cannot register DDS type " + type.get_type_name());
  }
  Topic* topic =
      participant_->create_topic(name, type.get_type_name(), participant_->get_default_topic_qos());
  if (topic == nullptr) return refused("cannot create DDS topic " + name);
  topics_.emplace(name, topic);
  return topic;
}

Result<DataWriter*> Participant::writer(Topic* topic, const DataWriterQos& qos,
                                        DataWriterListener* listener) {
  DataWriter* writer = publisher_->create_datawriter(topic, qos, listener);
  if (writer == nullptr) return refused("cannot create a writer for " + topic->get_name());
  return writer;
}

Result<DataReader*> Participant::reader(TopicDescription* topic, const DataReaderQos& qos,
                                        DataReaderListener* listener, const StatusMask& mask) {
  DataReader* reader = subscriber_->create_datareader(
      topic, qos, listener, listener == nullptr ? StatusMask::none() : mask);
  if (reader == nullptr) return refused("cannot create a reader for " + topic->get_name());
  return reader;
}

Result<DataReader*> Participant::reader_of_serials(Topic* topic,
                                                   const std::set<std::uint32_t>& serials,
                                                   const DataReaderQos& qos) {
  const std::string expression = serial_filter_expression(serials);
  const std::string name = topic->get_name() + " serials " + expression;
  auto it = filtered_topics_.find(name);
  if (it == filtered_topics_.end()) {
    auto* filtered =
        participant_->create_contentfilteredtopic(name, topic, expression, {}, kSerialFilterClass);
    if (filtered == nullptr) return refused("cannot filter " + topic->get_name() + " by serial");
    it = filtered_topics_.emplace(name, filtered).first;
  }
  return reader(it->second, qos);
}

void Participant::delete_reader(DataReader* reader) {
  if (reader == nullptr) return;
  reader->set_listener(nullptr);
  subscriber_->delete_datareader(reader);
}

std::size_t Participant::readers_of(const std::string& topic_name) const {
  std::vector<DataReader*> readers;
  subscriber_->get_datareaders(readers);
  return static_cast<std::size_t>(
      std::count_if(readers.begin(), readers.end(), [&topic_name](const DataReader* reader) {
        return reader->get_topicdescription()->get_name() == topic_name;
      }));
}

void Participant::delete_writer(DataWriter* writer) {
  if (writer == nullptr) return;
  empty_history(writer);
  publisher_->delete_datawriter(writer);
}

}  // namespace teejet::dds
