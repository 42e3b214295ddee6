#include "session.hpp"

#include <algorithm>
#include <cmath>
#include <ctime>
#include <iomanip>
#include <optional>
#include <ostream>
#include <set>
#include <sstream>
#include <variant>
#include <vector>

#include "exit_codes.hpp"
#include "render.hpp"
#include "teejet/client/command_client.hpp"
#include "teejet/client/valve_view.hpp"
#include "teejet/codec/table.hpp"
#include "teejet/dds/conversions.hpp"
#include "teejet/dds/tcp_rejoin.hpp"
#include "teejet/dds/topics.hpp"

namespace teejet::valvectl {

using namespace client;

namespace {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

// After the directory is complete, how long `list` waits for online valves' first telemetry.
constexpr milliseconds kTelemetryGrace{1000};
// A reply sample is published right after the status that completes its request.
constexpr milliseconds kReplyGrace{1000};
// How often a waiting command looks at the valve's position to show progress.
constexpr milliseconds kProgressPeriod{100};
// How long a run without --command-readers waits for its commands' acknowledgements on exit.
constexpr milliseconds kDeliveryWait{1000};
// identify: how far each jog goes, how many there are, and how long one may take at most.
constexpr double kJogDegrees = 10.0;
constexpr int kJogs = 2;
constexpr milliseconds kJogTimeout{30000};
// Longest wait before watch's first frame, so it does not start with an empty table.
constexpr milliseconds kWatchFirstFrame{2000};
// The lease valvectl announces: longer than the run, so that the gateways and the other
// clients never check it before it leaves (Fast DDS 2.9.1 may abort a peer that removes a
// leaving participant while checking its lease; docs/topics.md, "Short-lived participants"):
// at least 30 s, and 10 s more than a run may wait in all, which every wait is held to (watch
// and its Ctrl-C excepted: a watch is a long-lived participant). A command may wait --timeout
// for its valves, for their gateways' readers, for its first statuses and for its readers'
// acknowledgements, then --wait-timeout for its final statuses; a layout change three times.
// valvectl's fail-safe does not rest on it: a run that is killed leaves no valve running for
// long (moves and jogs end by themselves; `manual` exits once the valve runs, as it would in
// order), and its command writer's liveliness (2 s) reports it when it is the only commander.
constexpr std::chrono::seconds kValvectlLease{30};
constexpr std::chrono::seconds kLeaseBeyondTheRun{10};
// valvectl's periodic announcement: its lease is at least 30 s, and it meets the programs
// already running without it (ParticipantOptions::least_announcement_period); one started later
// meets it at its next, as it sits beyond the initial peers (outside_initial_peers).
constexpr std::chrono::seconds kAnnouncement{2};

std::chrono::seconds lease_for(const Invocation& invocation) {
  std::chrono::milliseconds longest = invocation.global.timeout;
  if (invocation.subcommand == Subcommand::kCommand ||
      invocation.subcommand == Subcommand::kLayoutChange) {
    longest = 4 * invocation.global.timeout;
  }
  if (invocation.subcommand == Subcommand::kCommand && invocation.command.wait) {
    longest += invocation.command.wait_timeout;
  }
  if (invocation.subcommand == Subcommand::kIdentify) longest += 2 * kJogs * kJogTimeout;
  return std::max(kValvectlLease,
                  std::chrono::ceil<std::chrono::seconds>(longest) + kLeaseBeyondTheRun);
}

bool shows_progress(CommandKind kind) {
  return kind == COMMAND_TARGET_DEGREES || kind == COMMAND_DEGREES_FROM_POSITION ||
         kind == COMMAND_MILLISECONDS_TO_RUN;
}

// The subject of the reply a completed request's answer arrives as, if it is a request.
std::optional<std::string> awaited_reply(const ValveCommand& command) {
  if (command.kind() != COMMAND_REQUEST && command.kind() != COMMAND_REQUEST_BAUD_RATE) {
    return std::nullopt;
  }
  const auto message = dds::to_message(command);
  if (!message) return std::nullopt;
  return std::string(codec::subject(*message));
}

// Whether a waiting command shows the position as the valve moves: to a person at a terminal,
// or when asked (--progress). Every gateway sends a follower of positions each of its valves'
// ten a second (the serial filter drops the others only on arrival, topics.md): scripts and the
// many commands of a test rig get only the final position, read once the command completes.
bool follows_progress(const Invocation& invocation, bool out_is_tty) {
  const CommandRequest& request = invocation.command;
  return invocation.subcommand == Subcommand::kCommand && request.wait &&
         shows_progress(request.command.kind()) && (out_is_tty || request.progress);
}

// What a run follows: a list or a watch the columns it prints and the errors (everything into
// JSON); a command or a layout change the directory, with the position it shows while it waits
// and the reply it awaits, of the valves named on the command line only when it names them.
// Each topic followed is one more sample per valve that every gateway sends this client as it
// joins; each valve's position ten more a second to take.
ViewTopics topics_for(const Invocation& invocation, bool out_is_tty) {
  switch (invocation.subcommand) {
    case Subcommand::kList:
    case Subcommand::kWatch:
      if (invocation.global.json) return {};
      return {.everything = false, .telemetry = column_subjects(), .errors = true};
    case Subcommand::kLayoutChange:
      return {.everything = false};
    case Subcommand::kIdentify:
      return {.everything = false, .telemetry = {dds::topics::telemetry_subject<ValvePosition>()}};
    case Subcommand::kCommand: {
      const CommandRequest& request = invocation.command;
      ViewTopics topics{.everything = false,
                        .serials = {request.serials.begin(), request.serials.end()}};
      if (follows_progress(invocation, out_is_tty)) {
        topics.telemetry.insert(dds::topics::telemetry_subject<ValvePosition>());
      }
      if (const auto reply = awaited_reply(request.command)) topics.telemetry.insert(*reply);
      return topics;
    }
    default:
      return {};
  }
}

std::string seconds_text(milliseconds duration) {
  std::ostringstream text;
  text << std::chrono::duration<double>(duration).count() << " s";
  return text.str();
}

// Thrown when joining again fails (said already): nothing of the session is left to use.
struct JoinFailed {};

class Session {
 public:
  // Joins the domain and subscribes; an Error says what DDS refused.
  static Result<std::unique_ptr<Session>> create(const Invocation& invocation,
                                                 const Terminal& terminal) {
    std::unique_ptr<Session> session(new Session(invocation, terminal));
    if (auto joined = session->join(); !joined) return joined.error();
    return session;
  }

