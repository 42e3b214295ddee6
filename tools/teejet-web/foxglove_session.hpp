#pragma once

// One Foxglove client as teejet-web keeps it: its subscriptions, the channels it publishes on,
// and its outbox, bounded so that a client that reads slower than the valves talk loses messages
// (counted, and told) while every other client and the DDS side go on at their pace. What it
// publishes is checked by the page's rules (page_command) before DDS sees it. No network and no
// threads here: the server's I/O thread drives it, and the unit tests drive it alike.

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "foxglove_protocol.hpp"
#include "page_command.hpp"
#include "teejet/client/valve_table.hpp"

namespace teejet::web::foxglove {

// Message data one client may have waiting: 1 MiB is about 10 s of every topic of 32 valves at
// the full poll rate (2,650 messages, 100 kB a second); a client further behind loses what comes
// next until it catches up.
inline constexpr std::size_t kMaxQueuedBytes = 1024 * 1024;
// Status messages one client may have waiting: one that sends refused messages and never reads
// the refusals gets no more of them.
inline constexpr std::size_t kMaxQueuedStatuses = 64;

class Outbox {
 public:
  explicit Outbox(std::size_t max_queued_bytes = kMaxQueuedBytes)
      : max_queued_bytes_(max_queued_bytes) {}

  enum class Kind { kText, kBinary };
  struct Write {
    Kind kind;
    std::string bytes;
    bool operator==(const Write&) const = default;
  };

  // A Message Data frame: queued, or dropped and counted (false) when it would take the frames
  // waiting over the outbox's bound (kMaxQueuedBytes unless told).
  bool post_data(std::string frame);
  // serverInfo and advertise: always queued.
  void post_text(std::string text);
  // A status: queued unless kMaxQueuedStatuses wait already (then dropped, false).
  bool post_status(std::string text);
  // The next frame to write when none is being written and one waits.
  std::optional<Write> start_write();
  void write_done();

  std::uint64_t dropped() const { return dropped_; }
  std::size_t queued_data_bytes() const { return data_bytes_; }
  std::size_t max_queued_bytes() const { return max_queued_bytes_; }

 private:
  std::size_t max_queued_bytes_;
  struct Queued {
    Kind kind;
    bool status;
    std::string bytes;
  };
  std::deque<Queued> waiting_;
  std::size_t data_bytes_ = 0;
  std::size_t statuses_ = 0;
  std::uint64_t dropped_ = 0;
  bool writing_ = false;
};

// What a client publishes, answered: who may, on which topic, and the command it carries. The
// refusals are the page's (policy_refusal, check_published_command) and DDS's.
struct Publish {
  ClientChannel channel;
  std::vector<std::uint8_t> payload;
};

// The status a published command is answered with: the command id it went out with, or why it
// did not. `token` is what the client's URL carried.
struct PublishAnswer {
  Level level;
  std::string message;
};
PublishAnswer answer_publish(const Publish& publish, const client::ValveTable& table,
                             const CommandPolicy& policy, std::optional<std::string_view> token,
                             CommandSender& sender, const TokenCheck& check_token);

class Session {
 public:
  // `publish_refusal`: why this client may not publish at all (teejet-web is read-only, or takes
  // commands from Foxglove only with a token); nullopt: it may, on teejet/valve/command.
  explicit Session(std::optional<std::string> publish_refusal,
                   std::size_t max_queued_bytes = kMaxQueuedBytes);

  struct Reaction {
    std::vector<std::string> statuses;     // to send back, in order
    std::vector<Subscription> subscribed;  // each gets its channel's current state at once
  };
  Reaction on_text(std::string_view text);

  // A Client Message Data frame: what to publish, or the status refusing it.
  std::variant<Publish, std::string> on_binary(std::span<const std::uint8_t> frame);

  // The client's subscriptions to `channel`, in the order made.
  std::span<const std::uint32_t> subscriptions(std::uint32_t channel) const;

  Outbox outbox;

 private:
  void subscribe(const Subscribe& request, Reaction& reaction);
  void unsubscribe(const Unsubscribe& request, Reaction& reaction);
  void advertise(const ClientAdvertise& request, Reaction& reaction);
  void unadvertise(const ClientUnadvertise& request, Reaction& reaction);

  const std::optional<std::string> publish_refusal_;
  std::map<std::uint32_t, std::uint32_t> subscriptions_;            // id → channel
  std::map<std::uint32_t, std::vector<std::uint32_t>> by_channel_;  // channel → ids
  std::map<std::uint32_t, ClientChannel> client_channels_;          // by the client's id
};

}  // namespace teejet::web::foxglove
