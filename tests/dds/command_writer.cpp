// Test peer: writes one command to the given domain, prints "sent", then waits to be killed,
// so a test can make a commanding writer vanish the hard way.
#include <unistd.h>

#include <cstdio>
#include <cstdlib>

#include "teejet/dds/participant.hpp"
#include "teejet/dds/topics.hpp"
#include "teejet/valvePubSubTypes.h"

int main(int argc, char** argv) {
  if (argc != 3) return 2;
  auto participant =
      teejet::dds::Participant::create({.domain = std::atoi(argv[1]), .name = "command-writer"});
  if (!participant) {
    std::fprintf(stderr, "command_writer: %s\n", participant.error().reason.c_str());
    return 1;
  }
  auto topic = (*participant)->topic<teejet::ValveCommandPubSubType>(teejet::dds::topics::kCommand);
  if (!topic) return 1;
  auto writer = (*participant)->writer(*topic, teejet::dds::topics::command_writer_qos());
  if (!writer) return 1;
  teejet::ValveCommand command;
  command.serial(static_cast<std::uint32_t>(std::atoi(argv[2])));
  command.command_id(1);
  command.kind(teejet::COMMAND_MANUAL);
  command.speed_percent(50);
  command.direction(teejet::DIRECTION_OPEN);
  // Wait for the gateway's reader so the command is not written into the void.
  eprosima::fastdds::dds::PublicationMatchedStatus matched;
  while ((*writer)->get_publication_matched_status(matched) ==
             eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK &&
         matched.current_count == 0) {
    usleep(10'000);
  }
  (*writer)->write(&command);
  std::puts("sent");
  std::fflush(stdout);
  for (;;) pause();
}