  int run() {
    switch (invocation_.subcommand) {
      case Subcommand::kList:
        return list();
      case Subcommand::kWatch:
        return watch();
      case Subcommand::kLayout:
        return layout();
      case Subcommand::kNeighbours:
        return neighbours();
      case Subcommand::kLayoutChange:
        return layout_change();
      case Subcommand::kIdentify:
        return identify();
      case Subcommand::kCommand:
        return command();
    }
    return kExitFailure;
  }

 private:
  // ---- Output --------------------------------------------------------------------------

  // One line per event, flushed at once: scripts read valvectl's output as it happens.
  void emit(const std::string& text, const nlohmann::json& json) {
    terminal_.out << (invocation_.global.json ? json.dump() : text) << '\n' << std::flush;
  }

  void complain(const std::string& message) {
    terminal_.err << "valvectl: " << message;
    if (Clock::now() >= run_ends_) {
      terminal_.err << " (its whole run is held to "
                    << seconds_text(std::chrono::duration_cast<milliseconds>(run_ends_ - started_))
                    << ", within the lease it announced)";
    }
    terminal_.err << '\n' << std::flush;
  }

  std::string domain_text() const { return "domain " + std::to_string(invocation_.global.domain); }

  // Says how far discovery got, so that "nothing on the network" (or another profile or domain)
  // and "a gateway that did not answer" read differently.
  std::string no_gateway_text(const ValveTable& table) const {
    std::string text = "no gateway found on " + domain_text() + " within " +
                       seconds_text(invocation_.global.timeout) + ": discovery met ";
    const std::size_t met = table.participants_met();
    if (met == 0) return text + "no other participant (check the network, --profile and --domain)";
    text += std::to_string(met) + (met == 1 ? " participant, " : " participants, ");
    const std::size_t gateways = table.gateway_participants();
    if (gateways == 0) return text + (met == 1 ? "not a gateway" : "none of them a gateway");
    return text + std::to_string(gateways) + (gateways == 1 ? " gateway" : " gateways") +
           " whose topics did not match";
  }

