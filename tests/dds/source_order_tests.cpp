// Why every writer of ours stamps through SourceStamps (teejet/dds/source_stamps.hpp): Fast DDS
// 2.9.1 aborts a reader when a writer's source timestamps go back and one of its samples arrives
// late while another writer's sample sits in the reader's history. Three participants in this
// process exchange over UDP (intraprocess delivery off), one of them through Fast DDS's test
// transport, which loses the first sample of its writer once. Each scenario runs in a child
// process: the one that aborts must not take the suite with it.

#include <fastdds/rtps/messages/CDRMessage.h>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastdds/rtps/transport/test_UDPv4TransportDescriptor.h>
#include <fastrtps/xmlparser/XMLProfileManager.h>
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <map>
#include <memory>
#include <set>

#include "support/eventually.hpp"
#include "support/test_domain.hpp"
#include "teejet/dds/source_stamps.hpp"
#include "teejet/dds/topics.hpp"
#include "teejet/valvePubSubTypes.h"

namespace teejet::dds::source_order {
namespace {

using namespace std::chrono_literals;
using namespace eprosima::fastdds::dds;
using eprosima::fastdds::rtps::TransportDescriptorInterface;
using ReturnCode = eprosima::fastrtps::types::ReturnCode_t;

constexpr std::uint64_t kSecond = 1'000'000'000;
const eprosima::fastrtps::Duration_t kAckWait{10, 0};

// One participant with a writer or a reader of the presence topic, on `transport` only.
class Side {
 public:
  explicit Side(std::shared_ptr<TransportDescriptorInterface> transport) {
    auto* factory = DomainParticipantFactory::get_instance();
    DomainParticipantQos qos = factory->get_default_participant_qos();
    qos.transport().use_builtin_transports = false;
    qos.transport().user_transports = {std::move(transport)};
    participant_ =
        factory->create_participant(static_cast<DomainId_t>(testing::test_domain()), qos);
    if (participant_ == nullptr) return;
    TypeSupport type(new ValvePresencePubSubType());
    type.register_type(participant_);
    topic_ = participant_->create_topic(topics::kPresence, type.get_type_name(), TOPIC_QOS_DEFAULT);
  }
  ~Side() {
    if (participant_ != nullptr) {
      participant_->delete_contained_entities();
      DomainParticipantFactory::get_instance()->delete_participant(participant_);
    }
  }

  DataWriter* writer() {
    auto qos = topics::state_writer_qos();
    // The lost sample is asked for again at the next heartbeat: soon.
    qos.reliable_writer_qos().times.heartbeatPeriod = {0, 100'000'000};
    return participant_->create_publisher(PUBLISHER_QOS_DEFAULT)->create_datawriter(topic_, qos);
  }
  DataReader* reader() {
    return participant_->create_subscriber(SUBSCRIBER_QOS_DEFAULT)
        ->create_datareader(topic_, topics::state_reader_qos());
  }

