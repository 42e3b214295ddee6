#include "teejet/client/valve_view.hpp"

#include <algorithm>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <utility>
#include <vector>

#include "teejet/dds/conversions.hpp"
#include "teejet/dds/topics.hpp"
#include "teejet/valvePubSubTypes.h"

namespace teejet::client {

using eprosima::fastdds::dds::DataReader;
using eprosima::fastdds::dds::SampleInfo;
using ReturnCode = eprosima::fastrtps::types::ReturnCode_t;

ValveView::Reader ValveView::reader_of(const std::string& topic_name,
                                       Result<eprosima::fastdds::dds::Topic*> topic,
                                       const std::set<std::uint32_t>& serials,
                                       const eprosima::fastdds::dds::DataReaderQos& qos) {
  if (failure_) return nullptr;
  if (!topic) {
    failure_ = topic.error();
    return nullptr;
  }
  // No listener yet: create() attaches them once handlers_ is complete.
  auto reader = !serials.empty() ? participant_.reader_of_serials(*topic, serials, qos)
                                 : participant_.reader(*topic, qos);
  if (!reader) {
    failure_ = Error{reader.error().code, reader.error().reason + " (" + topic_name + ")"};
    return nullptr;
  }
  return *reader;
}

template <class Sample>
ValveView::Handler ValveView::taking(OnSample<Sample> on_sample) {
  return [this, on_sample = std::move(on_sample)](Reader from) {
    // Take first, then lock: Fast DDS holds the reader's lock while it calls the listener, so
    // taking with mutex_ held would invert the lock order against a listener thread.
    std::vector<std::pair<Sample, SampleInfo>> samples;
    Sample sample;
    SampleInfo info;
    while (from->take_next_sample(&sample, &info) == ReturnCode::RETCODE_OK) {
      if (info.valid_data) samples.emplace_back(sample, info);
    }
    if (samples.empty()) return;
    std::lock_guard lock(mutex_);
    for (const auto& [taken, taken_info] : samples) on_sample(taken, taken_info);
    changed_.notify_all();
  };
}

template <class Sample>
ValveView::Reader ValveView::subscribe(OnSample<Sample> on_sample,
                                       const std::set<std::uint32_t>& serials,
                                       const eprosima::fastdds::dds::DataReaderQos& qos) {
  Reader reader = reader_of(dds::topics::topic_name<Sample>(),
                            dds::topics::topic_of<Sample>(participant_), serials, qos);
  if (reader == nullptr) return nullptr;
  std::unique_lock handlers_lock(handlers_mutex_);
  handlers_.emplace(reader, taking<Sample>(std::move(on_sample)));
  return reader;
}

Result<std::unique_ptr<ValveView>> ValveView::create(dds::Participant& participant,
                                                     const ViewTopics& topics) {
  std::unique_ptr<ValveView> view(new ValveView(participant, topics));
  if (view->failure_) return *view->failure_;
  std::vector<Reader> readers;
  for (const auto& [reader, handler] : view->handlers_) readers.push_back(reader);
  view->listen_to(readers);
  return view;
}

void ValveView::listen_to(const std::vector<Reader>& readers) {
  // Samples that arrived before a reader had its listener are taken right after. Gateway
  // status also tells when a gateway's writers lost their liveliness or left.
  for (const Reader reader : readers) {
    using eprosima::fastdds::dds::StatusMask;
    const auto mask = reader == gateway_status_reader_
                          ? StatusMask::data_available() << StatusMask::liveliness_changed()
                                                         << StatusMask::subscription_matched()
                          : StatusMask::data_available() << StatusMask::subscription_matched();
    reader->set_listener(this, mask);
  }
  // Without handlers_mutex_ held: taking locks the reader, and a listener thread holding that
  // lock takes handlers_mutex_.
  std::vector<std::pair<Reader, Handler>> taking;
  {
    std::shared_lock lock(handlers_mutex_);
    for (const Reader reader : readers) taking.emplace_back(reader, handlers_.at(reader));
  }
  for (const auto& [reader, handler] : taking) handler(reader);
}

Status ValveView::follow(const ViewTopics& more) {
  ViewTopics fresh{.everything = false, .serials = more.serials, .best_effort = more.best_effort};
  for (const auto& subject : more.telemetry) {
    if (!telemetry_followed_.contains(subject)) fresh.telemetry.insert(subject);
  }
  if (fresh.telemetry.empty()) return {};
  listen_to(subscribe_telemetry(std::type_identity<dds::TelemetrySample>{}, fresh));
  if (failure_) return *failure_;
  return {};
}

void ValveView::stop_following_presence() {
  Reader reader = nullptr;
  {
    std::unique_lock lock(handlers_mutex_);
    reader = std::exchange(presence_reader_, nullptr);
    if (reader == nullptr) return;
    handlers_.erase(reader);
  }
  // Deleted without handlers_mutex_ held: a listener thread may hold the reader's lock while
  // it waits for that mutex, and finds no handler once it has it.
  participant_.delete_reader(reader);
}

ValveView::ValveView(dds::Participant& participant, const ViewTopics& topics)
    : participant_(participant) {
  presence_reader_ =
      subscribe<ValvePresence>([this](const ValvePresence& sample, const SampleInfo& info) {
        table_.on_presence(sample, dds::participant_of(info.publication_handle));
      });
  // Gateway status follows its writers' liveliness: a gateway that dies without a word is
  // shown lost.
  gateway_status_reader_ = subscribe<GatewayStatus>(
      [this](const GatewayStatus& sample, const SampleInfo& info) {
        table_.on_gateway_status(sample, dds::participant_of(info.publication_handle));
      },
      {}, dds::topics::liveliness_reader_qos());
  subscribe<ValveLocation>([this](const ValveLocation& sample, const SampleInfo& info) {
    table_.on_location(sample, dds::participant_of(info.publication_handle));
  });
  subscribe_telemetry(std::type_identity<dds::TelemetrySample>{}, topics);
  if (!topics.everything && !topics.errors) return;

  // Errors are keyed by (serial, kind) and disposed on Clear Errors: they need the instance.
  if (Reader errors = reader_of(dds::topics::kError,
                                participant_.topic<ValveErrorPubSubType>(dds::topics::kError), {},
                                dds::topics::state_reader_qos())) {
    std::unique_lock handlers_lock(handlers_mutex_);
    handlers_.emplace(errors, [this](Reader from) { take_errors(from); });
  }
}

template <class... Samples>
std::vector<ValveView::Reader> ValveView::subscribe_telemetry(
    std::type_identity<std::variant<Samples...>>, const ViewTopics& topics) {
  // Every telemetry topic alike, as the codec's messages; errors are instances of their own.
  std::vector<Reader> made;
  const auto one = [this, &topics, &made](auto identity) {
    using Sample = typename decltype(identity)::type;
    if constexpr (!std::is_same_v<Sample, ValveError>) {
      const std::string subject = dds::topics::telemetry_subject<Sample>();
      if (!topics.everything && !topics.telemetry.contains(subject)) return;
      telemetry_followed_.insert(subject);
      const auto serials = topics.everything ? std::set<std::uint32_t>{} : topics.serials;
      const bool stream = topics.best_effort.contains(subject);
      Reader reader = subscribe<Sample>(
          [this](const Sample& sample, const SampleInfo&) {
            table_.on_telemetry(sample.serial(), dds::from_sample(sample), sample.received_ns());
          },
          serials, stream ? dds::topics::stream_reader_qos() : dds::topics::state_reader_qos());
      if (reader == nullptr) return;
      made.push_back(reader);
      if (!stream) return;
      // Made on the catch-up thread, through the stream's own topic (filtered or not): the
      // participant's maps of topics are this thread's.
      auto make_catch_up = [this, topic = const_cast<eprosima::fastdds::dds::TopicDescription*>(
                                      reader->get_topicdescription())]() -> Reader {
        auto catch_up = participant_.reader(topic, dds::topics::state_reader_qos());
        if (!catch_up) return nullptr;
        std::unique_lock handlers_lock(handlers_mutex_);
        handlers_.emplace(*catch_up,
                          taking<Sample>([this](const Sample& sample, const SampleInfo&) {
                            table_.on_telemetry_history(sample.serial(), dds::from_sample(sample),
                                                        sample.received_ns());
                          }));
        return *catch_up;
      };
      // Wanted at once: writers may match the stream before it has its listener.
      std::lock_guard lock(streams_mutex_);
      streams_[reader] = {.make_catch_up = std::move(make_catch_up), .wanted = true};
      streams_changed_.notify_all();
      if (!catch_up_thread_.joinable()) catch_up_thread_ = std::thread([this] { catch_up(); });
    }
  };
  (one(std::type_identity<Samples>{}), ...);
  return made;
}

ValveView::~ValveView() {
  {
    std::lock_guard lock(streams_mutex_);
    stopping_ = true;
  }
  streams_changed_.notify_all();
  if (catch_up_thread_.joinable()) catch_up_thread_.join();
  // Delete the readers while this listener still exists: the participant outlives the view.
  for (const auto& [reader, handler] : handlers_) participant_.delete_reader(reader);
}

void ValveView::take_errors(Reader reader) {
  std::vector<std::pair<ValveError, SampleInfo>> taken;  // taken before locking, as above
  ValveError sample;
  SampleInfo info;
  while (reader->take_next_sample(&sample, &info) == ReturnCode::RETCODE_OK) {
    taken.emplace_back(sample, info);
  }
  if (taken.empty()) return;
  std::lock_guard lock(mutex_);
  for (const auto& [error, error_info] : taken) {
    if (error_info.valid_data) {
      error_instances_[error_info.instance_handle] = {error.serial(), error.kind()};
      table_.on_error(error.serial(), error.kind());
    } else if (error_info.instance_state ==
               eprosima::fastdds::dds::NOT_ALIVE_DISPOSED_INSTANCE_STATE) {
      if (const auto it = error_instances_.find(error_info.instance_handle);
          it != error_instances_.end()) {
        table_.on_error_cleared(it->second.first, it->second.second);
      }
    }
  }
  changed_.notify_all();
}

void ValveView::catch_up() {
  std::unique_lock lock(streams_mutex_);
  while (!stopping_) {
    const auto now = std::chrono::steady_clock::now();
    auto next = now + std::chrono::hours(1);
    std::vector<Stream*> to_make;
    std::vector<Reader> to_delete;
    for (auto& [stream_reader, stream] : streams_) {
      if (stream.catch_up == nullptr) {
        if (stream.wanted && stream.make_catch_up) to_make.push_back(&stream);
      } else if (now >= stream.last_match + kCatchUpQuiet) {
        to_delete.push_back(std::exchange(stream.catch_up, nullptr));
      } else {
        next = std::min(next, stream.last_match + kCatchUpQuiet);
      }
    }
    if (to_make.empty() && to_delete.empty()) {
      streams_changed_.wait_until(lock, next);
      continue;
    }
    // Without streams_mutex_: a listener thread holds its reader's lock while it takes it.
    lock.unlock();
    std::vector<std::pair<Stream*, Reader>> made;
    for (Stream* stream : to_make) made.emplace_back(stream, stream->make_catch_up());
    for (const Reader reader : to_delete) {
      {
        std::unique_lock handlers_lock(handlers_mutex_);
        handlers_.erase(reader);
      }
      participant_.delete_reader(reader);
    }
    std::vector<Reader> listening;
    lock.lock();
    // Every writer that had matched the stream is there to match its catch-up reader too.
    for (auto [stream, reader] : made) {
      stream->wanted = false;
      stream->catch_up = reader;
      stream->last_match = std::chrono::steady_clock::now();
      if (reader != nullptr) listening.push_back(reader);
    }
    if (listening.empty()) continue;
    lock.unlock();
    listen_to(listening);
    lock.lock();
  }
}

void ValveView::on_data_available(DataReader* reader) {
  // Held while the handler runs: follow() adds to the map, never while holding mutex_.
  std::shared_lock lock(handlers_mutex_);
  if (const auto it = handlers_.find(reader); it != handlers_.end()) it->second(reader);
}

void ValveView::on_liveliness_changed(
    DataReader* /*reader*/, const eprosima::fastdds::dds::LivelinessChangedStatus& status) {
  // One writer per gateway on this topic: its participant is the gateway's.
  const bool back = status.alive_count_change > 0;
  const bool gone = status.not_alive_count_change > 0 ||
                    (status.alive_count_change < 0 && status.not_alive_count_change == 0);
  if (!back && !gone) return;
  std::lock_guard lock(mutex_);
  table_.on_participant_liveliness(dds::participant_of(status.last_publication_handle), back);
  changed_.notify_all();
}

void ValveView::on_subscription_matched(
    DataReader* reader, const eprosima::fastdds::dds::SubscriptionMatchedStatus& status) {
  if (status.current_count_change == 0) return;
  if (reader != gateway_status_reader_) {
    if (status.current_count_change < 0) return;
    std::lock_guard lock(streams_mutex_);
    for (auto& [stream_reader, stream] : streams_) {
      if (reader != stream_reader && reader != stream.catch_up) continue;
      stream.last_match = std::chrono::steady_clock::now();
      if (stream.catch_up == nullptr) {
        stream.wanted = true;
        streams_changed_.notify_all();
      }
    }
    return;
  }
  // A status writer that matches again belongs to a participant discovery found again: alive,
  // whatever its liveliness said before (Fast DDS may report none on a rematch).
  std::lock_guard lock(mutex_);
  table_.on_participant_liveliness(dds::participant_of(status.last_publication_handle),
                                   status.current_count_change > 0);
  changed_.notify_all();
}

ValveTable ValveView::snapshot() const {
  update_gateways_matched();
  std::lock_guard lock(mutex_);
  return table_;
}

std::vector<GatewaySummary> ValveView::gateways() const {
  std::lock_guard lock(mutex_);
  return table_.gateways();
}

ValveView::Changes ValveView::changes_since(std::uint64_t revision,
                                            const std::set<std::uint32_t>& also) const {
  std::lock_guard lock(mutex_);
  return {table_.rows_changed_since(revision, also), table_.gateways(), table_.locations(),
          table_.revision()};
}

void ValveView::update_gateways_matched() const {
  eprosima::fastdds::dds::SubscriptionMatchedStatus matched;
  if (gateway_status_reader_->get_subscription_matched_status(matched) != ReturnCode::RETCODE_OK) {
    return;
  }
  const std::size_t announced = participant_.participants_with_role(dds::kGatewayRole).size();
  const bool settled = participant_.discovery_settled();
  const std::size_t met = participant_.participants_met();
  std::lock_guard lock(mutex_);
  table_.set_participants_met(met);
  table_.set_gateways_matched(static_cast<std::size_t>(matched.current_count));
  table_.set_gateway_participants(announced);
  table_.set_discovery_settled(settled);
}

bool ValveView::wait_until(const Condition& condition, Deadline until,
                           const std::atomic<bool>& interrupted) const {
  // Discovery changes (matched writers) notify nobody: look again at least this often.
  constexpr auto kRecheck = std::chrono::milliseconds(50);
  for (;;) {
    update_gateways_matched();
    std::unique_lock lock(mutex_);
    if (condition(table_)) return true;
    const auto now = std::chrono::steady_clock::now();
    if (interrupted || now >= until) return false;
    changed_.wait_for(lock, std::min<std::chrono::steady_clock::duration>(kRecheck, until - now));
  }
}

}  // namespace teejet::client