  // One participant and the view through it, made afresh by a rejoin.
  Result<void> join() {
    auto participant = dds::Participant::create({.domain = invocation_.global.domain,
                                                 .profile_file = invocation_.global.profile_file,
                                                 .name = "valvectl",
                                                 .minimum_lease = lease_for(invocation_),
                                                 .least_announcement_period = kAnnouncement,
                                                 .outside_initial_peers = true});
    if (!participant) return participant.error();
    auto view = ValveView::create(**participant, topics_for(invocation_, terminal_.out_is_tty));
    if (!view) return view.error();
    participant_ = std::move(*participant);
    view_ = std::move(*view);
    rejoin_.joined(Clock::now());
    return {};
  }

  // view_.wait_until, replacing a participant stalled over TCP (dds::TcpRejoin) meanwhile.
  bool wait_until(const ValveView::Condition& condition, Deadline until) {
    for (;;) {
      if (view_->wait_until(condition, std::min(until, rejoin_.due()), terminal_.interrupted)) {
        return true;
      }
      if (terminal_.interrupted || Clock::now() >= until) return false;
      if (rejoin_.replace(*participant_, Clock::now())) rejoin();
    }
  }

  void rejoin() {
    terminal_.err << "valvectl: met no gateway within "
                  << seconds_text(std::chrono::duration_cast<milliseconds>(rejoin_.waited()))
                  << " over TCP; joining " << domain_text() << " again\n"
                  << std::flush;
    // The old participant goes first: a new one that met it leaving would be in the very
    // situation that stalls it.
    view_.reset();
    participant_.reset();
    if (auto joined = join(); !joined) {
      // It joined once with the same settings: a refusal now ends the run, as one at the start.
      complain("cannot join again: " + joined.error().reason);
      throw JoinFailed{};
    }
  }

  // Every wait ends by the end of the run the lease covers.
  Deadline within_run(Deadline until) const { return std::min(until, run_ends_); }
  Deadline after(milliseconds wait) const { return within_run(Clock::now() + wait); }
  Deadline after_timeout() const { return after(invocation_.global.timeout); }

  bool discover_directory(Deadline until) {
    return wait_until([](const ValveTable& table) { return table.directory_complete(); }, until);
  }

  // ---- list and watch --------------------------------------------------------------------

  int list() {
    const Deadline until = after_timeout();
    const unsigned wanted = invocation_.list.wait_for_online;
    const bool complete = wait_until(
        [&](const ValveTable& table) {
          return table.directory_complete() && table.online_count() >= wanted;
        },
        until);
    if (terminal_.interrupted) return kExitInterrupted;
    if (complete) {
      // Telemetry is durable too and follows presence closely; do not print a row of dashes
      // for a valve whose values are on their way.
      wait_until([](const ValveTable& table) { return table.telemetry_complete(); },
                 std::min(until, after(kTelemetryGrace)));
    }
    const ValveTable table = view_->snapshot();
    if (table.empty()) {
      complain(no_gateway_text(table));
      return kExitNotFound;
    }
    print_table(table, /*with_gateways=*/false);
    if (table.online_count() < wanted) {
      complain("only " + std::to_string(table.online_count()) + " of " + std::to_string(wanted) +
               " valves are online on " + domain_text() + " after " +
               seconds_text(invocation_.global.timeout));
      return kExitNotFound;
    }
    return kExitOk;
  }

  int layout() {
    discover_directory(after_timeout());
    if (terminal_.interrupted) return kExitInterrupted;
    wait_until([](const ValveTable& table) { return table.telemetry_complete(); },
               after(kTelemetryGrace));
    const ValveTable table = view_->snapshot();
    if (table.empty()) {
      complain(no_gateway_text(table));
      return kExitNotFound;
    }
    if (table.locations().empty()) {
      complain("no gateway on " + domain_text() + " has a layout (docs/layout.md)");
      return kExitNotFound;
    }
    if (invocation_.global.json) {
      terminal_.out << layout_json(table).dump() << '\n';
    } else {
      terminal_.out << render_layout(table);
    }
    terminal_.out << std::flush;
    return kExitOk;
  }

