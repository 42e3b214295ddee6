#pragma once

// A client's window on the domain: subscribes to presence, places and gateway status, and to every
// telemetry topic and errors or only the telemetry it names (durable topics, so a fresh client
// sees everything at once), and keeps the latest per valve in a ValveTable. Listeners only take
// samples into the table; callers wait on conditions over it.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <shared_mutex>
#include <string>
#include <thread>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include "teejet/client/valve_table.hpp"
#include "teejet/dds/participant.hpp"
#include "teejet/dds/topics.hpp"

namespace teejet::client {

using Deadline = std::chrono::steady_clock::time_point;

// The telemetry a view follows besides presence, places and gateway status (always followed).
// Every gateway sends a joining reader the last sample of each of its instances: a client that
// needs only the directory (a command, a layout change) costs each gateway 32 samples a topic
// for 32 valves, where following everything costs about twelve topics' worth.
struct ViewTopics {
  bool everything = true;           // every telemetry topic and the errors
  std::set<std::string> telemetry;  // otherwise only these subjects ("position")
  bool errors = false;              // with `telemetry`: the errors too
  // With `telemetry`: only these valves' samples of it (empty: every valve's); the others are
  // dropped as they arrive (dds/serial_filter.hpp). Presence stays whole.
  std::set<std::uint32_t> serials;
  // Of the telemetry followed, the subjects taken best effort ("position"): those the gateways
  // resend on their own every poll, where a lost sample is replaced by the next one and
  // acknowledging each costs more than it is worth. Each gateway's last sample of them still
  // arrives as it appears: a reliable reader of the subject follows it until no writer has
  // matched for kCatchUpQuiet, and fills only what the stream has not given anything newer for.
  std::set<std::string> best_effort;
};

class ValveView final : public eprosima::fastdds::dds::DataReaderListener {
 public:
  // Subscribes to the durable topics `topics` names; an Error names what DDS refused.
  static Result<std::unique_ptr<ValveView>> create(dds::Participant& participant,
                                                   const ViewTopics& topics = {});
  ~ValveView() override;
  // How long a best-effort subject's reliable reader stays after its last writer matched.
  static constexpr std::chrono::seconds kCatchUpQuiet{3};
  ValveView(const ValveView&) = delete;
  ValveView& operator=(const ValveView&) = delete;

  // Follows the telemetry subjects of `more` too (its `everything` and errors aside), of its
  // serials only when it names them, from now on: each gateway sends the new readers the last
  // sample of every valve, then every new one. A subject already followed stays as it is.
  // A client that needs a topic only at the end (a command's final position) saves the
  // gateways sending it every sample while it waits. An Error names what DDS refused.
  Status follow(const ViewTopics& more);
  // Stops following valve presence; the rows stay as they last were. Every gateway sends a
  // follower each of its valves' I'm Here, once a second: a client that has found the valves it
  // commands and waits for their statuses saves them that (and itself the wake-ups).
  void stop_following_presence();

  ValveTable snapshot() const;
  // The gateways alone (ValveTable::gateways), without copying every valve's row.
  std::vector<GatewaySummary> gateways() const;

  // What a dashboard's tick sends on, without copying the table: the rows changed after
  // `revision` (ValveTable::rows_changed_since) and those of `also` whatever their revision,
  // every gateway and place, and the revision all this is as of.
  struct Changes {
    std::vector<ValveRow> rows;
    std::vector<GatewaySummary> gateways;
    std::vector<LocationRow> places;
    std::uint64_t revision = 0;
  };
  Changes changes_since(std::uint64_t revision, const std::set<std::uint32_t>& also = {}) const;

  // Waits until `condition` holds (true), or `until` passes or `interrupted` is set (false).
  // The condition runs with the table locked and must not call the view.
  using Condition = std::function<bool(const ValveTable&)>;
  bool wait_until(const Condition& condition, Deadline until,
                  const std::atomic<bool>& interrupted) const;

