#include "teejet/client/command_client.hpp"

#include <unistd.h>

#include <array>
#include <fastdds/dds/publisher/DataWriterListener.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <random>
#include <thread>
#include <vector>

#include "teejet/dds/topics.hpp"
#include "teejet/valvePubSubTypes.h"

namespace teejet::client {

using eprosima::fastdds::dds::DataReader;
using eprosima::fastdds::dds::SampleInfo;
using ReturnCode = eprosima::fastrtps::types::ReturnCode_t;

namespace {

constexpr std::size_t kMaxOriginLength = 64;  // string<64> in the IDL
constexpr auto kMatchPoll = std::chrono::milliseconds(10);

// Ids start at a random point: a restarted valvectl with a recycled PID (same origin) must not
// pick up statuses that belong to its predecessor.
std::uint32_t random_first_id() {
  std::random_device entropy;
  std::uniform_int_distribution<std::uint32_t> pick(1, 0x7FFFFFFF);
  return pick(entropy);
}

// How long the extra readers of --command-readers get to match this writer on their own side.
constexpr auto kReaderSideOfMatch = std::chrono::milliseconds(250);

// Fast DDS offers no wait on matches without a listener of one's own; polling is cheap and short.
bool wait_for(const std::function<bool()>& done, Deadline until,
              const std::atomic<bool>& interrupted) {
  while (!done()) {
    if (interrupted || std::chrono::steady_clock::now() >= until) return false;
    std::this_thread::sleep_for(kMatchPoll);
  }
  return true;
}

void count_match(std::multiset<std::string>& participants, int change,
                 const eprosima::fastrtps::rtps::InstanceHandle_t& endpoint) {
  const auto participant = dds::participant_of(endpoint);
  if (change > 0) {
    participants.insert(participant);
  } else if (change < 0) {
    if (const auto it = participants.find(participant); it != participants.end()) {
      participants.erase(it);
    }
  }
}

}  // namespace

std::string default_origin(std::string_view program) {
  std::array<char, 256> host{};
  if (::gethostname(host.data(), host.size() - 1) != 0) host[0] = '\0';
  // Appended, not "a" + b: GCC 12 reports a false -Wrestrict on that at -O3.
  std::string pid = ":";
  pid += std::to_string(::getpid());
  std::string origin(program);
  origin += '@';
  origin += host.data();
  // Keep the PID, which tells two runs on one host apart, when a long host name must be cut.
  origin.resize(std::min(origin.size(), kMaxOriginLength - pid.size()));
  return origin + pid;
}

template <class Request>
class RequestClient<Request>::CommandWriterMatches final
    : public eprosima::fastdds::dds::DataWriterListener {
 public:
  explicit CommandWriterMatches(RequestClient& client) : client_(client) {}
  void on_publication_matched(
      eprosima::fastdds::dds::DataWriter* /*writer*/,
      const eprosima::fastdds::dds::PublicationMatchedStatus& status) override {
    std::lock_guard lock(client_.match_mutex_);
    count_match(client_.command_readers_, status.current_count_change,
                status.last_subscription_handle);
  }

 private:
  RequestClient& client_;
};

template <class Request>
RequestClient<Request>::RequestClient(dds::Participant& participant, std::string origin)
    : participant_(participant), origin_(std::move(origin)), next_id_(random_first_id()) {}

template <class Request>
Result<std::unique_ptr<RequestClient<Request>>> RequestClient<Request>::create(
    dds::Participant& participant, std::string origin) {
  std::unique_ptr<RequestClient> client(new RequestClient(participant, std::move(origin)));
  auto topic = dds::topics::topic_of<Status>(participant);
  if (!topic) return topic.error();
  auto reader =
      participant.reader(*topic, dds::topics::status_reader_qos(), client.get(),
                         eprosima::fastdds::dds::StatusMask::data_available()
                             << eprosima::fastdds::dds::StatusMask::subscription_matched());
  if (!reader) return reader.error();
  client->status_reader_ = *reader;
  return client;
}

template <class Request>
RequestClient<Request>::~RequestClient() {
  // The participant outlives this client: delete the reader while its listener still exists.
  participant_.delete_reader(status_reader_);
  participant_.delete_writer(command_writer_);
}

template <class Request>
std::set<std::string> RequestClient<Request>::missing(const std::set<std::string>& owners,
                                                      bool command_writer_too) const {
  std::lock_guard lock(match_mutex_);
  std::set<std::string> missing;
  for (const auto& owner : owners) {
    if (!status_writers_.contains(owner) ||
        (command_writer_too && !command_readers_.contains(owner))) {
      missing.insert(owner);
    }
  }
  return missing;
}

template <class Request>
std::set<std::string> RequestClient<Request>::unmatched(const std::set<std::string>& owners) const {
  return missing(owners, /*command_writer_too=*/true);
}

template <class Request>
Result<bool> RequestClient<Request>::connect(const std::set<std::string>& owners,
                                             std::size_t command_readers, Deadline until,
                                             const std::atomic<bool>& interrupted) {
  const bool reader_matched = wait_for(
      [&] { return missing(owners, /*command_writer_too=*/false).empty(); }, until, interrupted);
  if (!reader_matched) return false;
  if (command_writer_ == nullptr) {
    auto topic = dds::topics::topic_of<Request>(participant_);
    if (!topic) return topic.error();
    writer_matches_ = std::make_unique<CommandWriterMatches>(*this);
    auto writer =
        participant_.writer(*topic, dds::topics::command_writer_qos(), writer_matches_.get());
    // The QoS is fixed, so a refusal here is DDS-Security: an observer's permissions say no.
    if (!writer) {
      return Error{ErrorCode::kDds, "this participant may not write " +
                                        dds::topics::topic_name<Request>() +
                                        " (its DDS-Security permissions do not grant it); no " +
                                        RequestTopics<Request>::kWhat + " was sent"};
    }
    command_writer_ = *writer;
  }
  const bool matched = wait_for([&] { return unmatched(owners).empty(); }, until, interrupted);
  if (!matched) return false;
  // Readers beyond the owners (a recorder) are waited for until `until`, then the commands go.
  const auto readers = [this] {
    std::lock_guard lock(match_mutex_);
    return command_readers_.size();
  };
  if (command_readers > owners.size()) {
    wait_for([&] { return readers() >= command_readers; }, until, interrupted);
    // The writer's side of a match comes first; a busy reader (a recorder taking thousands of
    // samples a second) may learn of this writer later. A Fast DDS reader then repairs what it
    // missed from this writer (delivered() keeps the writer until it has); a VOLATILE reader of
    // some other vendors instead skips what the first heartbeat it hears already counts (see
    // status_reader_qos). Asked-for extra readers get a moment more for that.
    std::this_thread::sleep_for(kReaderSideOfMatch);
  }
  return true;
}

template <class Request>
std::optional<std::uint32_t> RequestClient<Request>::send(Request request) {
  const std::uint32_t id = next_id_++;
  if (next_id_ == 0) next_id_ = 1;
  RequestTopics<Request>::set_id(request, id);
  request.origin(origin_);
  if (command_writer_ == nullptr) return std::nullopt;
  const auto written = command_stamps_.write_now([&](const auto& stamp) {
    return command_writer_->write_w_timestamp(&request, eprosima::fastdds::dds::HANDLE_NIL, stamp);
  });
  if (written != ReturnCode::RETCODE_OK) return std::nullopt;
  return id;
}

template <class Request>
bool RequestClient<Request>::delivered(Deadline until) {
  if (command_writer_ == nullptr) return true;
  return command_writer_->wait_for_acknowledgments(dds::to_dds_duration(
             until - std::chrono::steady_clock::now())) == ReturnCode::RETCODE_OK;
}

template <class Request>
auto RequestClient<Request>::next_status(std::uint32_t id, Deadline until)
    -> std::optional<Status> {
  std::unique_lock lock(mutex_);
  auto& queue = statuses_[id];
  if (!arrived_.wait_until(lock, until, [&] { return !queue.empty(); })) return std::nullopt;
  Status status = std::move(queue.front());
  queue.pop_front();
  return status;
}

template <class Request>
void RequestClient<Request>::on_subscription_matched(
    DataReader* /*reader*/, const eprosima::fastdds::dds::SubscriptionMatchedStatus& status) {
  std::lock_guard lock(match_mutex_);
  count_match(status_writers_, status.current_count_change, status.last_publication_handle);
}

template <class Request>
void RequestClient<Request>::on_data_available(DataReader* reader) {
  // Take first, then lock: Fast DDS holds the reader's lock while it calls the listener.
  std::vector<Status> ours;
  Status status;
  SampleInfo info;
  while (reader->take_next_sample(&status, &info) == ReturnCode::RETCODE_OK) {
    if (info.valid_data && status.origin().to_string() == origin_) ours.push_back(status);
  }
  if (ours.empty()) return;
  std::lock_guard lock(mutex_);
  for (const Status& taken : ours) statuses_[RequestTopics<Request>::id_of(taken)].push_back(taken);
  arrived_.notify_all();
}

template class RequestClient<ValveCommand>;
template class RequestClient<LayoutChange>;

}  // namespace teejet::client
