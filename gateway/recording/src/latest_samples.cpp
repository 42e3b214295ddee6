#include "teejet/recording/latest_samples.hpp"

#include <cstring>

#include "teejet/dds/participant.hpp"

namespace teejet::recording {

bool LatestSamples::admit(std::size_t topic, const TopicType& type, TakenSample& sample) {
  const Key key{topic, sample.instance};
  if (sample.writers_gone) {
    held_.erase(key);
    return false;
  }
  if (sample.disposed) {
    const auto last = held_.find(key);
    if (last == held_.end()) return false;
    sample.payload = std::move(last->second.payload);
    held_.erase(last);
  } else if (type.keyed && type.durable) {
    held_[key] = LatestSample{sample.source_ns != 0 ? sample.source_ns : sample.received_ns,
                              sample.payload, sample.writer};
  }
  return true;
}

void LatestSamples::forget_participants(const std::set<std::string>& participants) {
  std::erase_if(held_, [&](const auto& entry) {
    eprosima::fastrtps::rtps::InstanceHandle_t writer;
    std::memcpy(writer.value, entry.second.writer.data(), entry.second.writer.size());
    return participants.count(dds::participant_of(writer)) != 0;
  });
}

}  // namespace teejet::recording
