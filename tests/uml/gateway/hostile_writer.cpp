// Test peer for gateway_hostile.sh: a DDS writer built from the generated types that bypasses
// valvectl and sends the gateway what no client should (issue 10, item 3): every hostile value
// of the IDL's fields, an unknown serial, a flood to one valve, and good moves around them.
// It follows every command to its final status and prints, for the script to check against
// what candump saw on the wire:
//   case NAME id ID serial S expect rejected|final got STATES reason "…"
//   run_frames SERIAL N   (run commands, ids 0x00-0x05, it saw ACCEPTED for that valve)
//   summary sent N final N missing N unexpected N
//   flood_missing N       (of the above: flood commands whose final status never arrived)
// Exit 0 when every case, the move amid the flood and the good moves ended as expected and
// every command outside the flood got its final status. Statuses of the flood itself can be lost
// on their way to this reader (docs/gateway.md, "Statuses under a flood"): they are counted.
// Usage: hostile_writer DOMAIN SERIAL_1 SERIAL_2 UNKNOWN_SERIAL [FLOOD]
// FLOOD: commands to valve 1, written 10,000 a second at most (default 10,000).

#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <limits>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "support/eventually.hpp"
#include "support/valve_commands.hpp"
#include "teejet/dds/participant.hpp"
#include "teejet/dds/topics.hpp"
#include "teejet/valvePubSubTypes.h"

namespace {

using namespace std::chrono_literals;
using namespace teejet;
using eprosima::fastdds::dds::DataReader;
using eprosima::fastdds::dds::SampleInfo;
using ReturnCode = eprosima::fastrtps::types::ReturnCode_t;

const char* const kOrigin = "hostile-writer";

// A deadline `seconds` from now, scaled as every UML test's is.
std::chrono::steady_clock::time_point within(std::chrono::seconds seconds) {
  return std::chrono::steady_clock::now() + teejet::testing::scaled(seconds);
}

// Every status, taken on Fast DDS's thread as it arrives: a reader that keeps up.
class Statuses final : public eprosima::fastdds::dds::DataReaderListener {
 public:
  void on_data_available(DataReader* reader) override {
    CommandStatus status;
    SampleInfo info;
    std::lock_guard lock(mutex_);
    while (reader->take_next_sample(&status, &info) == ReturnCode::RETCODE_OK) {
      if (info.valid_data && status.origin().to_string() == kOrigin) {
        states_[status.command_id()].push_back(status);
      }
    }
    changed_.notify_all();
  }
  // The statuses of `id` once one is final, or what came by `deadline`.
  std::vector<CommandStatus> follow(std::uint32_t id, std::chrono::steady_clock::time_point until) {
    std::unique_lock lock(mutex_);
    changed_.wait_until(lock, until, [&] { return final_locked(id); });
    return states_[id];
  }
  // The first status of `id`, for a command that ends only when another replaces it.
  std::vector<CommandStatus> first(std::uint32_t id, std::chrono::steady_clock::time_point until) {
    std::unique_lock lock(mutex_);
    changed_.wait_until(lock, until, [&] { return !states_[id].empty(); });
    return states_[id];
  }

