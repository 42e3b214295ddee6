// Must NOT compile (tests/dds/CMakeLists.txt, test dds_telemetry_without_topic_does_not_compile):
// issue 7, bug 6. A telemetry type added to the sample variant without a topic used to compile
// and dereference a null writer at run time; now the writer table asks topics::topic_of<> for its
// topic.

#include <variant>

#include "teejet/dds/gateway_publisher.hpp"

namespace {

// A sample type nobody gave a topic to.
struct Unpublished {
  std::uint32_t serial() const { return 0; }
  std::uint64_t received_ns() const { return 0; }
};

}  // namespace

int main() {
  teejet::dds::SampleWriters<std::variant<teejet::ValvePosition, Unpublished>> writers;
  auto participant = teejet::dds::Participant::create({});
  return writers.create(**participant, teejet::dds::topics::state_writer_qos()).ok() ? 0 : 1;
}
