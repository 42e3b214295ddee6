#include "dds_support.hpp"

#include <thread>

namespace teejet::bench {

using ReturnCode = eprosima::fastrtps::types::ReturnCode_t;

bool wait_until(const std::function<bool()>& condition, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!condition()) {
    if (std::chrono::steady_clock::now() >= deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return true;
}

bool matched(fdds::DataWriter* writer) {
  fdds::PublicationMatchedStatus status;
  return writer->get_publication_matched_status(status) == ReturnCode::RETCODE_OK &&
         status.current_count > 0;
}

bool matched(fdds::DataReader* reader) {
  fdds::SubscriptionMatchedStatus status;
  return reader->get_subscription_matched_status(status) == ReturnCode::RETCODE_OK &&
         status.current_count > 0;
}

}  // namespace teejet::bench
