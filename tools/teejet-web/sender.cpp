#include "sender.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <iterator>
#include <set>
#include <utility>

namespace teejet::web {
namespace {

using Clock = std::chrono::steady_clock;

// How long the first command waits for the gateways to match the command writer.
constexpr auto kConnectTimeout = std::chrono::seconds(5);

}  // namespace

Result<std::uint32_t> DdsSender::send(ValveCommand command) {
  auto client = connected();
  if (!client) return client.error();
  std::lock_guard lock(mutex_);
  const auto id = (*client)->send(command);
  if (!id) return Error{ErrorCode::kInvalidValue, "DDS did not take the command"};
  command.command_id(*id);
  tracker_.on_sent(command);
  open_.insert(*id);
  unanswered_.insert(*id);
  return *id;
}

Result<std::uint32_t> DdsSender::send(LayoutChange change, const std::string& participant) {
  std::lock_guard lock(layout_mutex_);
  if (!layout_client_) {
    auto made = client::LayoutClient::create(participant_, client::default_origin("teejet-web"));
    if (!made) return made.error();
    layout_client_ = std::move(*made);
  }
  const std::atomic<bool> never{false};
  const auto matched =
      layout_client_->connect({participant}, 0, Clock::now() + kConnectTimeout, never);
  if (!matched) return matched.error();
  if (!*matched) {
    return Error{ErrorCode::kInvalidValue, "gateway " + change.gateway().to_string() +
                                               " did not subscribe to layout changes within 5 s; "
                                               "nothing was sent"};
  }
  const auto id = layout_client_->send(change);
  if (!id) return Error{ErrorCode::kInvalidValue, "DDS did not take the layout change"};
  open_changes_.insert(*id);
  std::lock_guard held(unanswered_changes_mutex_);
  unanswered_changes_.insert(*id);
  return *id;
}

void DdsSender::answered(const std::vector<std::uint32_t>& command_ids,
                         const std::vector<std::uint32_t>& change_ids) {
  if (!command_ids.empty()) {
    std::lock_guard lock(mutex_);
    for (const auto id : command_ids) unanswered_.erase(id);
  }
  if (!change_ids.empty()) {
    std::lock_guard lock(unanswered_changes_mutex_);
    for (const auto id : change_ids) unanswered_changes_.erase(id);
  }
}

DdsSender::Statuses DdsSender::take_statuses() {
  return {take_command_statuses(), take_layout_change_statuses()};
}

std::vector<CommandStatus> DdsSender::take_command_statuses() {
  std::lock_guard lock(mutex_);
  std::vector<CommandStatus> statuses;
  if (!client_) return statuses;
  for (auto it = open_.begin(); it != open_.end();) {
    if (unanswered_.count(*it) != 0) {
      ++it;
      continue;
    }
    bool final = false;
    while (const auto status = client_->next_status(*it, Clock::now())) {
      tracker_.on_status(*status);
      statuses.push_back(*status);
      final = final || status->state() != COMMAND_ACCEPTED;
    }
    it = final ? open_.erase(it) : std::next(it);
  }
  return statuses;
}

// A gateway answers a layout change once, applied or rejected. The lock is tried, not waited
// for: a send holds it while its gateway matches (up to 5 s), and the ticks must go on meanwhile;
// what arrived is taken at a later tick.
std::vector<LayoutChangeStatus> DdsSender::take_layout_change_statuses() {
  std::vector<LayoutChangeStatus> statuses;
  std::unique_lock lock(layout_mutex_, std::try_to_lock);
  if (!lock || !layout_client_) return statuses;
  std::lock_guard held(unanswered_changes_mutex_);
  for (auto it = open_changes_.begin(); it != open_changes_.end();) {
    if (unanswered_changes_.count(*it) != 0) {
      ++it;
      continue;
    }
    const auto status = layout_client_->next_status(*it, Clock::now());
    if (status) statuses.push_back(*status);
    it = status ? open_changes_.erase(it) : std::next(it);
  }
  return statuses;
}

Targets DdsSender::targets() {
  std::lock_guard lock(mutex_);
  return tracker_.targets();
}

client::ValveTable DdsSender::directory() {
  if (!directory_awaited_.exchange(true)) {
    const std::atomic<bool> never{false};
    view_.wait_until([](const client::ValveTable& table) { return table.directory_complete(); },
                     Clock::now() + kConnectTimeout, never);
  }
  return view_.snapshot();
}

// Connects on the first command: a read-only dashboard never announces a command writer.
// Under its own lock, so that ticks go on while discovery takes its time.
Result<client::CommandClient*> DdsSender::connected() {
  std::lock_guard connecting(connect_mutex_);
  {
    std::lock_guard lock(mutex_);
    if (client_) return client_.get();
  }
  auto made = client::CommandClient::create(participant_, client::default_origin("teejet-web"));
  if (!made) return made.error();
  // Every gateway known by then must hear the writer; one that joins later matches it by itself.
  const std::atomic<bool> never{false};
  const auto until = Clock::now() + kConnectTimeout;
  view_.wait_until([](const client::ValveTable& table) { return !table.gateways().empty(); }, until,
                   never);
  std::set<std::string> gateways;
  for (const auto& gateway : view_.gateways()) {
    gateways.insert(gateway.participants.begin(), gateway.participants.end());
  }
  if (gateways.empty()) return Error{ErrorCode::kInvalidValue, "no gateway found (waited 5 s)"};
  const auto matched = (*made)->connect(gateways, 0, until, never);
  if (!matched) return matched.error();
  if (!*matched) {
    const auto missing = (*made)->unmatched(gateways).size();
    return Error{ErrorCode::kInvalidValue, std::to_string(missing) + " of " +
                                               std::to_string(gateways.size()) +
                                               " gateways did not subscribe to commands "
                                               "within 5 s"};
  }
  std::lock_guard lock(mutex_);
  client_ = std::move(*made);
  return client_.get();
}

}  // namespace teejet::web