 private:
  bool final_locked(std::uint32_t id) {
    const auto it = states_.find(id);
    return it != states_.end() && !it->second.empty() &&
           it->second.back().state() != COMMAND_ACCEPTED;
  }
  std::mutex mutex_;
  std::condition_variable changed_;
  std::map<std::uint32_t, std::vector<CommandStatus>> states_;
};

const char* state_name(CommandState state) {
  switch (state) {
    case COMMAND_ACCEPTED:
      return "ACCEPTED";
    case COMMAND_REJECTED:
      return "REJECTED";
    case COMMAND_COMPLETED:
      return "COMPLETED";
    case COMMAND_TIMED_OUT:
      return "TIMED_OUT";
    case COMMAND_SUPERSEDED:
      return "SUPERSEDED";
  }
  return "?";
}

bool is_run(CommandKind kind) {
  return kind == COMMAND_STOP || kind == COMMAND_MANUAL || kind == COMMAND_TARGET_DEGREES ||
         kind == COMMAND_DEGREES_FROM_POSITION || kind == COMMAND_CLEAR_ERRORS ||
         kind == COMMAND_MILLISECONDS_TO_RUN;
}

struct Case {
  std::string name;
  ValveCommand command;
  bool rejected;  // expected REJECTED; otherwise any final state after ACCEPTED
};

using teejet::testing::command;
using teejet::testing::move_to;

std::vector<Case> hostile_cases(std::uint32_t valve, std::uint32_t unknown) {
  std::vector<Case> cases;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  for (const auto& [name, degrees] :
       std::vector<std::pair<std::string, float>>{{"target-nan", nan},
                                                  {"target-inf", inf},
                                                  {"target-minus-inf", -inf},
                                                  {"target-negative", -0.1f},
                                                  {"target-360", 360.0f},
                                                  {"target-huge", 1e30f},
                                                  {"target-minus-huge", -1e30f}}) {
    cases.push_back({name, move_to(valve, degrees), true});
    auto relative = command(valve, COMMAND_DEGREES_FROM_POSITION);
    relative.degrees(degrees);
    cases.push_back({"relative-" + name.substr(7), relative, true});
  }
  for (const auto kind : {COMMAND_MANUAL, COMMAND_TARGET_DEGREES, COMMAND_DEGREES_FROM_POSITION,
                          COMMAND_MILLISECONDS_TO_RUN}) {
    auto fast = command(valve, kind);
    fast.degrees(10.0f);
    fast.speed_percent(255);
    cases.push_back({"speed-255-kind-" + std::to_string(kind), fast, true});
    auto over = fast;
    over.speed_percent(101);
    cases.push_back({"speed-101-kind-" + std::to_string(kind), over, true});
  }
  cases.push_back({"kind-42", command(valve, static_cast<CommandKind>(42)), true});
  auto direction = move_to(valve, 10.0f);
  direction.direction(static_cast<Direction>(7));
  cases.push_back({"direction-7", direction, true});
  auto manual_direction = command(valve, COMMAND_MANUAL);
  manual_direction.direction(static_cast<Direction>(0x7FFFFFFF));
  cases.push_back({"manual-direction-max", manual_direction, true});
  auto shortest_manual = command(valve, COMMAND_MANUAL);
  shortest_manual.direction(DIRECTION_SHORTEST);
  cases.push_back({"manual-direction-shortest", shortest_manual, true});
  auto telemetry = command(valve, COMMAND_REQUEST);
  telemetry.telemetry(static_cast<Telemetry>(99));
  cases.push_back({"telemetry-99", telemetry, true});
  auto version = command(valve, COMMAND_REQUEST);
  version.telemetry(TELEMETRY_VERSION);
  version.resend_tenths(1);
  cases.push_back({"version-resend-1", version, true});
  version.resend_tenths(255);
  cases.push_back({"version-resend-255", version, true});
  auto baud = command(valve, COMMAND_SET_BAUD_RATE);
  baud.bit_rate(125000);
  cases.push_back({"set-baud-rate", baud, true});
  cases.push_back({"unknown-serial", move_to(unknown, 10.0f), true});
  // At the limits, and sent.
  auto zero_ms = command(valve, COMMAND_MILLISECONDS_TO_RUN);
  zero_ms.milliseconds(0);
  cases.push_back({"milliseconds-0", zero_ms, false});
  auto longest = command(valve, COMMAND_MILLISECONDS_TO_RUN);
  longest.milliseconds(65535);
  longest.speed_percent(1);
  cases.push_back({"milliseconds-65535", longest, false});  // superseded by the next
  auto still = move_to(valve, 60.0f);
  still.speed_percent(0);
  cases.push_back({"speed-0", still, false});
  cases.push_back({"target-359.9", move_to(valve, 359.9f), false});
  cases.push_back({"stop", command(valve, COMMAND_STOP), false});
  auto slowest = command(valve, COMMAND_REQUEST);
  slowest.telemetry(TELEMETRY_TEMPERATURE);
  slowest.resend_tenths(255);
  cases.push_back({"temperature-resend-255", slowest, false});
  auto restore = command(valve, COMMAND_REQUEST);
  restore.telemetry(TELEMETRY_TEMPERATURE);
  restore.resend_tenths(10);
  cases.push_back({"temperature-resend-10", restore, false});
  return cases;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 5 && argc != 6) {
    std::fprintf(stderr, "usage: hostile_writer DOMAIN SERIAL_1 SERIAL_2 UNKNOWN_SERIAL [FLOOD]\n");
    return 2;
  }
  // Line by line: a script that has to kill a stuck writer still sees how far it got.
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  const int flood = argc == 6 ? std::atoi(argv[5]) : 10'000;
  const int domain = std::atoi(argv[1]);
  const auto valve_1 = static_cast<std::uint32_t>(std::atoi(argv[2]));
  const auto valve_2 = static_cast<std::uint32_t>(std::atoi(argv[3]));
  const auto unknown = static_cast<std::uint32_t>(std::atoi(argv[4]));

