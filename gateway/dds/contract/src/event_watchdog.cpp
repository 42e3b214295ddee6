#include "teejet/dds/event_watchdog.hpp"

#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/DataWriterListener.hpp>

#include "teejet/dds/topics.hpp"

namespace teejet::dds {

using namespace eprosima::fastdds::dds;

class EventWatchdog::Listener final : public DataWriterListener {
 public:
  explicit Listener(EventWatchdog& watchdog) : watchdog_(watchdog) {}
  void on_offered_deadline_missed(DataWriter*, const OfferedDeadlineMissedStatus&) override {
    watchdog_.beat();
  }

 private:
  EventWatchdog& watchdog_;
};

EventWatchdog::EventWatchdog(Participant& participant, EventWatchdogOptions options)
    : participant_(participant),
      options_(std::move(options)),
      listener_(std::make_unique<Listener>(*this)),
      last_beat_(std::chrono::steady_clock::now().time_since_epoch().count()) {}

Result<std::unique_ptr<EventWatchdog>> EventWatchdog::create(Participant& participant,
                                                             EventWatchdogOptions options) {
  std::unique_ptr<EventWatchdog> made(new EventWatchdog(participant, std::move(options)));
  const auto refused = [](const Error& error) {
    return Error{error.code, "no watch on Fast DDS's event thread: " + error.reason +
                                 " (under DDS-Security, the role needs publish permission for " +
                                 topics::kEventWatchdog + ")"};
  };
  auto topic = participant.topic<ValvePositionPubSubType>(topics::kEventWatchdog);
  if (!topic) return refused(topic.error());
  DataWriterQos qos = DATAWRITER_QOS_DEFAULT;
  qos.reliability().kind = BEST_EFFORT_RELIABILITY_QOS;
  qos.durability().kind = VOLATILE_DURABILITY_QOS;
  qos.history().kind = KEEP_LAST_HISTORY_QOS;
  qos.history().depth = 1;
  qos.deadline().period = to_dds_duration(made->options_.period);
  auto writer = participant.writer(*topic, qos, made->listener_.get());
  if (!writer) return refused(writer.error());
  made->writer_ = *writer;
  // The deadline runs from the first write; nothing is written after it.
  ValvePosition sample;
  if (!made->writer_->write(&sample)) {
    return refused(Error{ErrorCode::kUnavailable, "cannot write the event watchdog's sample"});
  }
  made->watcher_ =
      std::jthread([watchdog = made.get()](std::stop_token stop) { watchdog->watch(stop); });
  return made;
}

EventWatchdog::~EventWatchdog() {
  if (watcher_.joinable()) {
    watcher_.request_stop();  // wakes the wait on wake_
    watcher_.join();
  }
  if (writer_ != nullptr) participant_.delete_writer(writer_);
}

void EventWatchdog::outlive_participant() { writer_ = nullptr; }

std::string EventWatchdog::describe(Duration silent_for) {
  return "Fast DDS's event thread has run no timer for " +
         std::to_string(std::chrono::duration_cast<std::chrono::seconds>(silent_for).count()) +
         " s: the participant hears, announces and acknowledges nothing any more (a deadlock "
         "inside Fast DDS, docs/topics.md, \"A participant that stops\")";
}

void EventWatchdog::beat() {
  last_beat_.store(std::chrono::steady_clock::now().time_since_epoch().count());
  beats_.fetch_add(1);
}

void EventWatchdog::watch(std::stop_token stop) {
  std::unique_lock lock(mutex_);
  while (!stop.stop_requested()) {
    wake_.wait_for(lock, stop, options_.period, [] { return false; });
    const auto last = std::chrono::steady_clock::time_point(
        std::chrono::steady_clock::duration(last_beat_.load()));
    const Duration silent_for = std::chrono::steady_clock::now() - last;
    if (silent_for >= options_.stalled_after) {
      stalled_.store(true);
      if (options_.on_stalled) options_.on_stalled(silent_for);
      return;
    }
  }
}

}  // namespace teejet::dds
