// The generated types as idl/patch_generated.cmake leaves them: a sample costs its fields only
// (no type object registration per sample), and the types are announced in discovery only when
// the build asks for it (TEEJET_DDS_TYPE_OBJECTS).

#include <fastrtps/types/TypeObjectFactory.h>
#include <gtest/gtest.h>

#include <initializer_list>

#include "teejet/valve.h"
#include "teejet/valvePubSubTypes.h"
#include "teejet/valveTypeObject.h"

namespace teejet {
namespace {

using eprosima::fastrtps::types::TypeObjectFactory;

constexpr const char* kTypeNames[] = {
    "teejet::SoftwareVersion", "teejet::ValvePresence",         "teejet::ValveVersion",
    "teejet::ValvePosition",   "teejet::ValveTemperature",      "teejet::ValveVoltage",
    "teejet::ValveCurrent",    "teejet::ValveDegreesPerSecond", "teejet::ValveSpeedDirection",
    "teejet::ValveRunTime",    "teejet::ValveCycleCounts",      "teejet::ValveBaudRate",
    "teejet::ValveError",      "teejet::ValveCommand",          "teejet::CommandStatus",
    "teejet::GatewayStatus"};

bool registered(const char* name) {
  auto* factory = TypeObjectFactory::get_instance();
  return factory->get_type_object(name, true) != nullptr &&
         factory->get_type_object(name, false) != nullptr;
}

constexpr bool kAnnounced = TEEJET_DDS_TYPE_OBJECTS;

void construct_samples() {
  for (int i = 0; i < 100; ++i) {
    ValvePosition position;
    ValveCommand command;
    CommandStatus status;
    GatewayStatus gateway;
    ValveError error;
    (void)position;
    (void)command;
    (void)status;
    (void)gateway;
    (void)error;
  }
}

// One test, one process (ctest runs each test case on its own): the factory starts empty.
TEST(GeneratedTypes, ConstructingSamplesRegistersNoTypeObject) {
  construct_samples();
  for (const char* name : kTypeNames) {
    EXPECT_FALSE(registered(name)) << name << " was registered by constructing samples";
  }
}

// Off by default (TEEJET_DDS_TYPE_OBJECTS): no TypeObject, no TypeInformation in discovery,
// and nothing registered that a receive thread could race (docs/types.md).
TEST(GeneratedTypes, TypesAreAnnouncedOnlyWhenTheBuildAsksForIt) {
  ValveCommandPubSubType command;
  ValvePositionPubSubType position;
  CommandStatusPubSubType status;
  GatewayStatusPubSubType gateway;
  for (const eprosima::fastdds::dds::TopicDataType* type :
       std::initializer_list<const eprosima::fastdds::dds::TopicDataType*>{&command, &position,
                                                                           &status, &gateway}) {
    EXPECT_EQ(type->auto_fill_type_object(), kAnnounced) << type->getName();
    EXPECT_EQ(type->auto_fill_type_information(), kAnnounced) << type->getName();
  }
  for (const char* name : kTypeNames) EXPECT_EQ(registered(name), kAnnounced) << name;
}

// Tools and ECUs that want the type objects without announcing them register them themselves.
TEST(GeneratedTypes, ExplicitRegistrationRegistersEveryTypeAndMayBeRepeated) {
  registervalveTypes();
  registervalveTypes();
  for (const char* name : kTypeNames) EXPECT_TRUE(registered(name)) << name;
}

}  // namespace
}  // namespace teejet
