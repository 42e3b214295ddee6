#pragma once

// Source timestamps that never go back on one writer.
//
// Fast DDS 2.9.1 files a reader's samples by source timestamp when they come from different
// writers and by sequence number when they come from one (history_order_cmp). When one writer's
// stamps go back, a sample of it that arrives late (its datagram was lost and sent again) can be
// filed after a later sample of the same writer. The reader then never counts it into its
// instance (History::get_change stops at the later one), hands it to take() all the same, and the
// next sample of that instance aborts the process: DataReaderInstance.hpp:105, "Assertion
// `ViewStateKind::NEW_VIEW_STATE == view_state' failed". It takes several writers, a lost
// datagram and stamps that go back: a presence stamped with its valve's last I'm Here after
// another valve's later one, a replay of several gateways' samples, a clock stepped back.
//
// Every reliable writer of ours stamps through one of these: each sample's source timestamp is
// the one it asks for, or the writer's previous one when that would go back (equal stamps of one
// writer are filed by sequence number). A best-effort writer needs none: its reader drops a
// sample older than the last it got instead of filing it late.

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <mutex>

#include "teejet/core/time.hpp"
#include "teejet/dds/participant.hpp"

namespace teejet::dds {

class SourceStamps {
 public:
  // Calls write(eprosima::fastrtps::Time_t) with the stamp for a sample that wants `wanted_ns`
  // (Unix nanoseconds) and returns what it returns. One write at a time: stamps rise with the
  // writer's sequence numbers, which the write hands out.
  template <class Write>
  auto write(std::uint64_t wanted_ns, Write&& write) {
    std::lock_guard lock(mutex_);
    last_ns_ = std::max(wanted_ns, last_ns_);
    return write(to_dds_time(last_ns_));
  }

  // The same, stamped now.
  template <class Write>
  auto write_now(Write&& write) {
    return this->write(unix_nanoseconds(std::chrono::system_clock::now()),
                       std::forward<Write>(write));
  }

 private:
  std::mutex mutex_;
  std::uint64_t last_ns_ = 0;
};

}  // namespace teejet::dds
