#include "teejet/gateway/gateway.hpp"

#include <pthread.h>
#include <spdlog/spdlog.h>

#include "teejet/gateway/bus_rate.hpp"
#include "teejet/layout/layout_file.hpp"

namespace teejet::gateway {
namespace {

using namespace std::chrono_literals;

// Malformed frames are reported at most this often: a babbling node must not flood the log.
constexpr Duration kDecodeReportPeriod = 10s;
// Longest wait of either thread: the bridge has a deadline at least once a second anyway.
constexpr Duration kLongestWait = 1s;
// At shutdown, how long the last command statuses may take to be acknowledged by every reader
// before the writer goes: long enough for a loaded machine, short enough for a service stop.
constexpr Duration kLastStatusesWait = 500ms;
// Frames taken off the bus per wake-up at most; the deadlines are looked at between batches.
constexpr std::size_t kReceiveBatch = 64;
// Batches taken without waiting before a deadline is kept: a backlog of 8 x 64 frames is longer
// than a 32-valve bus's burst of replies.
constexpr int kBatchesBeforeDeadlines = 8;

// A layout written into the configuration stays the person's: the gateway never rewrites it.
class LayoutInConfiguration final : public layout::LayoutStore {
 public:
  Status save(const layout::Layout&) override {
    return Error{ErrorCode::kUnavailable,
                 "this gateway's layout is in its configuration (layout:), which it never "
                 "rewrites; give the layout a file of its own (layout_file:) to change it over "
                 "DDS (docs/layout.md)"};
  }
};

}  // namespace

Gateway::Gateway(GatewayConfig config, BusBackend backend, std::shared_ptr<const Clock> clock)
    : config_(std::move(config)), backend_(std::move(backend)), clock_(std::move(clock)) {
  config_.bridge.can_interface = config_.can;
}

Gateway::~Gateway() { stop(); }

Status Gateway::start() {
  if (!backend_.bus) return Error{ErrorCode::kInvalidValue, "the gateway has no bus"};
  const auto fail = [this](Error error) -> Status {
    stop();
    return error;
  };
  if (backend_.simulator) {
    if (auto started = backend_.simulator->start(); !started) return fail(started.error());
  }
  if (auto opened = backend_.bus->open(); !opened) return fail(opened.error());

  // Two signals for a dead commander: its writer's liveliness (2 s lease) and its
  // participant's lease. Fast DDS 2.9 misses the first once another command writer is alive
  // (docs/gateway.md), so the second backs it up.
  lost_commanders_ = std::make_shared<dds::LostCommanders>();
  auto participant = dds::Participant::create(
      {.domain = config_.domain,
       .profile_file = config_.profile_file,
       .name = config_.bridge.gateway_name,
       .role = dds::kGatewayRole,
       .on_participant_dropped = [lost = lost_commanders_](const std::string& prefix) {
         lost->report(prefix);
       }});
  if (!participant) return fail(participant.error());
  participant_ = std::move(*participant);
  auto watchdog = dds::EventWatchdog::create(
      *participant_,
      {.stalled_after = dds_stalled_after_, .on_stalled = [this](Duration silent_for) {
         spdlog::critical("{}", dds::EventWatchdog::describe(silent_for));
         if (on_dds_stalled_) on_dds_stalled_(silent_for);
       }});
  if (watchdog) {
    watchdog_ = std::move(*watchdog);
  } else {
    spdlog::warn("{}", watchdog.error().reason);
  }
  std::set<std::string> locations;
  for (const auto& place : config_.bridge.layout.locations()) locations.insert(place.name);
  auto publisher =
      dds::GatewayPublisher::create(*participant_, config_.bridge.gateway_name, locations);
  if (!publisher) return fail(publisher.error());
  publisher_ = std::move(*publisher);
  if (config_.record_frames) {
    auto frames = dds::FramePublisher::create(*participant_, config_.bridge.gateway_name,
                                              config_.bridge.can_interface);
    if (!frames) return fail(frames.error());
    frames_ = std::move(*frames);
    // Wrapped before the bridge and the threads see the bus, so that every frame they send or
    // take goes through the observer; what arrived since open() is waiting inside and is seen
    // when taken.
    auto observed = std::make_unique<can::ObservedBus>(std::move(backend_.bus), *frames_, clock_);
    observed_bus_ = observed.get();
    backend_.bus = std::move(observed);
  }
  if (!config_.layout_file.empty()) {
    if (const auto removed = layout::remove_unfinished_saves(config_.layout_file); removed > 0) {
      spdlog::warn(
          "removed {} unfinished save(s) of {} left by a power cut or a kill; the file "
          "itself is whole",
          removed, config_.layout_file);
    }
    layout_store_ = std::make_unique<layout::LayoutFileStore>(config_.layout_file);
  } else if (config_.layout_in_config) {
    layout_store_ = std::make_unique<LayoutInConfiguration>();
  }
  {
    std::lock_guard lock(valves_mutex_);
    valves_stopped_ = false;
    bridge_ = std::make_unique<bridge::Bridge>(config_.bridge, *backend_.bus, *publisher_, clock_,
                                               publisher_->other_gateways(), layout_store_.get());
  }
  auto commands = dds::CommandSubscription::create(*participant_, lost_commanders_,
                                                   publisher_->answers_layout_changes());
  if (!commands) return fail(commands.error());
  commands_ = std::move(*commands);

  next_decode_report_ = clock_->steady();
  reader_ = std::jthread([this](std::stop_token stop) { read_bus(stop); });
  commander_ = std::jthread([this](std::stop_token stop) { take_commands(stop); });
  // Named for top -H, perf and the benchmarks' per-thread CPU figures (15 characters at most).
  pthread_setname_np(reader_.native_handle(), "tj-bus-reader");
  pthread_setname_np(commander_.native_handle(), "tj-commands");
  spdlog::info("gateway '{}' on {} in DDS domain {}{}; {}", config_.bridge.gateway_name,
               config_.can, config_.domain, frames_ ? ", every frame on teejet/can/frame" : "",
               participant_->setup());
  return {};
}

void Gateway::stop() {
  // Commands first: once the reader is gone, nothing can start a valve after the Stops below.
  if (commander_.joinable()) {
    commander_.request_stop();
    commands_->wake();
    commander_.join();
  }
  commands_.reset();
  if (bridge_ && config_.stop_valves_on_exit) {
    spdlog::info("stopped {} valve(s) on exit", stop_valves());
  }
  if (reader_.joinable()) {
    reader_.request_stop();
    backend_.bus->close();  // wakes the reader out of receive()
    reader_.join();
  }
  // A commander must not be left waiting: what is still followed (a move of a valve left
  // running, a request awaiting its reply) ends now, and its status reaches the readers.
  if (bridge_) {
    if (const auto ended = bridge_->end_all_commands(); ended > 0) {
      spdlog::info("{} command(s) still running ended TIMED_OUT on exit", ended);
    }
    if (publisher_ && !publisher_->wait_for_statuses(kLastStatusesWait)) {
      spdlog::warn(
          "not every reader acknowledged the last command statuses within {} ms",
          std::chrono::duration_cast<std::chrono::milliseconds>(kLastStatusesWait).count());
    }
  }
  // The publishers' writers go with the participant; the bridge writes through them, and the
  // bus through frames_ (nothing sends or takes frames any more). The peers' reader goes first:
  // the publisher deletes it through the participant.
  if (publisher_) publisher_->stop_hearing_peers();
  // Watched to the end: a participant that cannot be deleted is a stall too.
  if (watchdog_) watchdog_->outlive_participant();
  participant_.reset();
  watchdog_.reset();
  {
    std::lock_guard lock(valves_mutex_);
    bridge_.reset();
  }
  publisher_.reset();
  // The bus goes back to its unobserved self before its observer goes: a later start() finds
  // the bus as it was made.
  if (observed_bus_) {
    backend_.bus = observed_bus_->release();
    observed_bus_ = nullptr;
  }
  frames_.reset();
  if (backend_.bus) backend_.bus->close();
  if (backend_.simulator) backend_.simulator->stop();
}

void Gateway::on_dds_stalled(std::function<void(Duration)> handler, Duration stalled_after) {
  on_dds_stalled_ = std::move(handler);
  dds_stalled_after_ = stalled_after;
}

std::size_t Gateway::stop_valves() {
  std::lock_guard lock(valves_mutex_);
  if (valves_stopped_ || !bridge_ || !config_.stop_valves_on_exit) return 0;
  valves_stopped_ = true;
  return bridge_->stop_all();
}

Duration Gateway::until(SteadyTime deadline) const {
  return std::clamp(deadline - clock_->steady(), Duration{0}, kLongestWait);
}

// Frames are taken in bursts: one wake-up and one look at the deadlines per burst. On a busy
// bus (at least receive_coalesce_above frames a second, frames closer together than the
// coalescing window) the reader lets the next burst gather for the window instead of waking for
// every frame: at a full 500 kbit/s bus a wake-up costs this 2-vCPU machine more than decoding
// and publishing the frame it brings. Below that rate no frame waits.
void Gateway::read_bus(std::stop_token stop) {
  std::vector<can::TimedFrame> frames;
  frames.reserve(kReceiveBatch);
  const Duration window = config_.receive_coalesce;
  BusRate rate(config_.receive_coalesce_above, clock_->steady());
  bool busy = false;
  SteadyTime last_batch{};
  while (!stop.stop_requested()) {
    Duration left = until(bridge_->next_deadline());
    if (left <= Duration{0}) {
      // What the bus holds first (a few batches at most): on a starved machine the I'm Here
      // that keeps a valve online may be waiting in the socket when its deadline passes.
      for (int batch = 0; batch < kBatchesBeforeDeadlines; ++batch) {
        frames.clear();
        if (backend_.bus->receive_batch(frames, kReceiveBatch, std::chrono::milliseconds(0)) == 0) {
          break;
        }
        rate.count(frames.size(), clock_->steady());
        bridge_->on_frames(frames);
      }
      bridge_->tick();
      log_changes();  // at least once a second, never per frame
      continue;
    }
    if (busy) {
      std::this_thread::sleep_for(std::min(window, left));
      left = until(bridge_->next_deadline());
    }
    frames.clear();
    // After a coalescing wait, take what gathered without blocking: nothing means quiet again.
    const auto wait =
        busy ? std::chrono::milliseconds(0) : std::chrono::ceil<std::chrono::milliseconds>(left);
    const std::size_t taken = backend_.bus->receive_batch(frames, kReceiveBatch, wait);
    if (taken == 0) {
      busy = false;
      continue;
    }
    // Busy while each window brings frames or they come closer together than the window. A
    // full batch means more are waiting: take them at once.
    const SteadyTime now = clock_->steady();
    rate.count(taken, now);
    busy = window > Duration{0} && rate.busy() && taken < kReceiveBatch &&
           (busy || now - last_batch < window);
    last_batch = now;
    bridge_->on_frames(frames);
  }
}

// Commands arrive here, on the gateway's own thread; the same thread keeps any deadline a
// command sets, however soon, since the reader may be waiting for one further away.
void Gateway::take_commands(std::stop_token stop) {
  while (!stop.stop_requested()) {
    const auto events = commands_->wait(until(bridge_->next_command_deadline()));
    for (const auto& received : events.commands) {
      bridge_->on_command(received.command, received.writer);
    }
    for (const auto& change : events.layout_changes) bridge_->on_layout_change(change);
    for (const auto& commander : events.lost_commanders) commander_lost(commander);
    // Valves going quiet are the bus reader's to judge (Bridge::tick).
    if (until(bridge_->next_command_deadline()) <= Duration{0}) bridge_->tick_commands();
  }
}

void Gateway::commander_lost(const std::string& commander) {
  // A writer id is "prefix|entity"; a participant is its GUID prefix alone.
  const std::string what = commander.find('|') == std::string::npos
                               ? "participant " + commander + " dropped"
                               : "command writer " + commander + " lost liveliness";
  if (config_.on_commander_lost != OnCommanderLost::kStopItsValves) {
    spdlog::info("{} (fail-safe off)", what);
    return;
  }
  const auto stopped = bridge_->stop_commanded_by(commander);
  if (stopped > 0) spdlog::warn("{}: fail-safe stopped {} valve(s)", what, stopped);
}

// Logs only what changed: a quiet bus makes no log lines.
void Gateway::log_changes() {
  const auto state = backend_.bus->statistics().state;
  if (state != logged_state_) {
    spdlog::warn("CAN bus {} is {}", config_.can, can::to_string(state));
    logged_state_ = state;
  }
  const SteadyTime now = clock_->steady();
  if (now < next_decode_report_) return;
  const auto counters = bridge_->counters();
  if (counters.decode_errors != logged_decode_errors_) {
    spdlog::warn("{} malformed frame(s) so far; last: {}", counters.decode_errors,
                 counters.last_decode_error);
    logged_decode_errors_ = counters.decode_errors;
  }
  next_decode_report_ = now + kDecodeReportPeriod;
}

}  // namespace teejet::gateway