  auto participant = teejet::dds::Participant::create({.domain = domain, .name = "hostile-writer"});
  if (!participant) {
    std::fprintf(stderr, "hostile_writer: %s\n", participant.error().reason.c_str());
    return 1;
  }
  auto& p = **participant;
  auto status_topic = p.topic<CommandStatusPubSubType>(teejet::dds::topics::kCommandStatus);
  auto command_topic = p.topic<ValveCommandPubSubType>(teejet::dds::topics::kCommand);
  if (!status_topic || !command_topic) return 1;
  Statuses statuses;
  auto qos = teejet::dds::topics::status_reader_qos();
  qos.history().kind = eprosima::fastdds::dds::KEEP_ALL_HISTORY_QOS;
  // A flood's statuses, for the few valves here (max_samples must cover them all).
  qos.resource_limits().max_instances = 16;
  qos.resource_limits().max_samples_per_instance = 30'000;
  qos.resource_limits().max_samples = 16 * 30'000;
  auto reader =
      p.reader(*status_topic, qos, &statuses, eprosima::fastdds::dds::StatusMask::data_available());
  auto writer = p.writer(*command_topic, teejet::dds::topics::command_writer_qos());
  if (!reader || !writer) return 1;
  // Both halves matched before the first command: commands are VOLATILE.
  const auto match_until = within(30s);
  for (;;) {
    eprosima::fastdds::dds::PublicationMatchedStatus commands;
    eprosima::fastdds::dds::SubscriptionMatchedStatus status;
    (*writer)->get_publication_matched_status(commands);
    (*reader)->get_subscription_matched_status(status);
    if (commands.current_count > 0 && status.current_count > 0) break;
    if (std::chrono::steady_clock::now() > match_until) {
      std::fprintf(stderr, "hostile_writer: no gateway matched in 30 s\n");
      return 1;
    }
    std::this_thread::sleep_for(10ms);
  }

  std::uint32_t next_id = 0;
  std::vector<std::uint32_t> sent;
  std::map<std::uint32_t, ValveCommand> commands;
  int unexpected = 0;
  const auto write = [&](ValveCommand c) {
    c.origin(kOrigin);
    c.command_id(++next_id);
    if (!(*writer)->write(&c)) return std::uint32_t{0};
    sent.push_back(c.command_id());
    commands[c.command_id()] = c;
    return c.command_id();
  };

  // 1. Every hostile case, one at a time.
  for (const auto& hostile : hostile_cases(valve_1, unknown)) {
    const auto id = write(hostile.command);
    const auto until = within(10s);
    const bool runs_on = hostile.name == "milliseconds-65535";
    const auto got = id == 0   ? std::vector<CommandStatus>{}
                     : runs_on ? statuses.first(id, until)
                               : statuses.follow(id, until);
    std::string states;
    for (const auto& s : got)
      states += std::string(states.empty() ? "" : ",") + state_name(s.state());
    const bool final = !got.empty() && got.back().state() != COMMAND_ACCEPTED;
    const bool rejected = got.size() == 1 && got[0].state() == COMMAND_REJECTED;
    // "milliseconds-65535" ends only when the next command supersedes it.
    const bool as_expected =
        hostile.rejected
            ? rejected
            : (!got.empty() && got[0].state() == COMMAND_ACCEPTED && (final || runs_on));
    if (!as_expected) ++unexpected;
    std::printf("case %s id %u serial %u expect %s got %s reason \"%s\"%s\n", hostile.name.c_str(),
                id, hostile.command.serial(), hostile.rejected ? "rejected" : "final",
                states.empty() ? "nothing" : states.c_str(),
                got.empty() ? "" : got.back().reason().c_str(), as_expected ? "" : " UNEXPECTED");
  }

