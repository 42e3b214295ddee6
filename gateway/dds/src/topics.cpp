#include "teejet/dds/topics.hpp"

#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>

namespace teejet::dds::topics {

using namespace eprosima::fastdds::dds;

namespace {

const eprosima::fastrtps::Duration_t kCommandLease{2, 0};

template <class Qos>
Qos reliable(DurabilityQosPolicyKind durability, HistoryQosPolicyKind history, int depth) {
  Qos qos;
  qos.reliability().kind = RELIABLE_RELIABILITY_QOS;
  qos.durability().kind = durability;
  qos.history().kind = history;
  qos.history().depth = depth;
  return qos;
}

}  // namespace

DataWriterQos state_writer_qos() {
  return reliable<DataWriterQos>(TRANSIENT_LOCAL_DURABILITY_QOS, KEEP_LAST_HISTORY_QOS, 1);
}
DataReaderQos state_reader_qos() {
  return reliable<DataReaderQos>(TRANSIENT_LOCAL_DURABILITY_QOS, KEEP_LAST_HISTORY_QOS, 1);
}

DataWriterQos command_writer_qos() {
  auto qos = reliable<DataWriterQos>(VOLATILE_DURABILITY_QOS, KEEP_ALL_HISTORY_QOS, 1);
  qos.liveliness().kind = AUTOMATIC_LIVELINESS_QOS;
  qos.liveliness().lease_duration = kCommandLease;
  qos.liveliness().announcement_period = eprosima::fastrtps::Duration_t{0, 500'000'000};
  return qos;
}
DataReaderQos command_reader_qos() {
  auto qos = reliable<DataReaderQos>(VOLATILE_DURABILITY_QOS, KEEP_ALL_HISTORY_QOS, 1);
  qos.liveliness().kind = AUTOMATIC_LIVELINESS_QOS;
  qos.liveliness().lease_duration = kCommandLease;
  return qos;
}

DataWriterQos status_writer_qos() {
  return reliable<DataWriterQos>(VOLATILE_DURABILITY_QOS, KEEP_LAST_HISTORY_QOS, 32);
}
DataReaderQos status_reader_qos() {
  return reliable<DataReaderQos>(VOLATILE_DURABILITY_QOS, KEEP_LAST_HISTORY_QOS, 32);
}

}  // namespace teejet::dds::topics
