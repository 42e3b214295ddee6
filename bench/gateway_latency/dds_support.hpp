#pragma once

// DDS helpers every DDS mode uses: endpoints of the contract's topics made in one step, and
// waiting for discovery with a deadline.

#include <chrono>
#include <functional>

#include "support/eventually.hpp"
#include "teejet/core/result.hpp"
#include "teejet/dds/participant.hpp"
#include "teejet/dds/topics.hpp"

namespace teejet::bench {

namespace fdds = eprosima::fastdds::dds;

// 20 s, scaled as every deadline of the user-mode-linux tests that run this bench is.
inline const std::chrono::seconds kDiscoveryTimeout = testing::scaled(std::chrono::seconds{20});

// A reader (writer) of Sample's topic (dds::topics::topic_of), registering the topic on first use.
template <class Sample>
Result<fdds::DataReader*> open_reader(dds::Participant& participant, const fdds::DataReaderQos& qos,
                                      fdds::DataReaderListener* listener = nullptr) {
  auto topic = dds::topics::topic_of<Sample>(participant);
  if (!topic) return topic.error();
  return participant.reader(*topic, qos, listener);
}

template <class Sample>
Result<fdds::DataWriter*> open_writer(dds::Participant& participant,
                                      const fdds::DataWriterQos& qos) {
  auto topic = dds::topics::topic_of<Sample>(participant);
  if (!topic) return topic.error();
  return participant.writer(*topic, qos);
}

// Polls `condition` every 10 ms; false when it still does not hold after `timeout`.
bool wait_until(const std::function<bool()>& condition, std::chrono::milliseconds timeout);

// At least one remote endpoint matched.
bool matched(fdds::DataWriter* writer);
bool matched(fdds::DataReader* reader);

}  // namespace teejet::bench
