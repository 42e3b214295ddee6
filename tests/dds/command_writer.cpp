// Test peer: writes one command to the given domain, prints "sent", then waits to be killed,
// so a test can make a commanding writer vanish the hard way. Usage: command_writer DOMAIN SERIAL
// The command is Manual, opening at 50 %. Exits 1, saying why on standard error, when DDS
// refuses it or no command reader (a gateway's) matched it within kMatchDeadline.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "support/peer_program.hpp"
#include "support/valve_commands.hpp"
#include "teejet/dds/participant.hpp"
#include "teejet/dds/topics.hpp"
#include "teejet/valvePubSubTypes.h"

namespace {

using teejet::testing::refused;
constexpr const char* kPeer = "command_writer";

// As long as DdsPeer waits for a gateway: the tests that run this peer wait longer for "sent",
// so they see the reason below rather than their own timeout.
constexpr std::chrono::seconds kMatchDeadline{15};

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fputs("usage: command_writer DOMAIN SERIAL\n", stderr);
    return 2;
  }
  auto participant =
      teejet::dds::Participant::create({.domain = std::atoi(argv[1]), .name = "command-writer"});
  if (!participant) return refused(kPeer, participant.error().reason);
  auto topic = (*participant)->topic<teejet::ValveCommandPubSubType>(teejet::dds::topics::kCommand);
  if (!topic) return refused(kPeer, topic.error().reason);
  auto writer = (*participant)->writer(*topic, teejet::dds::topics::command_writer_qos());
  if (!writer) return refused(kPeer, writer.error().reason);

  // Wait for the gateway's reader so the command is not written into the void.
  const bool matched = teejet::testing::reader_matched(**writer, kMatchDeadline);
  if (!matched) {
    return refused(kPeer, "no command reader matched within " +
                              std::to_string(kMatchDeadline.count()) + " s on domain " + argv[1]);
  }
  auto command =
      teejet::testing::from("command-writer", 1,
                            teejet::testing::command(static_cast<std::uint32_t>(std::atoi(argv[2])),
                                                     teejet::COMMAND_MANUAL, 50));
  if (!(*writer)->write(&command)) return refused(kPeer, "DDS refused to write the command");
  std::puts("sent");
  std::fflush(stdout);
  for (;;) pause();
}
