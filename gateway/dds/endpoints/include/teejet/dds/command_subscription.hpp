#pragma once

// The gateway's command reader. Commands are taken on the caller's thread, which waits on a
// WaitSet, never on Fast DDS's listener threads: the bridge's work never runs under the
// middleware's locks. News of a lost commander (a command writer's liveliness, a participant's
// lease) arrives on Fast DDS's threads and is only queued there.

#include <fastdds/dds/core/condition/GuardCondition.hpp>
#include <fastdds/dds/core/condition/WaitSet.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "teejet/core/time.hpp"
#include "teejet/dds/participant.hpp"
#include "teejet/valve.h"

namespace teejet::dds {

// Identifies a command's writer in logs and in the fail-safe ("01.0f.ab...|0.0.1.3").
std::string writer_id(const eprosima::fastrtps::rtps::InstanceHandle_t& handle);

// Commanders reported lost on Fast DDS's threads (a command writer's liveliness, a participant's
// lease), waiting for the command thread. Shared: whoever reports may outlive the subscription.
class LostCommanders {
 public:
  void report(std::string commander);  // any thread
  std::vector<std::string> take();
  eprosima::fastdds::dds::GuardCondition& attention() { return attention_; }

 private:
  eprosima::fastdds::dds::GuardCondition attention_;
  std::mutex mutex_;
  std::vector<std::string> lost_;
};

class CommandSubscription {
 public:
  struct Received {
    ValveCommand command;
    std::string writer;  // writer_id() of its writer
  };
  // What one wait brought: commands in the order they were written, and lost commanders (writer
  // ids, or GUID prefixes of participants whose lease expired).
  struct Events {
    std::vector<Received> commands;
    std::vector<LayoutChange> layout_changes;
    std::vector<std::string> lost_commanders;
  };

  // `lost` also collects what the participant's on_participant_dropped reports. With
  // `layout_changes`, layout changes are taken too, when DDS-Security lets this participant read
  // them (a warning says when it does not).
  static Result<std::unique_ptr<CommandSubscription>> create(Participant& participant,
                                                             std::shared_ptr<LostCommanders> lost,
                                                             bool layout_changes = false);
  ~CommandSubscription();  // detaches the listener and deletes the reader, in that order
  CommandSubscription(const CommandSubscription&) = delete;
  CommandSubscription& operator=(const CommandSubscription&) = delete;

  // Waits until commands, layout changes or a lost commander arrive, wake() is called or `timeout`
  // passes, and takes what there is. One thread calls it.
  Events wait(Duration timeout);

  // Makes a wait() return now (to stop, or to look at a new deadline). Any thread.
  void wake();

 private:
  class LivelinessListener;

  CommandSubscription(Participant& participant, std::shared_ptr<LostCommanders> lost);

  Participant& participant_;
  std::shared_ptr<LostCommanders> lost_;
  eprosima::fastdds::dds::GuardCondition wake_;
  std::unique_ptr<LivelinessListener> listener_;
  eprosima::fastdds::dds::DataReader* reader_ = nullptr;
  eprosima::fastdds::dds::DataReader* layout_reader_ = nullptr;
  eprosima::fastdds::dds::WaitSet wait_set_;
};

}  // namespace teejet::dds
