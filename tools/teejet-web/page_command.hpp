#pragma once

// The commands the page may send over its WebSocket, parsed and checked before anything reaches
// DDS. The range rules are the codec's (client::checked_command, which encodes as the gateway
// will); the valve must be in the table. handle_page_message() either hands every command to a
// CommandSender or refuses with a reason and sends nothing, so a test with a recording sender
// proves that bad input never reaches a valve. docs/web.md lists the messages.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "teejet/client/valve_table.hpp"
#include "teejet/core/result.hpp"
#include "teejet/valve.h"

namespace teejet::web {

// Larger messages are refused unread: no command needs more than a few hundred bytes.
inline constexpr std::size_t kMaxCommandBytes = 4096;
// Deeper JSON is refused unparsed: a command is one object of plain values. nlohmann's dump()
// recurses once per level, and a CivetWeb worker's stack is 100 KiB.
inline constexpr int kMaxJsonDepth = 4;
// An "id" the answer echoes: a number, or a string of at most this many bytes (null otherwise).
inline constexpr std::size_t kMaxIdBytes = 64;

// Whether no array or object of `text` lies deeper than `max_depth`, counted without parsing:
// what a client sends is refused before a parser or dump() recurses into it.
bool nested_within(std::string_view text, int max_depth);

// A checked command: what to write, to which valves (several for stop_all).
struct PageCommand {
  std::vector<std::uint32_t> serials;
  ValveCommand command;  // serial, command_id and origin are set per send
};

// A checked change of a gateway's layout (assign, unassign): for the gateway whose layout holds
// the place, and only for it.
struct PageLayoutChange {
  LayoutChange change;      // change_id and origin are set when sent
  std::string participant;  // that gateway's (client::LocationRow::participant)
};

// {"command":"move","serial":"TJV000001","degrees":90,"speed_percent":100,"direction":"open"}
// and the others of docs/web.md; a valve is named by "serial" or by "location" (the place it
// sits at); an Error names what was wrong.
Result<PageCommand> parse_page_command(std::string_view text, const client::ValveTable& table);
// The same for a message already parsed (discarded when it was not JSON).
Result<PageCommand> check_page_command(const nlohmann::json& message,
                                       const client::ValveTable& table);

// A command a client wrote as a whole ValveCommand (a Foxglove client publishes them): the valve
// must be in the table, and its kind and fields pass the codec's checks as the page's commands
// do. Its serial is kept; command_id and origin are the sender's.
Result<PageCommand> check_published_command(const ValveCommand& published,
                                            const client::ValveTable& table);

// {"command":"assign","location":"section-03","serial":"TJV000007","move":false} ("move"
// optional) or {"command":"unassign","location":"section-03"}: the place must be in exactly one
// gateway's layout; whether the serial may go there is the gateway's to judge.
Result<PageLayoutChange> check_page_layout_change(const nlohmann::json& message,
                                                  const client::ValveTable& table);

// Where checked commands go: CommandClient in teejet-web, a recorder in the tests.
class CommandSender {
 public:
  virtual ~CommandSender() = default;
  // The command_id the command was written with, or an Error saying why it was not written.
  virtual Result<std::uint32_t> send(ValveCommand command) = 0;
  // The same for a layout change, to the gateway of `participant`: its change_id.
  virtual Result<std::uint32_t> send(LayoutChange change, const std::string& participant) = 0;
};

struct CommandPolicy {
  bool allow_commands = false;  // --allow-commands; read-only otherwise
  std::string token;            // --token: when set, every command must carry it
};

// What the page may send and what the valves tell, from the codec's table, so that the page
// builds its inputs, request list, readings and plot fields without restating the sheet:
// {"commands":{"move":{"speed_percent":{"type":"number","unit":"%","min":0,"max":100,"step":1},
//  "direction":{"type":"word","unit":"","words":["close","open","shortest"]},"degrees":{..}},
//  ...,"request":{"telemetry":["version","position",...],"resend_tenths":{..}}},
//  "telemetry":{"position":{"degrees":{"type":"number","unit":"°",...}},"current":{..},...}}
nlohmann::json page_protocol_json();

// What the page's snapshot says of commands, so that a read-only page builds no controls and a
// page that needs a token asks for one: {"allowed":true,"token_required":false}. Never the token.
nlohmann::json command_policy_json(const CommandPolicy& policy);

// The refusal of a token, nullopt when it is accepted: a TokenGuard in teejet-web.
using TokenCheck = std::function<std::optional<std::string>(std::string_view token)>;

// Why no command of a client is taken whatever it asks (read-only; a token missing, nullopt, or
// wrong), nullopt when its commands may be checked. The page's messages and a Foxglove client's
// publishes both pass here. With a token in `policy`, `token` goes to `check_token` (when given;
// compared with the policy's otherwise).
std::optional<std::string> policy_refusal(const CommandPolicy& policy,
                                          std::optional<std::string_view> token,
                                          const TokenCheck& check_token = {});

// The answer to one message from the page:
// {"type":"sent","id":ID,"commands":[{"serial":"TJV000001","command_id":7}]} (a command DDS did
// not take has "error":"why" instead of "command_id"),
// {"type":"sent","id":ID,"changes":[{"location":"section-03","gateway":"boom","change_id":4}]}
// for a layout change (or "error" likewise) or
// {"type":"refused","id":ID,"reason":"..."}; "id" echoes the page's own "id" when it is a number
// or a string of at most kMaxIdBytes, null otherwise. With a token in `policy`, a message's
// "token" goes to `check_token` (when given; compared with the policy's otherwise).
nlohmann::json handle_page_message(std::string_view text, const client::ValveTable& table,
                                   const CommandPolicy& policy, CommandSender& sender,
                                   const TokenCheck& check_token = {});

}  // namespace teejet::web
