// Address arbitration, readdressing, routing by address and staggered I'm Here.

#include <gtest/gtest.h>

#include <set>

#include "sim_test_support.hpp"
#include "teejet/sim/valve_bank.hpp"

namespace teejet::sim::testing {
namespace {

std::vector<ValveConfig> valves_with(std::initializer_list<std::uint32_t> serials) {
  std::vector<ValveConfig> configs;
  for (const auto serial : serials) {
    ValveConfig config;
    config.serial = serial;
    configs.push_back(config);
  }
  return configs;
}

TEST(SimValveBank, RanksBySerialLowestFirstWhateverTheOrderGiven) {
  ValveBank bank;
  ASSERT_TRUE(bank.power_up(valves_with({300, 100, 200}), kT0));
  EXPECT_EQ(bank.assignments(), (std::vector<Assignment>{{100, 0xD8}, {200, 0xD9}, {300, 0xDA}}));
  EXPECT_EQ(bank.address_of(200), std::optional<std::uint8_t>(0xD9));
  EXPECT_FALSE(bank.address_of(400));
  EXPECT_EQ(bank.valve_at(0xDA)->serial(), 300u);
  EXPECT_EQ(bank.valve_at(0xDB), nullptr);
  EXPECT_EQ(bank.valve_at(0xD5), nullptr);
}

TEST(SimValveBank, RefusesEmptyDuplicateInvalidAndOversizedBanks) {
  EXPECT_FALSE(ValveBank{}.power_up({}, kT0));
  const auto duplicate = ValveBank{}.power_up(valves_with({5, 6, 5}), kT0);
  EXPECT_FALSE(duplicate);
  EXPECT_NE(duplicate.error().reason.find("TJV000005"), std::string::npos);
  auto invalid = valves_with({1});
  invalid[0].opened_degrees = 350;
  EXPECT_FALSE(ValveBank{}.power_up(invalid, kT0));

  std::vector<ValveConfig> thirty_three;
  for (std::uint32_t serial = 1; serial <= 33; ++serial) thirty_three.push_back(valve_with(serial));
  ValveBank bank;
  const auto refused = bank.power_up(thirty_three, kT0);
  EXPECT_FALSE(refused);
  EXPECT_NE(refused.error().reason.find("33 valves"), std::string::npos) << refused.error().reason;
  EXPECT_EQ(bank.size(), 0u);
  thirty_three.pop_back();
  EXPECT_TRUE(bank.power_up(thirty_three, kT0));
  EXPECT_EQ(bank.assignments().back(), (Assignment{32, 0xF7}));
}

TEST(SimValveBank, AThirtyThirdValveAddedAtRunTimeIsRefusedAndNothingChanges) {
  std::vector<ValveConfig> configs;
  for (std::uint32_t serial = 10; serial < 42; ++serial) configs.push_back(valve_with(serial));
  ValveBank bank;
  ASSERT_TRUE(bank.power_up(configs, kT0));
  const auto before = bank.assignments();
  const auto refused = bank.add_valve(valve_with(1), at_ms(10));
  EXPECT_FALSE(refused);
  EXPECT_NE(refused.error().reason.find("0xD8-0xF7"), std::string::npos) << refused.error().reason;
  EXPECT_EQ(bank.assignments(), before);
}

TEST(SimValveBank, AddingALowerSerialReshufflesTheAddressesAbove) {
  ValveBank bank;
  ASSERT_TRUE(bank.power_up({valve_with(100, 10.0), valve_with(300, 30.0)}, kT0));
  std::vector<AddressChange> changes;
  ASSERT_TRUE(bank.add_valve(valve_with(200, 20.0), at_ms(5000), &changes));
  EXPECT_EQ(changes, (std::vector<AddressChange>{{200, std::nullopt, 0xD9}, {300, 0xD9, 0xDA}}));
  EXPECT_EQ(bank.assignments(), (std::vector<Assignment>{{100, 0xD8}, {200, 0xD9}, {300, 0xDA}}));
  // Frames to 0xD9 now reach the new valve; the moved one answers at 0xDA.
  auto at_d9 = bank.handle(0xD9, codec::RequestPosition{0}, at_ms(5001));
  ASSERT_EQ(at_d9.size(), 1u);
  EXPECT_EQ(at_d9[0].address, 0xD9);
  EXPECT_EQ(at_d9[0].message, (codec::FromValveMessage{codec::Position{20.0}}));
  auto at_da = bank.handle(0xDA, codec::RequestPosition{0}, at_ms(5001));
  ASSERT_EQ(at_da.size(), 1u);
  EXPECT_EQ(at_da[0].message, (codec::FromValveMessage{codec::Position{30.0}}));
}

TEST(SimValveBank, MovedAndNewValvesAnnounceAtTheirNewAddressesTheOthersKeepTheirRhythm) {
  ValveBank bank;
  ASSERT_TRUE(bank.power_up({valve_with(100), valve_with(300)}, kT0));
  EXPECT_EQ(bank.advance(kT0).size(), 1u);                    // 100 at 0xD8
  EXPECT_EQ(bank.advance(kT0 + kIAmHereStagger).size(), 1u);  // 300 at 0xD9
  ASSERT_TRUE(bank.add_valve(valve_with(50), at_ms(400)));
  // Ranks: 50 -> 0xD8 (announces at 400), 100 -> 0xD9 (400 + 31.25), 300 -> 0xDA (400 + 62.5).
  auto announced = bank.advance(at_ms(400));
  ASSERT_EQ(announced.size(), 1u);
  EXPECT_EQ(announced[0].address, 0xD8);
  EXPECT_EQ(announced[0].message, (codec::FromValveMessage{codec::IAmHere{0, 50, false}}));
  announced = bank.advance(at_ms(400) + kIAmHereStagger);
  ASSERT_EQ(announced.size(), 1u);
  EXPECT_EQ(announced[0].address, 0xD9);
  EXPECT_EQ(announced[0].message, (codec::FromValveMessage{codec::IAmHere{0, 100, false}}));
  announced = bank.advance(at_ms(400) + 2 * kIAmHereStagger);
  ASSERT_EQ(announced.size(), 1u);
  EXPECT_EQ(announced[0].address, 0xDA);
  // Adding the highest serial moves nobody.
  std::vector<AddressChange> changes;
  ASSERT_TRUE(bank.add_valve(valve_with(900), at_ms(600), &changes));
  EXPECT_EQ(changes, (std::vector<AddressChange>{{900, std::nullopt, 0xDB}}));
}

TEST(SimValveBank, ADuplicateOrInvalidValveIsRefused) {
  ValveBank bank;
  ASSERT_TRUE(bank.power_up({valve_with(100)}, kT0));
  EXPECT_FALSE(bank.add_valve(valve_with(100), at_ms(1)));
  ValveConfig bad = valve_with(7);
  bad.degrees_per_second = 0;
  EXPECT_FALSE(bank.add_valve(bad, at_ms(1)));
  EXPECT_EQ(bank.size(), 1u);
}

TEST(SimValveBank, IAmHereOfAFullBankIsSpreadOverTheSecond) {
  std::vector<ValveConfig> configs;
  for (std::uint32_t serial = 1; serial <= 32; ++serial) configs.push_back(valve_with(serial));
  ValveBank bank;
  ASSERT_TRUE(bank.power_up(configs, kT0));
  std::set<std::uint8_t> announced;
  for (int rank = 0; rank < 32; ++rank) {
    const auto at = kT0 + rank * kIAmHereStagger;
    EXPECT_EQ(bank.next_due(), std::optional(at));
    const auto out = bank.advance(at);
    ASSERT_EQ(out.size(), 1u) << "rank " << rank;
    EXPECT_EQ(out[0].address, 0xD8 + rank);
    EXPECT_EQ(std::get<codec::IAmHere>(out[0].message).serial,
              static_cast<std::uint32_t>(rank + 1));
    announced.insert(out[0].address);
  }
  EXPECT_EQ(announced.size(), 32u);
  EXPECT_LT(31 * kIAmHereStagger, std::chrono::seconds(1));
  EXPECT_EQ(bank.next_due(), std::optional(kT0 + std::chrono::seconds(1)));  // rank 0 again
}

TEST(SimValveBank, FramesToAnEmptyAddressAreIgnored) {
  ValveBank bank;
  ASSERT_TRUE(bank.power_up({valve_with(1)}, kT0));
  EXPECT_TRUE(bank.handle(0xE0, codec::RequestVersion{}, kT0).empty());
  EXPECT_EQ(bank.handle(0xD8, codec::RequestVersion{}, kT0).size(), 1u);
}

TEST(SimValveBank, ErrorsAreInjectedBySerial) {
  ValveBank bank;
  ASSERT_TRUE(bank.power_up({valve_with(1), valve_with(2)}, kT0));
  EXPECT_FALSE(bank.inject_error(3, codec::HighVoltageError{16, 15}, kT0));
  EXPECT_FALSE(bank.inject_error(2, codec::HighTemperatureError{300, 15}, kT0));
  EXPECT_EQ(bank.advance(at_ms(100)).size(), 2u);  // the I'm Here of both
  ASSERT_TRUE(bank.inject_error(2, codec::LowVoltageError{9, 10}, at_ms(500)));
  const auto out = bank.advance(at_ms(500));
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].address, 0xD9);
  EXPECT_EQ(out[0].message, (codec::FromValveMessage{codec::LowVoltageError{9, 10}}));
}

TEST(SimValveBank, SerialForAnAddedValveTakesTheFirstAddress) {
  EXPECT_EQ(serial_for_added_valve({}), std::optional<std::uint32_t>(1));
  EXPECT_EQ(serial_for_added_valve({{1, 0xD8}, {2, 0xD9}}), std::optional<std::uint32_t>(0));
  EXPECT_EQ(serial_for_added_valve({{123456, 0xD8}}), std::optional<std::uint32_t>(123455));
  EXPECT_EQ(serial_for_added_valve({{0, 0xD8}, {5, 0xD9}}), std::optional<std::uint32_t>(6));
  EXPECT_FALSE(serial_for_added_valve({{0, 0xD8}, {kMaxSerial, 0xD9}}));
}

}  // namespace
}  // namespace teejet::sim::testing
