#pragma once

// The last sample of every instance of the state topics, as a subscriber to the teejet topics by
// their bytes sees them: what a disposal shows (on Fast DDS 2.9 a disposal carries no key, its
// DataReader::get_key_value being unsupported, so it is named by the instance's last sample),
// and what a newcomer starts from (a split recording's next file, a Foxglove client's new
// subscription).

#include <cstddef>
#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "teejet/recording/catalog.hpp"

namespace teejet::recording {

struct LatestSample {
  std::uint64_t source_ns = 0;  // its publish time: the writer's stamp, else its reception
  std::vector<std::uint8_t> payload;
  InstanceHandle writer{};
};

class LatestSamples {
 public:
  // By the caller's index of the topic, then the instance.
  using Key = std::pair<std::size_t, InstanceHandle>;

  // Takes in `sample` of the topic with index `topic` and type `type`: a sample of a keyed state
  // topic is held; a disposal gets the payload of its instance's last sample, which is no longer
  // held. False for a disposal of an instance never seen alive (nothing names it, it cannot be
  // shown) and for an instance whose writers left, which is forgotten: the present no longer
  // holds it.
  bool admit(std::size_t topic, const TopicType& type, TakenSample& sample);

  // Gateways are gone (stopped, or lost: Fast DDS 2.9 hands a reader no sample for either): the
  // instances whose last word was a writer of one of these participants (as
  // dds::participant_of names them) are forgotten.
  void forget_participants(const std::set<std::string>& participants);

  const std::map<Key, LatestSample>& held() const { return held_; }

 private:
  std::map<Key, LatestSample> held_;
};

}  // namespace teejet::recording