  int neighbours() {
    discover_directory(after_timeout());
    if (terminal_.interrupted) return kExitInterrupted;
    const ValveTable table = view_->snapshot();
    if (table.gateways().empty()) {
      complain(no_gateway_text(table));
      return kExitNotFound;
    }
    if (invocation_.global.json) {
      terminal_.out << neighbours_json(table.gateways()).dump() << '\n';
    } else {
      terminal_.out << render_gateways(table.gateways())
                    << render_neighbours(table.gateways(), system_clock()->wall());
    }
    terminal_.out << std::flush;
    return kExitOk;
  }

  // A client of `Request`s whose writer and status reader every gateway in `owners` has matched
  // (and `readers` command readers in all), or the exit status that says why not; nothing is
  // sent then. `unmatched(client)` says which owners did not subscribe.
  template <class Request, class Unmatched>
  std::variant<std::unique_ptr<RequestClient<Request>>, int> connected_client(
      const std::set<std::string>& owners, std::size_t readers, Unmatched unmatched) {
    rejoin_.keep();  // the command client holds it
    auto made = RequestClient<Request>::create(*participant_, default_origin("valvectl"));
    if (!made) {
      complain(made.error().reason);
      return kExitFailure;
    }
    const auto connected =
        (*made)->connect(owners, readers, after_timeout(), terminal_.interrupted);
    if (!connected) {
      complain(connected.error().reason);
      return kExitFailure;
    }
    if (!*connected) {
      if (terminal_.interrupted) return kExitInterrupted;
      complain(unmatched(**made));
      return kExitNotFound;
    }
    return std::move(*made);
  }

  // The one place called `name` among the gateways' layouts, or the exit status that says why
  // there is none: no gateway has it, or two claim it (nothing is sent to either).
  std::variant<LocationRow, int> find_place(const std::string& name, Deadline until) {
    const auto named = [&](const ValveTable& table) { return table.locations_named(name); };
    wait_until(
        [&](const ValveTable& table) {
          return table.directory_complete() && !named(table).empty();
        },
        until);
    if (terminal_.interrupted) return kExitInterrupted;
    const ValveTable table = view_->snapshot();
    const auto places = named(table);
    if (table.empty()) {
      complain(no_gateway_text(table));
      return kExitNotFound;
    }
    if (places.empty()) {
      complain("no gateway on " + domain_text() + " has a location '" + name + "' in its layout" +
               (table.directory_complete() ? "" : " (discovery was still going on)"));
      return kExitNotFound;
    }
    if (places.size() > 1) {
      complain("location '" + name + "' is in the layouts of " + std::to_string(places.size()) +
               " gateways (" + gateway_names(places) +
               "): a name belongs to one; rename it in all but one layout. Nothing was sent");
      return kExitRejected;
    }
    return places.front();
  }

  // assign and unassign: to the one gateway whose layout holds the place.
  int layout_change() {
    const LayoutChangeRequest& request = invocation_.layout_change;
    auto found = find_place(request.location, after_timeout());
    if (const int* exit_code = std::get_if<int>(&found)) return *exit_code;
    const LocationRow& place = std::get<LocationRow>(found);
    auto made = connected_client<LayoutChange>({place.participant}, 0, [&](const LayoutClient&) {
      return "gateway " + place.gateway + " did not subscribe to layout changes within " +
             seconds_text(invocation_.global.timeout) + " on " + domain_text() +
             "; nothing was sent";
    });
    if (const int* exit_code = std::get_if<int>(&made)) return *exit_code;
    LayoutClient& client = *std::get<std::unique_ptr<LayoutClient>>(made);
    const auto id =
        client.send(layout_change_of(place, request.kind, request.serial, request.move));
    if (!id) {
      complain("could not write the layout change");
      return kExitFailure;
    }
    const auto status = client.next_status(*id, after_timeout());
    if (!status) {
      complain("no answer from gateway " + place.gateway + " to the layout change of '" +
               request.location + "' within " + seconds_text(invocation_.global.timeout));
      return kExitTimedOut;
    }
    emit(layout_change_text(*status), status_json(*status));
    return status->state() == LAYOUT_CHANGE_APPLIED ? kExitOk : kExitRejected;
  }

  void print_table(const ValveTable& table, bool with_gateways) {
    if (invocation_.global.json) {
      terminal_.out << to_json(table.rows()).dump() << '\n';
    } else {
      if (with_gateways) terminal_.out << render_gateways(table.gateways());
      terminal_.out << render_table(table.rows());
    }
    terminal_.out << std::flush;
  }