  void on_data_available(eprosima::fastdds::dds::DataReader* reader) override;
  // Gateway status only: a gateway whose writers lost their liveliness (it died without a word)
  // or left is marked lost in the table.
  void on_liveliness_changed(
      eprosima::fastdds::dds::DataReader* reader,
      const eprosima::fastdds::dds::LivelinessChangedStatus& status) override;
  // Gateway status: a writer that goes before its first liveliness assertion reached this
  // reader changes no liveliness (Fast DDS never counted it alive); its unmatch, when its
  // participant's lease ends, marks it lost instead, and a match marks it back. A best-effort
  // subject's readers: a new writer wants its last samples caught up.
  void on_subscription_matched(
      eprosima::fastdds::dds::DataReader* reader,
      const eprosima::fastdds::dds::SubscriptionMatchedStatus& status) override;

 private:
  using Reader = eprosima::fastdds::dds::DataReader*;
  using Handler = std::function<void(Reader)>;
  ValveView(dds::Participant& participant, const ViewTopics& topics);
  template <class Sample>
  using OnSample = std::function<void(const Sample&, const eprosima::fastdds::dds::SampleInfo&)>;
  // Registers a reader of Sample's topic; nullptr (and failure_ set) when DDS refuses.
  template <class Sample>
  Reader subscribe(
      OnSample<Sample> on_sample, const std::set<std::uint32_t>& serials = {},
      const eprosima::fastdds::dds::DataReaderQos& qos = dds::topics::state_reader_qos());
  // Takes what `from` holds and hands it to `on_sample` with mutex_ held.
  template <class Sample>
  Handler taking(OnSample<Sample> on_sample);
  Reader reader_of(const std::string& topic_name, Result<eprosima::fastdds::dds::Topic*> topic,
                   const std::set<std::uint32_t>& serials,
                   const eprosima::fastdds::dds::DataReaderQos& qos);
  // The readers it made (those DDS refused set failure_).
  template <class... Samples>
  std::vector<Reader> subscribe_telemetry(std::type_identity<std::variant<Samples...>>,
                                          const ViewTopics& topics);
  // Gives `readers` this view as their listener and takes what arrived before it.
  void listen_to(const std::vector<Reader>& readers);
  void take_errors(Reader reader);
  // The catch-up thread: makes a reliable reader of each best-effort subject a new writer
  // matched, and deletes it once no writer has matched for kCatchUpQuiet.
  void catch_up();
  // Fast DDS calls listeners with its reader's lock held and takes that lock to report the
  // matched count: asking it with mutex_ held would invert the lock order, so this runs first
  // and stores the count in the table.
  void update_gateways_matched() const;

  dds::Participant& participant_;
  std::optional<Error> failure_;  // the first thing DDS refused while subscribing
  // Grows in the constructor and follow(); listener threads look their reader up in it.
  mutable std::shared_mutex handlers_mutex_;
  std::map<Reader, Handler> handlers_;
  std::set<std::string> telemetry_followed_;
  Reader gateway_status_reader_ = nullptr;
  Reader presence_reader_ = nullptr;  // guarded by handlers_mutex_ after the constructor

  mutable std::mutex mutex_;
  mutable std::condition_variable changed_;
  mutable ValveTable table_;  // mutable: update_gateways_matched() refreshes a count in it
  // Disposed samples carry no data: the instance handle says which error was cleared.
  std::map<eprosima::fastrtps::rtps::InstanceHandle_t, std::pair<std::uint32_t, ErrorKind>>
      error_instances_;

  struct Stream {
    std::function<Reader()> make_catch_up;  // nullptr when DDS refused
    Reader catch_up = nullptr;
    bool wanted = false;  // a writer matched the stream while it had no catch-up reader
    std::chrono::steady_clock::time_point last_match;
  };
  std::mutex streams_mutex_;
  std::condition_variable streams_changed_;
  std::map<Reader, Stream> streams_;  // by their best-effort reader
  bool stopping_ = false;
  std::thread catch_up_thread_;  // started with the first best-effort subject
};

}  // namespace teejet::client
