#pragma once

// valvectl's command line: what the user asked for, checked before anything touches DDS. Every
// value the gateway would refuse is refused here first, with a message that names the option, so
// that a typo never costs a discovery round-trip and never reaches a valve.

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "teejet/valve.h"

namespace teejet::valvectl {

struct GlobalOptions {
  int domain = 0;
  std::string profile_file;  // Fast DDS XML profiles; empty: Fast DDS's own defaults
  bool json = false;
  // How long to look for gateways and valves, and to wait for a command's first status.
  std::chrono::milliseconds timeout{5000};
  // Command readers (the gateways, and recorders) to wait for before sending: commands are
  // VOLATILE, so a reader that matches after the write never hears it. 0: the gateways.
  std::size_t command_readers = 0;
};

struct ListOptions {
  unsigned wait_for_online = 0;  // wait until at least this many valves are online
};

struct WatchOptions {
  std::chrono::milliseconds interval{1000};
  std::optional<std::chrono::milliseconds> duration;  // nullopt: until Ctrl-C
  std::string title;  // shown above the table on every refresh, which clears the screen
};

// A valve command subcommand: the command to write to each valve and how far to follow it.
struct CommandRequest {
  std::string subcommand;              // "move", for messages
  std::vector<std::uint32_t> serials;  // the valves named on the command line
  std::string location;                // or the place of the valve, in a layout
  bool every_online_valve = false;     // --all (move, stop, jog, clear-errors)
  std::string only_gateway;            // with --all: only this gateway's valves
  ValveCommand command;                // serial, command_id and origin are set per send
  bool wait = false;                   // follow each command to its final status
  bool progress = false;  // with wait: the moving position also into a pipe (always on a tty)
  std::chrono::milliseconds wait_timeout{60000};  // backstop when no final status arrives
};

// assign and unassign: a change of the layout of the gateway that holds the location.
struct LayoutChangeRequest {
  LayoutChangeKind kind = LAYOUT_ASSIGN;
  std::string location;
  std::uint32_t serial = 0;  // assign
  bool move = false;         // assign: take the valve from the place it sits at now
};

enum class Subcommand { kList, kWatch, kLayout, kNeighbours, kLayoutChange, kIdentify, kCommand };

struct Invocation {
  GlobalOptions global;
  Subcommand subcommand = Subcommand::kList;
  ListOptions list;
  WatchOptions watch;
  CommandRequest command;
  LayoutChangeRequest layout_change;
};

// Either an invocation to run, or an exit status with what to print first (help and version on
// `out`, usage errors on `err`).
struct ParseOutcome {
  std::optional<Invocation> invocation;
  int exit_code = 0;
  std::string out;
  std::string err;
};

ParseOutcome parse_command_line(int argc, const char* const* argv);

}  // namespace teejet::valvectl