  int watch() {
    const auto started = Clock::now();
    const Deadline end =
        invocation_.watch.duration ? started + *invocation_.watch.duration : Deadline::max();
    const auto never = [](const ValveTable&) { return false; };
    discover_directory(std::min({after_timeout(), Deadline(started + kWatchFirstFrame), end}));
    for (auto next = Clock::now();;) {
      if (terminal_.interrupted) return kExitOk;  // Ctrl-C is how a watch normally ends
      draw_frame();
      if (Clock::now() >= end) return kExitOk;
      // Keep the rhythm, but never try to catch up on frames a slow terminal made us miss.
      next = std::max(next + invocation_.watch.interval, Clock::now());
      wait_until(never, std::min(next, end));
    }
  }

  void draw_frame() {
    const ValveTable table = view_->snapshot();
    if (!invocation_.global.json) {
      if (terminal_.out_is_tty) terminal_.out << "\x1b[H\x1b[2J";  // home, clear screen
      const std::time_t now = std::time(nullptr);
      std::tm local{};
      localtime_r(&now, &local);
      if (!invocation_.watch.title.empty()) terminal_.out << invocation_.watch.title << '\n';
      terminal_.out << "valvectl watch: " << domain_text() << ", "
                    << std::put_time(&local, "%H:%M:%S") << '\n';
      if (table.empty()) terminal_.out << "no gateway found yet\n";
    }
    print_table(table, /*with_gateways=*/true);
    // Into a pipe or file, frames follow each other: a blank line tells them apart.
    if (!invocation_.global.json && !terminal_.out_is_tty) terminal_.out << '\n' << std::flush;
  }

  // ---- identify ------------------------------------------------------------------------

  // Two jogs of kJogDegrees out and back with Target Degrees, within the place's mechanics (or
  // inside 0..359.9), each followed to COMPLETED; the valve ends where it started.
  int identify() {
    auto targets = find_targets();
    if (const int* exit_code = std::get_if<int>(&targets)) return *exit_code;
    const std::uint32_t serial = std::get<std::vector<std::uint32_t>>(targets).front();
    const std::string valve = codec::format_serial(serial);
    wait_until(
        [&](const ValveTable& table) {
          const auto row = table.row(serial);
          return row && row->position_degrees();
        },
        after_timeout());
    if (terminal_.interrupted) return kExitInterrupted;
    const ValveTable table = view_->snapshot();
    const auto row = table.row(serial);
    if (!row || !row->online || row->gateway_lost) {
      complain(valve + " is not online: nothing to identify");
      return kExitNotFound;
    }
    if (!row->position_degrees()) {
      complain("no position from " + valve + " within " + seconds_text(invocation_.global.timeout) +
               "; it was not moved");
      return kExitTimedOut;
    }
    const double start = *row->position_degrees();
    double low = 0.0;
    double high = 359.9;
    for (const auto& place : table.locations()) {
      if (place.serial == serial && place.opened_degrees && *place.opened_degrees < 360.0) {
        low = *place.closed_degrees;
        high = *place.opened_degrees;
      }
    }
    const bool out_opens = start + kJogDegrees <= high || start - kJogDegrees < low;
    const double out = std::clamp(start + (out_opens ? kJogDegrees : -kJogDegrees), low, high);

    auto made = connected_client<ValveCommand>({row->participant}, 0, [&](const CommandClient&) {
      return "gateway " + row->gateway + " did not subscribe to commands within " +
             seconds_text(invocation_.global.timeout) + "; it was not moved";
    });
    if (const int* exit_code = std::get_if<int>(&made)) return *exit_code;
    CommandClient& client = *std::get<std::unique_ptr<CommandClient>>(made);
    for (int jog = 0; jog < kJogs; ++jog) {
      for (const auto& [to, opening] : {std::pair{out, out_opens}, std::pair{start, !out_opens}}) {
        if (const int failed = jog_to(client, serial, to, opening); failed != kExitOk) {
          return failed;
        }
      }
    }
    const auto place = row->location.empty() ? std::string() : " at " + row->location;
    emit(valve + place + ": identified, back at " + one_decimal(start),
         {{"event", "identified"},
          {"serial", valve},
          {"location", row->location},
          {"degrees", start}});
    return kExitOk;
  }

