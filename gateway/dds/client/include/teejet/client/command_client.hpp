#pragma once

// Writes requests to the gateways and follows their statuses: ValveCommands and their
// CommandStatus, LayoutChanges and their LayoutChangeStatus. Every request gets a fresh id and
// the origin "valvectl@HOST:PID"; statuses of other senders are ignored, so several valvectl
// runs and ECUs can command the same domain at once.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <string_view>

#include "teejet/client/valve_view.hpp"
#include "teejet/dds/participant.hpp"
#include "teejet/dds/source_stamps.hpp"

namespace teejet::client {

// "PROGRAM@HOST:PID", at most 64 characters (the IDL's bound).
std::string default_origin(std::string_view program);

// What tells the two kinds of request apart: the status that answers one, the field that
// carries its id, and what messages call it. Topics follow from the types (dds::topics).
template <class Request>
struct RequestTopics;
template <>
struct RequestTopics<ValveCommand> {
  using Status = CommandStatus;
  static constexpr const char* kWhat = "command";
  static void set_id(ValveCommand& request, std::uint32_t id) { request.command_id(id); }
  static std::uint32_t id_of(const Status& status) { return status.command_id(); }
};
template <>
struct RequestTopics<LayoutChange> {
  using Status = LayoutChangeStatus;
  static constexpr const char* kWhat = "layout change";
  static void set_id(LayoutChange& request, std::uint32_t id) { request.change_id(id); }
  static std::uint32_t id_of(const Status& status) { return status.change_id(); }
};

template <class Request>
class RequestClient final : public eprosima::fastdds::dds::DataReaderListener {
 public:
  using Status = typename RequestTopics<Request>::Status;

  // Subscribes to command status at once; the command writer is created by connect().
  static Result<std::unique_ptr<RequestClient>> create(dds::Participant& participant,
                                                       std::string origin);
  ~RequestClient() override;
  RequestClient(const RequestClient&) = delete;
  RequestClient& operator=(const RequestClient&) = delete;

  // Waits until every gateway in `owners` (their participants, ValveRow::participant: the
  // gateways that own the valves to command) matches the status reader, then creates the
  // command writer and waits until each matches it too. Commands are VOLATILE: one written
  // before its gateway's reader matched would be lost, and a count of matched readers cannot
  // tell the owner's reader from another gateway's. Announcing the writer only after the reader
  // has matched gives the gateway a discovery round-trip to learn of the reader before it
  // writes a status (which is TRANSIENT_LOCAL as well, for the half-matched moment left).
  // With `command_readers` above the owners, the writer also waits for that many command
  // readers (a recorder) until `until`, then sends anyway.
  // False when an owner has not matched both by `until` (unmatched() names them) or when
  // interrupted; an Error when DDS refused the writer.
  Result<bool> connect(const std::set<std::string>& owners, std::size_t command_readers,
                       Deadline until, const std::atomic<bool>& interrupted);
  // The owners that have not matched both the status reader and the command writer.
  std::set<std::string> unmatched(const std::set<std::string>& owners) const;

  // Writes `command` with a fresh command_id and this client's origin; returns the id, or
  // nullopt when the write failed. Requires connect().
  std::optional<std::uint32_t> send(Request request);

  // The next status of command `id` not returned before, in the order the gateway wrote them;
  // nullopt when none arrives by `until`.
  std::optional<Status> next_status(std::uint32_t id, Deadline until);

  // Waits until every command reader this writer matched has acknowledged every command sent,
  // or `until`; false when one has not. A reader whose own side of the match came after the
  // write gets the command only by repair from this writer, so the writer must outlive that.
  bool delivered(Deadline until);

  const std::string& origin() const { return origin_; }

  void on_data_available(eprosima::fastdds::dds::DataReader* reader) override;
  void on_subscription_matched(
      eprosima::fastdds::dds::DataReader* reader,
      const eprosima::fastdds::dds::SubscriptionMatchedStatus& status) override;

 private:
  RequestClient(dds::Participant& participant, std::string origin);
  class CommandWriterMatches;
  // The owners not yet matched by the status reader and, `command_writer_too`, the writer.
  std::set<std::string> missing(const std::set<std::string>& owners, bool command_writer_too) const;

  dds::Participant& participant_;
  const std::string origin_;
  eprosima::fastdds::dds::DataReader* status_reader_ = nullptr;
  eprosima::fastdds::dds::DataWriter* command_writer_ = nullptr;
  dds::SourceStamps command_stamps_;
  std::uint32_t next_id_;
  std::unique_ptr<CommandWriterMatches> writer_matches_;

  // The participants of the endpoints matched so far, from the matched callbacks (Fast DDS 2.9
  // cannot list them: get_matched_publications is unsupported). A multiset: one participant may
  // have several.
  mutable std::mutex match_mutex_;
  std::multiset<std::string> status_writers_;
  std::multiset<std::string> command_readers_;

  std::mutex mutex_;
  std::condition_variable arrived_;
  std::map<std::uint32_t, std::deque<Status>> statuses_;  // by request id, not yet read
};

using CommandClient = RequestClient<ValveCommand>;
using LayoutClient = RequestClient<LayoutChange>;
extern template class RequestClient<ValveCommand>;
extern template class RequestClient<LayoutChange>;

}  // namespace teejet::client
