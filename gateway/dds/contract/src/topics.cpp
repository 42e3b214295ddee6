#include "teejet/dds/topics.hpp"

#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <type_traits>

namespace teejet::dds::topics {

using namespace eprosima::fastdds::dds;

namespace {

const eprosima::fastrtps::Duration_t kCommandLease{2, 0};
// A gateway that dies without a word (SIGKILL, power, a cut cable) loses the liveliness of its
// state writers 3 s later, and clients show its valves as unknown instead of frozen and online.
// A reader asking for no liveliness (DDS's default: infinite) still matches.
const eprosima::fastrtps::Duration_t kStateLease{3, 0};
const eprosima::fastrtps::Duration_t kStateAnnouncement{1, 0};

// Explicit bounds, so that memory is predictable. Fast DDS's default of 10 instances per topic
// silently dropped the 11th valve of a bus (and would refuse commands for it); 4096 instances
// cover 32 valves per bus on many gateways, and the six error kinds of each. (Fast DDS 2.9
// spells "infinite" 0 here, and refuses every write with LENGTH_UNLIMITED.)
constexpr std::int32_t kMaxInstances = 4096;
constexpr std::int32_t kCommandsQueuedPerValve = 256;
// What the gateway's command reader may hold per valve before it takes them. Far more than one
// writer's queue: Fast DDS 2.9.1 stalls a writer for good once a KEEP_ALL reader refuses one of
// its samples for a full instance (measured: 10,000 commands in 1 s to one valve, reader limit
// 256 like the writer's: the last 256 never arrived in 30 s and every later write timed out;
// with 4096 all 10,000 arrived within 1.24 s). Memory grows only with what is waiting, and the
// gateway takes commands as they come.
constexpr std::int32_t kCommandsHeldPerValve = 4096;

const eprosima::fastrtps::Duration_t kInitialAcknackDelay{0, 5'000'000};
const eprosima::fastrtps::Duration_t kStateHeartbeat{0, 200'000'000};

template <class Qos>
Qos reliable(DurabilityQosPolicyKind durability, HistoryQosPolicyKind history, int depth) {
  Qos qos;
  qos.reliability().kind = RELIABLE_RELIABILITY_QOS;
  qos.durability().kind = durability;
  qos.history().kind = history;
  qos.history().depth = depth;
  const std::int32_t per_instance =
      history == KEEP_ALL_HISTORY_QOS ? kCommandsQueuedPerValve : depth;
  qos.resource_limits().max_instances = kMaxInstances;
  qos.resource_limits().max_samples_per_instance = per_instance;
  qos.resource_limits().max_samples = kMaxInstances * per_instance;
  if constexpr (std::is_same_v<Qos, DataReaderQos>) {
    // A new reader asks a writer it matched for its data at once, not after Fast DDS's 70 ms:
    // a late joiner that met a gateway's writers before their first heartbeat reached it
    // otherwise waits those 70 ms (measured in a late `valvectl list`).
    qos.reliable_reader_qos().times.initialAcknackDelay = kInitialAcknackDelay;
  }
  return qos;
}

// Best effort, for the raw frames: one instance (BusFrame has no key), `depth` samples.
template <class Qos>
Qos best_effort(int depth) {
  Qos qos;
  qos.reliability().kind = BEST_EFFORT_RELIABILITY_QOS;
  qos.durability().kind = VOLATILE_DURABILITY_QOS;
  qos.history().kind = KEEP_LAST_HISTORY_QOS;
  qos.history().depth = depth;
  qos.resource_limits().max_instances = 1;
  qos.resource_limits().max_samples_per_instance = depth;
  qos.resource_limits().max_samples = depth;
  return qos;
}

constexpr int kFramesWritten = 256;
constexpr int kFramesHeld = 8192;

}  // namespace

DataWriterQos state_writer_qos() {
  auto qos = reliable<DataWriterQos>(TRANSIENT_LOCAL_DURABILITY_QOS, KEEP_LAST_HISTORY_QOS, 1);
  qos.liveliness().kind = AUTOMATIC_LIVELINESS_QOS;
  qos.liveliness().lease_duration = kStateLease;
  qos.liveliness().announcement_period = kStateAnnouncement;
  qos.reliable_writer_qos().times.heartbeatPeriod = kStateHeartbeat;
  return qos;
}
DataReaderQos state_reader_qos() {
  return reliable<DataReaderQos>(TRANSIENT_LOCAL_DURABILITY_QOS, KEEP_LAST_HISTORY_QOS, 1);
}
DataReaderQos liveliness_reader_qos() {
  auto qos = state_reader_qos();
  qos.liveliness().kind = AUTOMATIC_LIVELINESS_QOS;
  qos.liveliness().lease_duration = kStateLease;
  return qos;
}

DataReaderQos stream_reader_qos() {
  auto qos = state_reader_qos();
  qos.reliability().kind = BEST_EFFORT_RELIABILITY_QOS;
  qos.durability().kind = VOLATILE_DURABILITY_QOS;
  return qos;
}

DataWriterQos command_writer_qos() {
  auto qos = reliable<DataWriterQos>(VOLATILE_DURABILITY_QOS, KEEP_ALL_HISTORY_QOS, 1);
  qos.liveliness().kind = AUTOMATIC_LIVELINESS_QOS;
  qos.liveliness().lease_duration = kCommandLease;
  qos.liveliness().announcement_period = eprosima::fastrtps::Duration_t{0, 500'000'000};
  // A KEEP_ALL writer holds every command until the readers acknowledge it, and they do when
  // the writer heartbeats: every 3 s by default, long enough to fill the history at a few
  // dozen commands a second (measured: a fifth of them timed out in write()).
  qos.reliable_writer_qos().times.heartbeatPeriod = eprosima::fastrtps::Duration_t{0, 100'000'000};
  return qos;
}
DataReaderQos command_reader_qos() {
  auto qos = reliable<DataReaderQos>(VOLATILE_DURABILITY_QOS, KEEP_ALL_HISTORY_QOS, 1);
  qos.resource_limits().max_samples_per_instance = kCommandsHeldPerValve;
  qos.resource_limits().max_samples = kMaxInstances * kCommandsHeldPerValve;
  qos.liveliness().kind = AUTOMATIC_LIVELINESS_QOS;
  qos.liveliness().lease_duration = kCommandLease;
  return qos;
}

DataWriterQos status_writer_qos() {
  return reliable<DataWriterQos>(TRANSIENT_LOCAL_DURABILITY_QOS, KEEP_LAST_HISTORY_QOS, 32);
}
DataReaderQos status_reader_qos() {
  return reliable<DataReaderQos>(TRANSIENT_LOCAL_DURABILITY_QOS, KEEP_LAST_HISTORY_QOS, 32);
}

DataWriterQos frame_writer_qos() { return best_effort<DataWriterQos>(kFramesWritten); }
DataReaderQos frame_reader_qos() { return best_effort<DataReaderQos>(kFramesHeld); }

}  // namespace teejet::dds::topics
