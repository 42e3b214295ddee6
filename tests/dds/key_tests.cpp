// Instance keys computed by two threads at once on one type object, as a participant's writer
// and reader of one topic (or two receive threads) do: each key must be its own sample's.

#include <gtest/gtest.h>

#include <array>
#include <string>
#include <thread>
#include <vector>

#include "teejet/dds/participant.hpp"
#include "teejet/valvePubSubTypes.h"

namespace teejet::dds {
namespace {

using eprosima::fastrtps::rtps::InstanceHandle_t;

ValveLocation place(int n) {
  ValveLocation sample;
  sample.location("section-" + std::to_string(n));
  sample.gateway("a-gateway-name-long-enough-for-an-md5-key-" + std::to_string(n));
  return sample;
}

// How many of `rounds` keys each of two threads computed wrongly on one type object.
template <class Type>
int wrong_keys_of_two_threads(Type& type, int rounds) {
  std::array<ValveLocation, 2> samples{place(1), place(2)};
  std::array<InstanceHandle_t, 2> expected;
  for (std::size_t i = 0; i < 2; ++i) type.getKey(&samples[i], &expected[i], false);
  EXPECT_NE(expected[0], expected[1]);
  std::array<int, 2> wrong{0, 0};
  std::vector<std::thread> threads;
  for (std::size_t i = 0; i < 2; ++i) {
    threads.emplace_back([&, i] {
      for (int round = 0; round < rounds; ++round) {
        InstanceHandle_t handle;
        type.getKey(&samples[i], &handle, false);
        wrong[i] += handle != expected[i];
      }
    });
  }
  for (auto& thread : threads) thread.join();
  return wrong[0] + wrong[1];
}

TEST(InstanceKeys, TwoThreadsOnOneTypeObjectEachGetTheirSamplesKey) {
  KeyLockedType<ValveLocationPubSubType> type;
  EXPECT_EQ(wrong_keys_of_two_threads(type, 200'000), 0);
}

}  // namespace
}  // namespace teejet::dds
