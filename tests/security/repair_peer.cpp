// A secure DDS peer for leaving_reader_test.py, with the profile of a site made by tools/pki:
//
//   repair_peer PROFILE write N   the gateway's position writer (its QoS) holding the positions
//                                 of N valves; "wrote N" on stdout once they are written, and
//                                 "readers K" whenever the number of matched readers changes;
//                                 until SIGINT or SIGTERM
//   repair_peer PROFILE read N    a late reader of positions: takes N samples (20 s at most),
//                                 prints "took K" and leaves at once, while the writer is still
//                                 repairing the rest of its history to it
//
// Exit 0; 1 when DDS refuses something (the reason on stderr); 2 when the reader took fewer
// than N.

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <fastdds/dds/publisher/DataWriterListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <iostream>
#include <string>
#include <thread>

#include "teejet/dds/participant.hpp"
#include "teejet/dds/topics.hpp"
#include "teejet/stop_signals.hpp"

namespace {

using namespace eprosima::fastdds::dds;

class MatchPrinter final : public DataWriterListener {
 public:
  void on_publication_matched(DataWriter*, const PublicationMatchedStatus& status) override {
    std::cout << "readers " << status.current_count << std::endl;
  }
};

int refused(const teejet::Error& error) {
  std::cerr << "repair_peer: " << error.reason << '\n';
  return 1;
}

std::atomic<bool> stop{false};

int write(teejet::dds::Participant& participant, eprosima::fastdds::dds::Topic* topic, int valves) {
  MatchPrinter printer;
  auto writer = participant.writer(topic, teejet::dds::topics::state_writer_qos(), &printer);
  if (!writer) return refused(writer.error());
  teejet::ValvePosition position;
  for (int serial = 1; serial <= valves; ++serial) {
    position.serial(static_cast<std::uint32_t>(serial));
    position.degrees(static_cast<float>(serial % 360));
    if (!(*writer)->write(&position)) {
      std::cerr << "repair_peer: the position of valve " << serial << " was not written\n";
      return 1;
    }
  }
  std::cout << "wrote " << valves << std::endl;
  while (!stop) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  participant.delete_writer(*writer);
  return 0;
}

int read(teejet::dds::Participant& participant, eprosima::fastdds::dds::Topic* topic, int wanted) {
  auto reader = participant.reader(topic, teejet::dds::topics::state_reader_qos());
  if (!reader) return refused(reader.error());
  int took = 0;
  teejet::ValvePosition position;
  SampleInfo info;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (took < wanted && std::chrono::steady_clock::now() < deadline) {
    if ((*reader)->wait_for_unread_message(
            teejet::dds::to_dds_duration(std::chrono::milliseconds(100)))) {
      while (took < wanted && (*reader)->take_next_sample(&position, &info) ==
                                  eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK) {
        took += info.valid_data ? 1 : 0;
      }
    }
  }
  std::cout << "took " << took << std::endl;
  return took == wanted ? 0 : 2;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string mode = argc == 4 ? argv[2] : "";
  if (mode != "write" && mode != "read") {
    std::cerr << "usage: repair_peer PROFILE write|read N\n";
    return 64;
  }
  // Before Fast DDS starts its threads, so that they leave the signals to ours.
  if (mode == "write") teejet::command_line::stop_on_sigint_or_sigterm(stop);
  auto participant =
      teejet::dds::Participant::create({.profile_file = argv[1], .name = "repair-peer-" + mode});
  if (!participant) return refused(participant.error());
  auto topic = teejet::dds::topics::topic_of<teejet::ValvePosition>(**participant);
  if (!topic) return refused(topic.error());
  const int count = std::atoi(argv[3]);
  return mode == "write" ? write(**participant, *topic, count) : read(**participant, *topic, count);
}
