#pragma once

// For the test peers that run outside GoogleTest (tests/dds/command_writer.cpp,
// writer_teardown.cpp): header-only, as eventually.hpp.

#include <chrono>
#include <cstdio>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <string>

#include "support/eventually.hpp"

namespace teejet::testing {

// Why the peer stops, as "PEER: WHAT" on standard error; its exit status 1.
inline int refused(const char* peer, const std::string& what) {
  std::fprintf(stderr, "%s: %s\n", peer, what.c_str());
  return 1;
}

// Whether a reader matched `writer` within `deadline` (scaled, as eventually()).
inline bool reader_matched(eprosima::fastdds::dds::DataWriter& writer,
                           std::chrono::milliseconds deadline) {
  return eventually(
      [&] {
        eprosima::fastdds::dds::PublicationMatchedStatus status;
        return writer.get_publication_matched_status(status) ==
                   eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK &&
               status.current_count > 0;
      },
      deadline);
}

}  // namespace teejet::testing
