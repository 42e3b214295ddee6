// Compiled into every suite that links teejet_dds_test_support (an INTERFACE source: an object
// of a static library that no test calls into would be left out of the link).
//
// A DDS test process holds several participants at once: the gateway runtime and the peers
// playing ECUs. Fast DDS 2.9.1 hands a sample between participants of one process directly, on
// the sending thread, and its automatic liveliness assertion (WLP::automatic_liveliness_assertion)
// sends while holding its participant's PDP mutex; the receiving participant's WLPListener then
// takes that participant's PDP mutex. Two participants asserting liveliness at once take the two
// mutexes in opposite orders and their event threads block each other for good; deleting a reader
// then waits forever too (fixed upstream in 2.10.5, 2.14.3 and 3.0.0, never in 2.9).
// USER_DATA_ONLY sends the built-in protocols (liveliness, endpoint discovery) through the
// profile's transports, to be received on the other participant's own threads, and keeps
// samples direct: with intraprocess delivery wholly off, a flood of command statuses outruns the
// status writer's KEEP_LAST 32, and a reader then misses some, as one in another process would.

#include <fastrtps/attributes/LibrarySettingsAttributes.h>
#include <fastrtps/xmlparser/XMLProfileManager.h>
#include <gtest/gtest.h>

namespace teejet::testing {
namespace {

class BuiltinTrafficThroughTransports final : public ::testing::Environment {
 public:
  // Before the first test, so before any participant: Fast DDS reads the setting whenever two
  // endpoints match.
  void SetUp() override {
    eprosima::fastrtps::LibrarySettingsAttributes settings;
    settings.intraprocess_delivery = eprosima::fastrtps::INTRAPROCESS_USER_DATA_ONLY;
    eprosima::fastrtps::xmlparser::XMLProfileManager::library_settings(settings);
  }
};

[[maybe_unused]] ::testing::Environment* const builtin_traffic_through_transports =
    ::testing::AddGlobalTestEnvironment(new BuiltinTrafficThroughTransports);

}  // namespace
}  // namespace teejet::testing
