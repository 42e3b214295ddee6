// What a Foxglove client may send teejet-web's Foxglove port (foxglove_session): text messages
// (subscribe, unsubscribe, advertise, anything else) and binary ones (Client Message Data), and
// a published command's answer (the CDR of a ValveCommand, the page's rules), on a connection
// that may publish.
//
// Input: a sequence of messages, each one byte of kind (even: text, odd: binary) and two bytes of
// length (little-endian), then that many bytes.
//
// Properties: no crash; every reaction is a status message (JSON, op "status", level 0..2) or a
// subscription of an advertised channel; a publish is answered either "command not sent: ..."
// and nothing sent, or one command sent to a valve of the table whose fields pass the codec.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "foxglove_protocol.hpp"
#include "foxglove_session.hpp"
#include "fuzz_input.hpp"
#include "teejet/dds/conversions.hpp"

namespace {

using namespace teejet;
using namespace teejet::web;

class CountingSender final : public CommandSender {
 public:
  Result<std::uint32_t> send(ValveCommand command) override {
    sent.push_back(command);
    return static_cast<std::uint32_t>(sent.size());
  }
  Result<std::uint32_t> send(LayoutChange, const std::string&) override {
    return Error{ErrorCode::kInvalidValue, "no layout changes here"};
  }
  std::vector<ValveCommand> sent;
};

const client::ValveTable& table() {
  static const client::ValveTable kTable = [] {
    client::ValveTable made;
    for (std::uint32_t serial = 1; serial <= 3; ++serial) {
      ValvePresence presence;
      presence.serial(serial);
      presence.address(static_cast<std::uint8_t>(0xD7 + serial));
      presence.online(true);
      presence.gateway("gw");
      made.on_presence(presence);
    }
    return made;
  }();
  return kTable;
}

void check_status(const std::string& text) {
  const auto message = nlohmann::json::parse(text, nullptr, false);
  FUZZ_CHECK(message.is_object() && message.value("op", "") == "status", text);
  const int level = message.at("level").get<int>();
  FUZZ_CHECK(level >= 0 && level <= 2, text);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  foxglove::Session session(std::nullopt);
  const CommandPolicy policy{true, "token"};
  std::size_t at = 0;
  while (at + 3 <= size) {
    const bool binary = (data[at] & 1) != 0;
    const std::size_t claimed =
        static_cast<std::size_t>(data[at + 1]) | static_cast<std::size_t>(data[at + 2]) << 8;
    const std::size_t length = std::min(claimed, size - at - 3);
    const std::uint8_t* bytes = data + at + 3;
    at += 3 + length;
    if (!binary) {
      const auto reaction =
          session.on_text(std::string_view(reinterpret_cast<const char*>(bytes), length));
      for (const auto& status : reaction.statuses) check_status(status);
      for (const auto& subscription : reaction.subscribed) {
        FUZZ_CHECK(foxglove::find_channel(subscription.channel) != nullptr, "subscribed");
      }
      continue;
    }
    auto outcome = session.on_binary({bytes, length});
    if (const auto* refusal = std::get_if<std::string>(&outcome)) {
      check_status(*refusal);
      continue;
    }
    CountingSender sender;
    const auto answer = foxglove::answer_publish(std::get<foxglove::Publish>(outcome), table(),
                                                 policy, "token", sender, {});
    if (answer.message.rfind("command not sent: ", 0) == 0) {
      FUZZ_CHECK(answer.level == foxglove::Level::kError && sender.sent.empty(), answer.message);
      continue;
    }
    FUZZ_CHECK(answer.level == foxglove::Level::kInfo && sender.sent.size() == 1, answer.message);
    const ValveCommand& sent = sender.sent.front();
    FUZZ_CHECK(table().row(sent.serial()).has_value(), answer.message);
    FUZZ_CHECK(dds::to_message(sent).ok(), answer.message);
  }
  return 0;
}
