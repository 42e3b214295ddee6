// Fast DDS 2.9.1's participant-lease race, played on purpose (bench/run-lease-race).
//
//   lease_race victim --endpoints K
//       one participant with K reliable readers and writers; prints "ready" and lives until
//       SIGTERM (exit 0). If Fast DDS aborts in PDP.cpp's check_remote_participant_liveliness,
//       the bench sees SIGABRT.
//   lease_race peers --participants N --lease-s L --endpoints K --write-period-ms P
//       N participants announcing an L s lease, each with K readers and writers that write every
//       P ms; prints "ready", and on each line read from stdin all of them leave at once
//       ("left") and N new ones are made ("ready") until stdin ends.
//
// A peer's goodbye is handled on the victim's receive thread while its lease check may fire
// on the event thread: when that check waits for the discovery mutex until the goodbye's
// removal has recycled the peer's record, Fast DDS asserts (docs/performance.md, "A peer's
// lease checked as it leaves").

#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/TopicDataType.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <iostream>
#include <string>
#include <thread>
#include <vector>

namespace {

using namespace eprosima::fastdds::dds;
using eprosima::fastrtps::rtps::InstanceHandle_t;
using eprosima::fastrtps::rtps::SerializedPayload_t;

constexpr std::uint32_t kSampleBytes = 4;

// Four zero bytes: the race is in discovery, what the samples hold does not matter.
class Opaque final : public TopicDataType {
 public:
  Opaque() {
    setName("lease_race::Opaque");
    m_typeSize = kSampleBytes + 4;  // and the encapsulation header
    m_isGetKeyDefined = false;
  }
  bool serialize(void*, SerializedPayload_t* payload) override {
    payload->length = kSampleBytes;
    std::memset(payload->data, 0, kSampleBytes);
    return true;
  }
  bool deserialize(SerializedPayload_t*, void*) override { return true; }
  std::function<std::uint32_t()> getSerializedSizeProvider(void*) override {
    return [] { return kSampleBytes + 4; };
  }
  void* createData() override { return new char[kSampleBytes]; }
  void deleteData(void* data) override { delete[] static_cast<char*>(data); }
  bool getKey(void*, InstanceHandle_t*, bool) override { return false; }
};

DomainParticipant* make_participant(std::int32_t lease_s) {
  auto* factory = DomainParticipantFactory::get_instance();
  DomainParticipantQos qos = factory->get_default_participant_qos();
  if (lease_s > 0) {
    qos.wire_protocol().builtin.discovery_config.leaseDuration =
        eprosima::fastrtps::Duration_t(lease_s, 0);
  }
  return factory->create_participant(0, qos);
}

// K reliable readers and writers on topics t0 … t(K-1), the same in every process, so that
// each peer's endpoints are matched with the victim's and its removal has them to unpair.
bool add_endpoints(DomainParticipant* participant, int count, std::vector<DataWriter*>& writers) {
  TypeSupport type(new Opaque());
  if (type.register_type(participant) != ReturnCode_t::RETCODE_OK) return false;
  Publisher* publisher = participant->create_publisher(PUBLISHER_QOS_DEFAULT);
  Subscriber* subscriber = participant->create_subscriber(SUBSCRIBER_QOS_DEFAULT);
  if (publisher == nullptr || subscriber == nullptr) return false;
  for (int i = 0; i < count; ++i) {
    Topic* topic =
        participant->create_topic("t" + std::to_string(i), type.get_type_name(), TOPIC_QOS_DEFAULT);
    DataWriterQos writer_qos = DATAWRITER_QOS_DEFAULT;
    writer_qos.reliability().kind = RELIABLE_RELIABILITY_QOS;
    DataReaderQos reader_qos = DATAREADER_QOS_DEFAULT;
    reader_qos.reliability().kind = RELIABLE_RELIABILITY_QOS;
    DataWriter* writer = topic ? publisher->create_datawriter(topic, writer_qos) : nullptr;
    if (writer == nullptr || subscriber->create_datareader(topic, reader_qos) == nullptr) {
      return false;
    }
    writers.push_back(writer);
  }
  return true;
}

void leave(DomainParticipant* participant) {
  participant->delete_contained_entities();
  DomainParticipantFactory::get_instance()->delete_participant(participant);
}

void say(const char* line) {
  std::printf("%s\n", line);
  std::fflush(stdout);
}

volatile std::sig_atomic_t g_stop = 0;

int run_victim(int endpoints) {
  std::signal(SIGTERM, [](int) { g_stop = 1; });
  DomainParticipant* participant = make_participant(0);
  std::vector<DataWriter*> writers;
  if (participant == nullptr || !add_endpoints(participant, endpoints, writers)) {
    std::fprintf(stderr, "lease_race victim: cannot make its participant or endpoints\n");
    return 3;
  }
  say("ready");
  while (g_stop == 0) pause();
  leave(participant);
  return 0;
}

int run_peers(int participants, int lease_s, int endpoints, int write_period_ms) {
  std::string line;
  for (;;) {
    std::vector<DomainParticipant*> made;
    std::vector<DataWriter*> writers;
    for (int i = 0; i < participants; ++i) {
      made.push_back(make_participant(lease_s));
      if (made.back() == nullptr || !add_endpoints(made.back(), endpoints, writers)) {
        std::fprintf(stderr, "lease_race peers: cannot make participant %d\n", i);
        return 3;
      }
    }
    std::atomic<bool> writing{true};
    std::thread writer([&] {
      char sample[kSampleBytes] = {};
      while (writing) {
        for (DataWriter* w : writers) w->write(sample);
        std::this_thread::sleep_for(std::chrono::milliseconds(write_period_ms));
      }
    });
    say("ready");
    const bool asked = static_cast<bool>(std::getline(std::cin, line));
    writing = false;
    writer.join();
    for (DomainParticipant* participant : made) leave(participant);
    if (!asked) return 0;
    say("left");
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Fast DDS's participant-lease race, played on purpose (bench/run-lease-race)"};
  app.require_subcommand(1);
  int endpoints = 6;
  int participants = 10;
  int lease_s = 3;
  int write_period_ms = 5;
  CLI::App* victim = app.add_subcommand("victim", "one participant that outlives the peers");
  victim->add_option("--endpoints", endpoints, "reliable readers and writers")
      ->capture_default_str();
  CLI::App* peers = app.add_subcommand("peers", "participants that leave on each line of stdin");
  peers->add_option("--participants", participants)->capture_default_str();
  peers->add_option("--lease-s", lease_s, "the participant lease they announce")
      ->capture_default_str();
  peers->add_option("--endpoints", endpoints)->capture_default_str();
  peers->add_option("--write-period-ms", write_period_ms)->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  // The profile named by FASTRTPS_DEFAULT_PROFILES_FILE (the loopback profile: 3 s lease,
  // 250 ms announcements) before the first QoS is read.
  DomainParticipantFactory::get_instance()->load_profiles();
  if (*victim) return run_victim(endpoints);
  return run_peers(participants, lease_s, endpoints, write_period_ms);
}