  // One Target Degrees of identify, followed to its final status.
  int jog_to(CommandClient& client, std::uint32_t serial, double degrees, bool opening) {
    ValveCommand command;
    command.serial(serial);
    command.kind(COMMAND_TARGET_DEGREES);
    command.speed_percent(100);
    command.direction(opening ? DIRECTION_OPEN : DIRECTION_CLOSE);
    command.degrees(static_cast<float>(std::round(degrees * 10.0) / 10.0));
    const auto id = client.send(command);
    if (!id) {
      complain("could not write the command for " + codec::format_serial(serial));
      return kExitFailure;
    }
    const Deadline until = after(kJogTimeout);
    while (true) {
      const auto status = client.next_status(*id, until);
      if (!status) {
        complain("no final status for command #" + std::to_string(*id) + " to " +
                 codec::format_serial(serial) + " within " + seconds_text(kJogTimeout));
        return kExitTimedOut;
      }
      emit(status_text(*status), status_json(*status));
      if (status->state() == COMMAND_ACCEPTED) continue;
      return exit_code_of(status->state());
    }
  }

  // ---- Commands --------------------------------------------------------------------------

  // The serials to command, or the exit status that says why there are none.
  std::variant<std::vector<std::uint32_t>, int> find_targets() {
    const CommandRequest& request = invocation_.command;
    const Deadline until = after_timeout();
    if (request.every_online_valve) {
      discover_directory(until);
      if (terminal_.interrupted) return kExitInterrupted;
      const ValveTable table = view_->snapshot();
      if (table.empty()) {
        complain(no_gateway_text(table));
        return kExitNotFound;
      }
      const std::string& only = request.only_gateway;
      if (!only.empty()) {
        const auto gateways = table.gateways();
        if (std::none_of(gateways.begin(), gateways.end(),
                         [&](const GatewaySummary& gateway) { return gateway.name == only; })) {
          complain("no gateway called \"" + only + "\" on " + domain_text() + " (met " +
                   std::to_string(gateways.size()) + ")");
          return kExitNotFound;
        }
      }
      std::vector<std::uint32_t> online;
      for (const ValveRow& row : table.rows()) {
        if (row.online && !row.gateway_lost && (only.empty() || row.gateway == only)) {
          online.push_back(row.serial);
        }
      }
      if (online.empty()) {
        complain("no valve is online on " + (only.empty() ? domain_text() : "gateway " + only));
      }
      return online;
    }
    std::vector<std::uint32_t> serials = request.serials;
    std::string located;  // what the serial of a location given is called in messages
    if (!request.location.empty()) {
      auto place = find_place(request.location, until);
      if (const int* exit_code = std::get_if<int>(&place)) return *exit_code;
      const LocationRow& row = std::get<LocationRow>(place);
      if (!row.serial) {
        complain(row.name + " on " + row.gateway +
                 " is empty: no valve sits there (valvectl "
                 "assign puts one there)");
        return kExitNotFound;
      }
      located = " (at " + row.name + ")";
      serials = {*row.serial};
    }
    for (const std::uint32_t serial : serials) {
      // Done when the valve shows up, or early when every gateway has told all it knows.
      wait_until(
          [&](const ValveTable& table) { return table.row(serial) || table.directory_complete(); },
          until);
      if (terminal_.interrupted) return kExitInterrupted;
      const ValveTable table = view_->snapshot();
      if (table.row(serial)) continue;
      complain(not_found_text(table, serial) + located);
      return kExitNotFound;
    }
    return serials;
  }

  // Why `serial` is not in `table`, saying how far discovery got: a valve is called unknown
  // only when every gateway there is to meet has told all it knows.
  std::string not_found_text(const ValveTable& table, std::uint32_t serial) const {
    if (table.empty()) return no_gateway_text(table);
    const auto met = table.gateways().size();
    const auto valves = std::to_string(table.rows().size()) + " valves";
    if (table.directory_complete()) {
      return "valve " + codec::format_serial(serial) + " is not known to any of the " +
             std::to_string(met) + " gateway(s) on " + domain_text() + " (" + valves + ")";
    }
    return "valve " + codec::format_serial(serial) + " was not found within " +
           seconds_text(invocation_.global.timeout) + " on " + domain_text() + ": met " +
           std::to_string(met) + " of " + std::to_string(table.gateways_expected()) +
           " gateway(s), " + valves + "; discovery was still going on (try a longer --timeout)";
  }

