#pragma once

// The teejet topics as the Foxglove clients get them: a reader of every topic with the
// recorder's QoS (gateway/recording's catalog), taken as CDR on a thread of its own and handed on
// in batches, so that neither DDS's threads nor the server's wait for the other.

#include <atomic>
#include <cstddef>
#include <functional>
#include <memory>
#include <thread>
#include <vector>

#include "teejet/core/result.hpp"
#include "teejet/dds/participant.hpp"
#include "teejet/recording/catalog.hpp"

namespace teejet::web::foxglove {

struct FeedSample {
  std::size_t topic = 0;  // the index of its type in recording::topic_types()
  recording::TakenSample taken;
};

class Feed {
 public:
  using Deliver = std::function<void(std::vector<FeedSample>)>;

  // Subscribes to every topic on `participant` and calls `deliver` from its thread with what
  // each wake-up took; an Error names what DDS refused. `participant` must outlive the feed.
  static Result<std::unique_ptr<Feed>> start(dds::Participant& participant, Deliver deliver);
  // Stops the thread and deletes the readers.
  ~Feed();
  Feed(const Feed&) = delete;
  Feed& operator=(const Feed&) = delete;

  struct Readers;  // the readers and their WaitSet, in foxglove_feed.cpp

 private:
  Feed(dds::Participant& participant, std::unique_ptr<Readers> readers, Deliver deliver);
  void run();

  dds::Participant& participant_;
  std::unique_ptr<Readers> readers_;
  const Deliver deliver_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace teejet::web::foxglove