 private:
  DomainParticipant* participant_ = nullptr;
  Topic* topic_ = nullptr;
};

// A transport that loses the first datagram carrying sequence number 1 of a user writer.
std::shared_ptr<TransportDescriptorInterface> losing_the_first_sample() {
  auto transport = std::make_shared<eprosima::fastdds::rtps::test_UDPv4TransportDescriptor>();
  auto lost = std::make_shared<std::atomic<bool>>(false);
  transport->drop_data_messages_filter_ = [lost](eprosima::fastrtps::rtps::CDRMessage_t& message) {
    namespace cdr = eprosima::fastrtps::rtps::CDRMessage;
    const auto start = message.pos;
    eprosima::fastrtps::rtps::EntityId_t writer;
    eprosima::fastrtps::rtps::SequenceNumber_t sequence;
    message.pos += 8;  // extra flags, octets to inline QoS, reader id
    cdr::readEntityId(&message, &writer);
    cdr::readInt32(&message, &sequence.high);
    cdr::readUInt32(&message, &sequence.low);
    message.pos = start;
    const bool user_writer = (writer.value[3] & 0xC0) == 0;  // not a built-in endpoint
    return user_writer && sequence == eprosima::fastrtps::rtps::SequenceNumber_t{0, 1} &&
           !lost->exchange(true);
  };
  return transport;
}

ValvePresence presence(std::uint32_t serial, std::uint8_t address) {
  ValvePresence sample;
  sample.serial(serial);
  sample.address(address);
  sample.online(true);
  sample.gateway("source-order");
  return sample;
}

template <class Condition>
bool within(Condition condition) {
  return testing::eventually(condition, 10s);
}

// Gateway B publishes valve 2; gateway A publishes valve 1 (lost on the way, sent again) and
// then valve 3 stamped before it, then valve 1 again. `stamp` gives A's source timestamps.
// Returns the address of every valve the reader took, valve 1's newest.
std::map<std::uint32_t, int> run(
    const std::function<eprosima::fastrtps::Time_t(DataWriter*, std::uint64_t)>& stamp) {
  eprosima::fastrtps::LibrarySettingsAttributes library;
  library.intraprocess_delivery = eprosima::fastrtps::INTRAPROCESS_OFF;
  eprosima::fastrtps::xmlparser::XMLProfileManager::library_settings(library);

  auto udp = std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>();
  Side reader_side(udp), a_side(losing_the_first_sample()), b_side(udp);
  DataReader* reader = reader_side.reader();
  DataWriter* a = a_side.writer();
  DataWriter* b = b_side.writer();
  std::map<std::uint32_t, int> taken;
  if (!reader || !a || !b) return taken;
  // Both ends of both matches: a writer that has not met the reader yet is acknowledged by
  // nobody and sends its samples later, in order.
  const bool matched = within([&] {
    SubscriptionMatchedStatus subscribed;
    PublicationMatchedStatus a_matched, b_matched;
    reader->get_subscription_matched_status(subscribed);
    a->get_publication_matched_status(a_matched);
    b->get_publication_matched_status(b_matched);
    return subscribed.current_count == 2 && a_matched.current_count == 1 &&
           b_matched.current_count == 1;
  });
  if (!matched) return taken;

  const auto write = [&](DataWriter* writer, ValvePresence sample, std::uint64_t wanted_ns) {
    writer->write_w_timestamp(&sample, HANDLE_NIL, stamp(writer, wanted_ns));
  };
  write(b, presence(2, 0xD9), 95 * kSecond);
  if (b->wait_for_acknowledgments(kAckWait) != ReturnCode::RETCODE_OK) return taken;
  write(a, presence(1, 0xD8), 100 * kSecond);  // lost, sent again after the next one
  write(a, presence(3, 0xDA), 90 * kSecond);   // valve 3 last heard before valve 1
  if (a->wait_for_acknowledgments(kAckWait) != ReturnCode::RETCODE_OK) return taken;

  const auto take = [&] {
    ValvePresence sample;
    SampleInfo info;
    while (reader->take_next_sample(&sample, &info) == ReturnCode::RETCODE_OK) {
      if (info.valid_data) taken[sample.serial()] = sample.address();
    }
  };
  take();
  write(a, presence(1, 0xDB), 110 * kSecond);  // valve 1 again: its instance is updated
  if (a->wait_for_acknowledgments(kAckWait) != ReturnCode::RETCODE_OK) return taken;
  within([&] {
    take();
    return taken[1] == 0xDB;
  });
  return taken;
}

const std::map<std::uint32_t, int> kEveryValveNewest{{1, 0xDB}, {2, 0xD9}, {3, 0xDA}};

// The exit code of a child that ran the exchange: 0 when the reader took every valve's newest.
[[noreturn]] void run_clamped() {
  std::map<DataWriter*, SourceStamps> stamps;
  const auto taken = run([&](DataWriter* writer, std::uint64_t wanted_ns) {
    return stamps[writer].write(wanted_ns, [](const auto& stamp) { return stamp; });
  });
  std::exit(taken == kEveryValveNewest ? 0 : 3);
}

[[noreturn]] void run_as_asked() {
  run([](DataWriter*, std::uint64_t wanted_ns) { return to_dds_time(wanted_ns); });
  std::exit(0);
}

TEST(SourceOrder, StampsThroughSourceStampsKeepAReaderAliveWhenASampleIsResent) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(run_clamped(), ::testing::ExitedWithCode(0), "");
}

// The cause, shown on Fast DDS itself: the same exchange stamped as asked aborts the reader. If
// this starts to fail, the Fast DDS in use no longer has the fault; SourceStamps can then go.
TEST(SourceOrder, FastDds291AbortsTheReaderWhenAWritersStampsGoBack) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_DEATH(run_as_asked(), "NEW_VIEW_STATE == view_state");
}

TEST(SourceStamps, AStampThatWouldGoBackIsThePreviousOne) {
  SourceStamps stamps;
  const auto stamped = [&](std::uint64_t wanted) {
    return stamps.write(wanted, [](const eprosima::fastrtps::Time_t& stamp) {
      return std::uint64_t(stamp.seconds) * kSecond + stamp.nanosec;
    });
  };
  EXPECT_EQ(stamped(100 * kSecond), 100 * kSecond);
  EXPECT_EQ(stamped(90 * kSecond), 100 * kSecond);
  EXPECT_EQ(stamped(100 * kSecond + 1), 100 * kSecond + 1);
  EXPECT_EQ(stamped(110 * kSecond), 110 * kSecond);
}

}  // namespace
}  // namespace teejet::dds::source_order
