// Test peer: deletes a writer that has readers behind it, ROUNDS times, through
// teejet::dds::Participant (the gateway's, valvectl's and every other program's way out), and
// exits 0 once every deletion has returned. Usage: writer_teardown DOMAIN ROUNDS
// Each round a participant writes one position of each of 4096 valves to a reader of another
// participant (intraprocess delivery off: over UDP, as between two processes), its heartbeat
// every millisecond, and is deleted at once, while most of those samples are unacknowledged.
// Fast DDS 2.9.1 can then hang in the deletion (participant.cpp, empty_history): the test that
// runs this peer kills it at its deadline. Exits 1, saying why, when DDS refuses a step.
#include <fastrtps/xmlparser/XMLProfileManager.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <string>

#include "support/peer_program.hpp"
#include "teejet/dds/participant.hpp"
#include "teejet/dds/topics.hpp"
#include "teejet/valvePubSubTypes.h"

namespace {

using teejet::testing::refused;
constexpr const char* kPeer = "writer_teardown";

constexpr std::chrono::seconds kMatchDeadline{15};
constexpr std::uint32_t kValves = 4096;  // every instance a topic allows

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fputs("usage: writer_teardown DOMAIN ROUNDS\n", stderr);
    return 2;
  }
  const int domain = std::atoi(argv[1]);
  const int rounds = std::atoi(argv[2]);
  eprosima::fastrtps::LibrarySettingsAttributes library;
  library.intraprocess_delivery = eprosima::fastrtps::INTRAPROCESS_OFF;
  eprosima::fastrtps::xmlparser::XMLProfileManager::library_settings(library);

  auto reading = teejet::dds::Participant::create({.domain = domain, .name = "teardown-reader"});
  if (!reading) return refused(kPeer, reading.error().reason);
  auto read_topic = teejet::dds::topics::topic_of<teejet::ValvePosition>(**reading);
  if (!read_topic) return refused(kPeer, read_topic.error().reason);
  auto reader = (*reading)->reader(*read_topic, teejet::dds::topics::state_reader_qos());
  if (!reader) return refused(kPeer, reader.error().reason);

  for (int round = 1; round <= rounds; ++round) {
    auto writing = teejet::dds::Participant::create({.domain = domain, .name = "teardown-writer"});
    if (!writing) return refused(kPeer, writing.error().reason);
    auto topic = teejet::dds::topics::topic_of<teejet::ValvePosition>(**writing);
    if (!topic) return refused(kPeer, topic.error().reason);
    auto qos = teejet::dds::topics::state_writer_qos();
    qos.reliable_writer_qos().times.heartbeatPeriod = eprosima::fastrtps::Duration_t{0, 1'000'000};
    auto writer = (*writing)->writer(*topic, qos);
    if (!writer) return refused(kPeer, writer.error().reason);
    const bool matched = teejet::testing::reader_matched(**writer, kMatchDeadline);
    if (!matched)
      return refused(kPeer,
                     "the reader did not match the writer in round " + std::to_string(round));
    teejet::ValvePosition position;
    for (std::uint32_t serial = 1; serial <= kValves; ++serial) {
      position.serial(serial);
      position.degrees(static_cast<float>(serial % 360));
      if (!(*writer)->write(&position)) {
        return refused(kPeer, "write refused in round " + std::to_string(round));
      }
    }
    writing->reset();  // the deletion under test
    std::printf("round %d\n", round);
    std::fflush(stdout);
  }
  std::puts("done");
  return 0;
}
