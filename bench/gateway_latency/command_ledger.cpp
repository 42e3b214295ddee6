#include "command_ledger.hpp"

#include <cctype>

namespace teejet::bench {

std::uint32_t CommandLedger::next_id() {
  std::lock_guard lock(mutex_);
  return ++sent_;
}

void CommandLedger::record(const CommandStatus& status) {
  std::lock_guard lock(mutex_);
  const std::uint32_t id = status.command_id();
  if (id == 0 || id > sent_) {
    ++counts_.unknown;
    return;
  }
  const CommandState state = status.state();
  if (state == COMMAND_ACCEPTED) {
    ++counts_.accepted;
    return;
  }
  if (!final_state_.emplace(id, state).second) {
    ++counts_.duplicate_finals;
    return;
  }
  switch (state) {
    case COMMAND_COMPLETED:
      ++counts_.completed;
      break;
    case COMMAND_SUPERSEDED:
      ++counts_.superseded;
      break;
    case COMMAND_TIMED_OUT:
      ++counts_.timed_out;
      break;
    default:
      ++counts_.rejected;
      break;
  }
  if (state == COMMAND_TIMED_OUT || state == COMMAND_REJECTED) {
    ++counts_.reasons[mask_numbers(status.reason().to_string())];
  }
}

LedgerCounts CommandLedger::counts() const {
  std::lock_guard lock(mutex_);
  LedgerCounts counts = counts_;
  counts.sent = sent_;
  counts.unaccounted = sent_ - static_cast<std::uint32_t>(final_state_.size());
  return counts;
}

std::uint32_t CommandLedger::unaccounted() const { return counts().unaccounted; }

std::string mask_numbers(const std::string& reason) {
  const auto digit = [](char c) { return std::isdigit(static_cast<unsigned char>(c)) != 0; };
  const auto hex = [](char c) { return std::isxdigit(static_cast<unsigned char>(c)) != 0; };
  std::string out;
  for (std::size_t i = 0; i < reason.size();) {
    if (reason.compare(i, 2, "0x") == 0 && i + 2 < reason.size() && hex(reason[i + 2])) {
      out += "0x*";
      for (i += 2; i < reason.size() && hex(reason[i]); ++i) {
      }
    } else if (digit(reason[i])) {
      out += '*';
      while (i < reason.size() && (digit(reason[i]) || (reason[i] == '.' && i + 1 < reason.size() &&
                                                        digit(reason[i + 1])))) {
        ++i;
      }
    } else {
      out += reason[i++];
    }
  }
  return out;
}

}  // namespace teejet::bench