  // 2. A flood: `flood` moves to valve 1 at up to 10,000 a second, a move of valve 2 amid it.
  const auto flood_start = std::chrono::steady_clock::now();
  std::uint32_t refused = 0, valve_2_move = 0;
  const std::uint32_t first_flood_id = next_id + 1;
  for (int i = 1; i <= flood; ++i) {
    if (write(move_to(valve_1, i % 2 ? 80.0f : 10.0f)) == 0) ++refused;
    if (i == flood / 2) valve_2_move = write(move_to(valve_2, 45.0f));
    std::this_thread::sleep_until(flood_start + i * 100us);
  }
  const std::uint32_t last_flood_id = next_id;
  const double flood_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - flood_start).count();
  const auto moved = statuses.follow(valve_2_move, within(30s));
  const bool valve_2_done = moved.size() == 2 && moved[1].state() == COMMAND_COMPLETED;
  if (!valve_2_done) ++unexpected;
  std::printf("flood of %d written in %.2f s, %u refused by DDS; valve 2 moved amid it: %s\n",
              flood, flood_s, refused, valve_2_done ? "COMPLETED" : "NOT COMPLETED UNEXPECTED");

  // Every command written must have a final status (the flood's before the good moves).
  const auto until = within(30s);
  std::size_t missing = 0, flood_missing = 0;
  std::map<std::string, std::size_t> tally;
  std::map<std::uint32_t, std::size_t> run_frames;
  for (const auto id : sent) {
    const auto got = statuses.follow(id, until);
    if (got.empty() || got.back().state() == COMMAND_ACCEPTED) {
      ++missing;
      if (id >= first_flood_id && id <= last_flood_id && id != valve_2_move) ++flood_missing;
      continue;
    }
    std::string states;
    for (const auto& s : got)
      states += std::string(states.empty() ? "" : ",") + state_name(s.state());
    ++tally[states];
    if (got.front().state() == COMMAND_ACCEPTED && is_run(commands[id].kind())) {
      ++run_frames[commands[id].serial()];
    }
    if (got.size() > 2) ++unexpected;
  }
  // 3. Good moves afterwards, once the flood is over: the flooded valve takes commands again.
  std::this_thread::sleep_for(300ms);  // the rate limit's refill, not a wait for an event
  for (const auto& [serial, degrees] : {std::pair{valve_1, 45.0f}, std::pair{valve_2, 20.0f}}) {
    const auto id = write(move_to(serial, degrees));
    const auto got = statuses.follow(id, within(15s));
    const bool done = got.size() == 2 && got[1].state() == COMMAND_COMPLETED;
    if (!done) ++unexpected;
    if (!got.empty() && got.front().state() == COMMAND_ACCEPTED) ++run_frames[serial];
    std::printf("good move of %u to %.1f: %s\n", serial, static_cast<double>(degrees),
                done ? "COMPLETED" : "NOT COMPLETED UNEXPECTED");
  }

  for (const auto& [states, n] : tally) std::printf("ended %s %zu\n", states.c_str(), n);
  for (const auto serial : {valve_1, valve_2}) {
    std::printf("run_frames %u %zu\n", serial, run_frames[serial]);
  }
  std::printf("summary sent %zu final %zu missing %zu unexpected %d\n", sent.size(),
              sent.size() - missing, missing, unexpected);
  std::printf("flood_missing %zu\n", flood_missing);
  std::fflush(stdout);
  return missing == flood_missing && unexpected == 0 ? 0 : 1;
}
