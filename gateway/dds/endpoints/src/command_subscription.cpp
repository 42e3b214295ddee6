#include "teejet/dds/command_subscription.hpp"

#include <fastdds/rtps/common/Guid.h>
#include <spdlog/spdlog.h>

#include <fastdds/dds/core/condition/StatusCondition.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <sstream>

#include "teejet/dds/topics.hpp"

namespace teejet::dds {

using namespace eprosima::fastdds::dds;

std::string writer_id(const eprosima::fastrtps::rtps::InstanceHandle_t& handle) {
  std::ostringstream text;
  text << eprosima::fastrtps::rtps::iHandle2GUID(handle);
  return text.str();
}

void LostCommanders::report(std::string commander) {
  {
    std::lock_guard lock(mutex_);
    lost_.push_back(std::move(commander));
  }
  attention_.set_trigger_value(true);
}

std::vector<std::string> LostCommanders::take() {
  std::lock_guard lock(mutex_);
  attention_.set_trigger_value(false);
  return std::exchange(lost_, {});
}

// Liveliness changes name their writer only in the callback (the status a WaitSet would read
// keeps just the last one), so this listener stays, and only queues.
class CommandSubscription::LivelinessListener final : public DataReaderListener {
 public:
  explicit LivelinessListener(std::shared_ptr<LostCommanders> lost) : lost_(std::move(lost)) {}
  void on_liveliness_changed(DataReader*, const LivelinessChangedStatus& status) override {
    if (status.not_alive_count_change > 0) lost_->report(writer_id(status.last_publication_handle));
  }

 private:
  std::shared_ptr<LostCommanders> lost_;
};

CommandSubscription::CommandSubscription(Participant& participant,
                                         std::shared_ptr<LostCommanders> lost)
    : participant_(participant),
      lost_(std::move(lost)),
      listener_(std::make_unique<LivelinessListener>(lost_)) {}

Result<std::unique_ptr<CommandSubscription>> CommandSubscription::create(
    Participant& participant, std::shared_ptr<LostCommanders> lost, bool layout_changes) {
  std::unique_ptr<CommandSubscription> made(new CommandSubscription(participant, std::move(lost)));
  auto topic = participant.topic<ValveCommandPubSubType>(topics::kCommand);
  if (!topic) return topic.error();
  // Data is taken on the waiting thread: the listener hears of liveliness only.
  auto reader = participant.reader(*topic, topics::command_reader_qos(), made->listener_.get(),
                                   StatusMask::liveliness_changed());
  if (!reader) return reader.error();
  made->reader_ = *reader;
  StatusCondition& data = made->reader_->get_statuscondition();
  data.set_enabled_statuses(StatusMask::data_available());
  made->wait_set_.attach_condition(data);
  made->wait_set_.attach_condition(made->lost_->attention());
  made->wait_set_.attach_condition(made->wake_);
  if (layout_changes) {
    auto changes = topics::topic_of<LayoutChange>(participant);
    auto layout_reader = changes ? participant.reader(*changes, topics::command_reader_qos(),
                                                      nullptr, StatusMask::none())
                                 : Result<DataReader*>(changes.error());
    if (!layout_reader) {
      spdlog::warn(
          "cannot read {} ({}): this gateway takes no layout changes over DDS (valvectl assign); "
          "give the gateway role subscribe permission for it (config/security/roles/gateway.xml)",
          topics::kLayoutChange, layout_reader.error().reason);
      return made;
    }
    made->layout_reader_ = *layout_reader;
    StatusCondition& changed = made->layout_reader_->get_statuscondition();
    changed.set_enabled_statuses(StatusMask::data_available());
    made->wait_set_.attach_condition(changed);
  }
  return made;
}

CommandSubscription::~CommandSubscription() {
  if (reader_ != nullptr) {
    (void)wait_set_.detach_condition(reader_->get_statuscondition());
    participant_.delete_reader(reader_);  // no callback reaches listener_ after this
  }
  if (layout_reader_ != nullptr) {
    (void)wait_set_.detach_condition(layout_reader_->get_statuscondition());
    participant_.delete_reader(layout_reader_);
  }
  (void)wait_set_.detach_condition(lost_->attention());
  (void)wait_set_.detach_condition(wake_);
}

CommandSubscription::Events CommandSubscription::wait(Duration timeout) {
  ConditionSeq triggered;
  (void)wait_set_.wait(triggered, to_dds_duration(timeout));  // TIMEOUT is an answer too

  wake_.set_trigger_value(false);
  Events events;
  ValveCommand command;
  SampleInfo info;
  while (reader_->take_next_sample(&command, &info) == ReturnCode_t::RETCODE_OK) {
    if (info.valid_data) events.commands.push_back({command, writer_id(info.publication_handle)});
  }
  if (layout_reader_ != nullptr) {
    LayoutChange change;
    while (layout_reader_->take_next_sample(&change, &info) == ReturnCode_t::RETCODE_OK) {
      if (info.valid_data) events.layout_changes.push_back(change);
    }
  }
  events.lost_commanders = lost_->take();
  return events;
}

void CommandSubscription::wake() { wake_.set_trigger_value(true); }

}  // namespace teejet::dds
