#include "foxglove_feed.hpp"

#include <chrono>
#include <cstring>
#include <fastdds/dds/core/condition/StatusCondition.hpp>
#include <fastdds/dds/core/condition/WaitSet.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <utility>

namespace teejet::web::foxglove {
namespace {

// Longest wait between looks at the stop flag.
constexpr auto kLongestWait = std::chrono::milliseconds(100);

}  // namespace

struct Feed::Readers {
  std::vector<std::unique_ptr<recording::TopicReader>> readers;  // by topic index
  eprosima::fastdds::dds::WaitSet wait_set;
};

Result<std::unique_ptr<Feed>> Feed::start(dds::Participant& participant, Deliver deliver) {
  auto readers = std::make_unique<Readers>();
  // Made whole before anything can fail: the destructor deletes what was made.
  std::unique_ptr<Feed> feed(new Feed(participant, std::move(readers), std::move(deliver)));
  for (const recording::TopicType& type : recording::topic_types()) {
    auto reader = type.open_reader(participant);
    if (!reader) return reader.error();
    auto& condition = (*reader)->reader()->get_statuscondition();
    condition.set_enabled_statuses(eprosima::fastdds::dds::StatusMask::data_available());
    feed->readers_->wait_set.attach_condition(condition);
    feed->readers_->readers.push_back(std::move(*reader));
  }
  feed->thread_ = std::thread([raw = feed.get()] { raw->run(); });
  return feed;
}

Feed::Feed(dds::Participant& participant, std::unique_ptr<Readers> readers, Deliver deliver)
    : participant_(participant), readers_(std::move(readers)), deliver_(std::move(deliver)) {}

Feed::~Feed() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
  // Out of the WaitSet before their conditions go.
  for (const auto& reader : readers_->readers) {
    readers_->wait_set.detach_condition(reader->reader()->get_statuscondition());
    participant_.delete_reader(reader->reader());
  }
}

void Feed::run() {
  std::vector<recording::TakenSample> taken;
  while (!stop_) {
    eprosima::fastdds::dds::ConditionSeq active;
    readers_->wait_set.wait(active, dds::to_dds_duration(kLongestWait));
    std::vector<FeedSample> batch;
    for (std::size_t topic = 0; topic < readers_->readers.size(); ++topic) {
      taken.clear();
      readers_->readers[topic]->take(taken);
      for (auto& sample : taken) batch.push_back({topic, std::move(sample)});
    }
    if (!batch.empty()) deliver_(std::move(batch));
  }
}

}  // namespace teejet::web::foxglove
