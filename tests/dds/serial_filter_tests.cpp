// The content filter on a valve's serial (dds/serial_filter.hpp): its expression, and the serial
// it reads from every type a reader may filter, serialized as Fast DDS sends it.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <fastdds/dds/core/LoanableSequence.hpp>
#include <type_traits>
#include <variant>

#include "teejet/dds/conversions.hpp"
#include "teejet/dds/serial_filter.hpp"
#include "teejet/dds/topics.hpp"
#include "teejet/valvePubSubTypes.h"

namespace teejet::dds {
namespace {

using eprosima::fastdds::dds::IContentFilter;
using eprosima::fastrtps::rtps::SerializedPayload_t;
using ReturnCode = eprosima::fastrtps::types::ReturnCode_t;

TEST(SerialFilter, TheExpressionIsTheSerialsInDecimal) {
  EXPECT_EQ(serial_filter_expression({200005, 1}), "1 200005");
  EXPECT_EQ(parse_serial_filter("1 200005"), (std::set<std::uint32_t>{1, 200005}));
  EXPECT_EQ(parse_serial_filter(" 7  7 "), (std::set<std::uint32_t>{7}));
  for (const char* refused : {"", " ", "1,2", "-1", "x", "0x10", "4294967296", "1 two"}) {
    EXPECT_FALSE(parse_serial_filter(refused)) << refused;
  }
}

// A sample of `serial` as a writer serializes it.
template <class Sample>
SerializedPayload_t serialized(std::uint32_t serial) {
  typename PubSubTypeOf<Sample>::type type;
  Sample sample;
  sample.serial(serial);
  SerializedPayload_t payload(type.getSerializedSizeProvider(&sample)());
  EXPECT_TRUE(type.serialize(&sample, &payload));
  return payload;
}

template <class... Samples>
void every_filterable_type(std::type_identity<std::variant<Samples...>>) {
  const auto one = [](auto identity) {
    using Sample = typename decltype(identity)::type;
    const auto payload = serialized<Sample>(0x00AB'CDEF);
    EXPECT_EQ(serial_of(payload), 0x00AB'CDEFu) << topics::topic_name<Sample>();
  };
  (one(std::type_identity<Samples>{}), ...);
  one(std::type_identity<ValvePresence>{});
}

TEST(SerialFilter, ReadsTheSerialOfPresenceAndOfEveryTelemetryType) {
  every_filterable_type(std::type_identity<TelemetrySample>{});
}

TEST(SerialFilter, ReadsEitherByteOrderAndLetsAnotherRepresentationPass) {
  SerializedPayload_t big(8);
  const std::array<unsigned char, 8> big_bytes{0, 0, 0, 0, 0x00, 0x03, 0x0D, 0x45};
  std::copy(big_bytes.begin(), big_bytes.end(), big.data);
  big.length = 8;
  EXPECT_EQ(serial_of(big), 200005u);
  SerializedPayload_t little(8);
  const std::array<unsigned char, 8> little_bytes{0, 1, 0, 0, 0x45, 0x0D, 0x03, 0x00};
  std::copy(little_bytes.begin(), little_bytes.end(), little.data);
  little.length = 8;
  EXPECT_EQ(serial_of(little), 200005u);

  const SerialFilter filter({200005});
  EXPECT_TRUE(filter.evaluate(little, {}, {}));
  little.data[4] = 0x46;
  EXPECT_FALSE(filter.evaluate(little, {}, {}));
  // Parameter-list CDR (0x0003), or a payload too short to hold a serial: passed on.
  little.data[1] = 3;
  EXPECT_FALSE(serial_of(little));
  EXPECT_TRUE(filter.evaluate(little, {}, {}));
  little.data[1] = 1;
  little.length = 6;
  EXPECT_TRUE(filter.evaluate(little, {}, {}));
}

TEST(SerialFilter, TheFactoryMakesFiltersOfItsClassFromValidExpressionsOnly) {
  SerialFilterFactory factory;
  IContentFilter* filter = nullptr;
  const eprosima::fastdds::dds::LoanableSequence<const char*> none;
  EXPECT_EQ(factory.create_content_filter(kSerialFilterClass, "teejet::ValvePosition", nullptr,
                                          "1 2", none, filter),
            ReturnCode::RETCODE_OK);
  ASSERT_NE(filter, nullptr);
  EXPECT_TRUE(filter->evaluate(serialized<ValvePosition>(2), {}, {}));
  EXPECT_FALSE(filter->evaluate(serialized<ValvePosition>(3), {}, {}));
  EXPECT_EQ(factory.delete_content_filter(kSerialFilterClass, filter), ReturnCode::RETCODE_OK);

  IContentFilter* refused = nullptr;
  EXPECT_EQ(factory.create_content_filter(kSerialFilterClass, "teejet::ValvePosition", nullptr,
                                          "1;2", none, refused),
            ReturnCode::RETCODE_BAD_PARAMETER);
  EXPECT_EQ(
      factory.create_content_filter("DDSSQL", "teejet::ValvePosition", nullptr, "1", none, refused),
      ReturnCode::RETCODE_BAD_PARAMETER);
  EXPECT_EQ(refused, nullptr);
}

}  // namespace
}  // namespace teejet::dds