  int command() {
    auto targets = find_targets();
    if (const int* exit_code = std::get_if<int>(&targets)) return *exit_code;
    const auto& serials = std::get<std::vector<std::uint32_t>>(targets);
    if (serials.empty()) return kExitOk;

    // Every gateway that owns one of the valves must hear the command: its own reader, not
    // just as many readers as there are owners.
    const ValveTable table = view_->snapshot();
    // Found: the directory has told what it had to. Followed on, every gateway would send this
    // client each of its valves' I'm Here once a second for as long as it waits, and a hundred
    // waiting clients overflowed the gateways' sockets on two cores (docs/performance.md).
    view_->stop_following_presence();
    std::set<std::string> owners;
    for (const std::uint32_t serial : serials) owners.insert(table.row(serial)->participant);
    owners.erase(std::string{});

    auto made = connected_client<ValveCommand>(
        owners, invocation_.global.command_readers, [&](const CommandClient& unmatched) {
          return unmatched_text(table, serials, unmatched.unmatched(owners));
        });
    if (const int* exit_code = std::get_if<int>(&made)) return *exit_code;
    CommandClient& client = *std::get<std::unique_ptr<CommandClient>>(made);
    std::vector<std::pair<std::uint32_t, std::uint32_t>> sent;  // serial, command id
    for (const std::uint32_t serial : serials) {
      ValveCommand command = invocation_.command.command;
      command.serial(serial);
      const auto id = client.send(command);
      if (!id) {
        complain("could not write the command for " + codec::format_serial(serial));
        return kExitFailure;
      }
      sent.emplace_back(serial, *id);
    }
    const std::set<std::uint32_t> sent_to(serials.begin(), serials.end());
    int worst = kExitOk;
    for (const auto& [serial, id] : sent) {
      worst = std::max(worst, follow(client, serial, id, sent_to));
    }
    if (terminal_.interrupted) return worst;
    // Exiting deletes the writer, and with it the commands a late reader has yet to repair.
    // Asked-for readers (a recorder that must hold every command) get the whole --timeout.
    const bool readers_asked = invocation_.global.command_readers > 0;
    if (!client.delivered(readers_asked ? after_timeout() : after(kDeliveryWait)) &&
        readers_asked) {
      complain("a command reader did not acknowledge the command(s) within " +
               seconds_text(invocation_.global.timeout) + "; it may not hold them");
      worst = std::max<int>(worst, kExitTimedOut);
    }
    return worst;
  }

  // Which owners did not subscribe, by gateway name and the valves they own.
  std::string unmatched_text(const ValveTable& table, const std::vector<std::uint32_t>& serials,
                             const std::set<std::string>& missing) const {
    std::string text;
    for (const std::uint32_t serial : serials) {
      const auto row = table.row(serial);
      if (!row || !missing.contains(row->participant)) continue;
      text += text.empty() ? "" : ", ";
      text += "gateway " + row->gateway + " (owner of " + codec::format_serial(serial) + ")";
    }
    return text + " did not subscribe to commands within " +
           seconds_text(invocation_.global.timeout) + " on " + domain_text() + "; nothing was sent";
  }

