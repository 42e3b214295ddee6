#pragma once

// How the page's commands reach the valves: through the DDS client's CommandClient, whose
// statuses are followed for the ticks, and for the targets of teejet-web's own moves; and how
// its layout changes reach the gateways: through a LayoutClient, likewise followed.

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <set>
#include <vector>

#include "page_command.hpp"
#include "target_tracker.hpp"
#include "teejet/client/command_client.hpp"
#include "teejet/client/valve_view.hpp"
#include "teejet/core/result.hpp"
#include "teejet/dds/participant.hpp"
#include "teejet/valve.h"

namespace teejet::web {

// Thread-safe: the WebSocket callbacks send while the tick takes statuses and targets.
class DdsSender final : public CommandSender {
 public:
  // `view` tells how many gateways to wait for on the first command; both must outlive this.
  DdsSender(dds::Participant& participant, client::ValveView& view)
      : participant_(participant), view_(view) {}

  // A command or change sent is held: its statuses wait in take_statuses() until answered()
  // says the page has its answer (the command_id the page matches its statuses with).
  Result<std::uint32_t> send(ValveCommand command) override;
  Result<std::uint32_t> send(LayoutChange change, const std::string& participant) override;
  void answered(const std::vector<std::uint32_t>& command_ids,
                const std::vector<std::uint32_t>& change_ids);

  // The statuses that arrived since the last call, in order; the tick hands them to every page.
  struct Statuses {
    std::vector<CommandStatus> commands;
    std::vector<LayoutChangeStatus> layout_changes;
  };
  Statuses take_statuses();

  Targets targets();

  // The table a command is checked against. The first call waits up to 5 s for the directory
  // to be complete (every gateway met has told its valves and places): a command that comes as
  // teejet-web starts is not refused for a valve it has yet to hear of. Later calls do not wait,
  // whether it completed or not.
  client::ValveTable directory();

 private:
  Result<client::CommandClient*> connected();
  std::vector<CommandStatus> take_command_statuses();
  std::vector<LayoutChangeStatus> take_layout_change_statuses();

  dds::Participant& participant_;
  client::ValveView& view_;
  std::atomic<bool> directory_awaited_{false};
  std::mutex connect_mutex_;
  std::mutex mutex_;
  std::unique_ptr<client::CommandClient> client_;
  TargetTracker tracker_;
  std::set<std::uint32_t> open_;        // command ids not yet final
  std::set<std::uint32_t> unanswered_;  // of those, the ones whose page has no answer yet
  // Made on the first layout change, and each change waits for its gateway to match it: a
  // setup page may assign on a gateway that joined after the first change.
  std::mutex layout_mutex_;
  std::unique_ptr<client::LayoutClient> layout_client_;
  std::set<std::uint32_t> open_changes_;  // change ids the gateway has not answered
  // Of those, the ones whose page has no answer yet. A lock of its own: answered() runs on the
  // I/O thread, which must not wait for a send's match.
  std::mutex unanswered_changes_mutex_;
  std::set<std::uint32_t> unanswered_changes_;
};

}  // namespace teejet::web
