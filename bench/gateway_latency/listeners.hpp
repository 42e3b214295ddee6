#pragma once

// Reader listeners of the bench. Each must outlive the participant that calls it: declare it
// before the participant, so that it is destroyed after.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <functional>
#include <map>
#include <mutex>
#include <optional>

#include "series.hpp"

namespace teejet::bench {

// Arrival times keyed by a number each sample carries (a sequence number, the position in
// tenths of a degree). The clock is read first thing in the listener: that is "on arrival".
template <class Sample>
class ArrivalLog final : public eprosima::fastdds::dds::DataReaderListener {
 public:
  struct Arrival {
    std::int64_t arrived_ns = 0;
    std::uint64_t carried_ns = 0;  // a time the sample itself carries (received_ns), or 0
  };
  using KeyOf = std::function<std::optional<std::int64_t>(const Sample&)>;
  using CarriedTimeOf = std::function<std::uint64_t(const Sample&)>;

  explicit ArrivalLog(KeyOf key_of, CarriedTimeOf carried_time_of = nullptr)
      : key_of_(std::move(key_of)), carried_time_of_(std::move(carried_time_of)) {}

  void on_data_available(eprosima::fastdds::dds::DataReader* reader) override {
    const std::int64_t arrived = realtime_ns();
    Sample sample;
    eprosima::fastdds::dds::SampleInfo info;
    while (reader->take_next_sample(&sample, &info) == ReturnCode::RETCODE_OK) {
      if (!info.valid_data) continue;
      const auto key = key_of_(sample);
      if (!key) continue;
      std::lock_guard lock(mutex_);
      arrivals_[*key] = {arrived, carried_time_of_ ? carried_time_of_(sample) : 0};
    }
    arrived_.notify_all();
  }

  std::optional<Arrival> wait_for(std::int64_t key, std::chrono::milliseconds timeout) {
    std::unique_lock lock(mutex_);
    if (!arrived_.wait_for(lock, timeout, [&] { return arrivals_.contains(key); })) {
      return std::nullopt;
    }
    return arrivals_[key];
  }

  std::map<std::int64_t, Arrival> arrivals() const {
    std::lock_guard lock(mutex_);
    return arrivals_;
  }

  void clear() {
    std::lock_guard lock(mutex_);
    arrivals_.clear();
  }

 private:
  using ReturnCode = eprosima::fastrtps::types::ReturnCode_t;

  const KeyOf key_of_;
  const CarriedTimeOf carried_time_of_;
  mutable std::mutex mutex_;
  std::condition_variable arrived_;
  std::map<std::int64_t, Arrival> arrivals_;
};

// Hands every valid sample to a function, on Fast DDS's listener thread.
template <class Sample>
class OnSample final : public eprosima::fastdds::dds::DataReaderListener {
 public:
  explicit OnSample(std::function<void(const Sample&)> handle) : handle_(std::move(handle)) {}

  void on_data_available(eprosima::fastdds::dds::DataReader* reader) override {
    Sample sample;
    eprosima::fastdds::dds::SampleInfo info;
    while (reader->take_next_sample(&sample, &info) == ReturnCode::RETCODE_OK) {
      if (info.valid_data) handle_(sample);
    }
  }

 private:
  using ReturnCode = eprosima::fastrtps::types::ReturnCode_t;

  const std::function<void(const Sample&)> handle_;
};

}  // namespace teejet::bench