  // Prints the command's statuses up to the first one (or, with --wait, the final one) and
  // returns what they mean as an exit status; `targets` are all the valves the command went to.
  int follow(CommandClient& client, std::uint32_t serial, std::uint32_t id,
             const std::set<std::uint32_t>& targets) {
    const CommandRequest& request = invocation_.command;
    const auto first = client.next_status(id, after_timeout());
    if (!first) {
      complain("no status for command #" + std::to_string(id) + " to " +
               codec::format_serial(serial) + " within " +
               seconds_text(invocation_.global.timeout));
      return kExitTimedOut;
    }
    emit(status_text(*first), status_json(*first));
    if (first->state() == COMMAND_REJECTED) return kExitRejected;
    if (!request.wait) return exit_code_of(first->state());

    const Deadline until = after(request.wait_timeout);
    const bool progress = follows_progress(invocation_, terminal_.out_is_tty);
    std::optional<double> shown_position;
    CommandStatus latest = *first;
    while (latest.state() == COMMAND_ACCEPTED) {
      const auto status =
          client.next_status(id, std::min(until, Deadline(Clock::now() + kProgressPeriod)));
      if (status) {
        latest = *status;
        // The final position goes before the final status, which stays the last line.
        if (latest.state() == COMMAND_COMPLETED && shows_progress(request.command.kind())) {
          if (!progress) show_final_position(serial, targets);
          show_position(serial, shown_position);
        }
        emit(status_text(latest), status_json(latest));
        continue;
      }
      if (terminal_.interrupted) {
        complain("stopped waiting; the valve was not stopped");
        return kExitInterrupted;
      }
      if (Clock::now() >= until) {
        complain("no final status for command #" + std::to_string(id) + " to " +
                 codec::format_serial(serial) + " within " + seconds_text(request.wait_timeout));
        return kExitTimedOut;
      }
      if (progress) show_position(serial, shown_position);
    }
    if (latest.state() == COMMAND_COMPLETED) print_reply(serial, first->stamp_ns());
    return exit_code_of(latest.state());
  }

  static int exit_code_of(CommandState state) {
    switch (state) {
      case COMMAND_ACCEPTED:
      case COMMAND_COMPLETED:
        return kExitOk;
      case COMMAND_REJECTED:
        return kExitRejected;
      case COMMAND_TIMED_OUT:
        return kExitTimedOut;
      case COMMAND_SUPERSEDED:
        return kExitSuperseded;
    }
    return kExitFailure;
  }

  // Follows the targets' positions from now on (once), and waits for `serial`'s.
  void show_final_position(std::uint32_t serial, const std::set<std::uint32_t>& targets) {
    const auto position = dds::topics::telemetry_subject<ValvePosition>();
    if (const auto followed =
            view_->follow({.everything = false, .telemetry = {position}, .serials = targets});
        !followed) {
      complain("cannot read positions: " + followed.error().reason);
      return;
    }
    const auto known = [serial](const ValveTable& table) {
      const auto row = table.row(serial);
      return row && row->position_degrees();
    };
    if (!wait_until(known, after_timeout()) && !terminal_.interrupted) {
      complain("no position from " + codec::format_serial(serial) + " within " +
               seconds_text(invocation_.global.timeout) + " of its completion");
    }
  }

  void show_position(std::uint32_t serial, std::optional<double>& shown) {
    const auto row = view_->snapshot().row(serial);
    const auto position = row ? row->position_degrees() : std::nullopt;
    if (!position || position == shown) return;
    shown = position;
    emit(position_text(serial, *shown), position_json(serial, *shown));
  }

  // A request's answer: the first sample of its kind received after the command was accepted.
  void print_reply(std::uint32_t serial, std::uint64_t accepted_ns) {
    const auto name = awaited_reply(invocation_.command.command);
    if (!name) return;
    const auto fresh = [&](const ValveTable& table) {
      const auto reply = table.reply(serial, *name);
      return reply && reply->received_ns >= accepted_ns;
    };
    if (!wait_until(fresh, after(kReplyGrace))) return;
    const Reply reply = *view_->snapshot().reply(serial, *name);
    emit(reply_text(serial, reply), reply_json(serial, reply));
  }

  Session(const Invocation& invocation, const Terminal& terminal)
      : invocation_(invocation),
        terminal_(terminal),
        run_ends_(invocation.subcommand == Subcommand::kWatch
                      ? Deadline::max()
                      : started_ + lease_for(invocation) - kLeaseBeyondTheRun) {}

  const Invocation& invocation_;
  const Terminal& terminal_;
  const Deadline started_ = Clock::now();
  const Deadline run_ends_;
  std::unique_ptr<dds::Participant> participant_;
  std::unique_ptr<ValveView> view_;  // destroyed before the participant: its readers go first
  dds::TcpRejoin rejoin_;
};

}  // namespace

int run(const Invocation& invocation, const Terminal& terminal) {
  auto session = Session::create(invocation, terminal);
  if (!session) {
    terminal.err << "valvectl: " << session.error().reason << '\n';
    return kExitFailure;
  }
  try {
    return (*session)->run();
  } catch (const JoinFailed&) {
    return kExitFailure;
  }
}

}  // namespace teejet::valvectl
