#include "teejet/recording/latest_samples.hpp"

namespace teejet::recording {

bool LatestSamples::admit(std::size_t topic, const TopicType& type, TakenSample& sample) {
  const Key key{topic, sample.instance};
  if (sample.disposed) {
    const auto last = held_.find(key);
    if (last == held_.end()) return false;
    sample.payload = std::move(last->second.payload);
    held_.erase(last);
  } else if (type.keyed && type.durable) {
    held_[key] =
        LatestSample{sample.source_ns != 0 ? sample.source_ns : sample.received_ns, sample.payload};
  }
  return true;
}

}  // namespace teejet::recording
