// Address claiming at 0xD5 as ISO 11783-5 / J1939-81 ask it of a controller at a fixed address:
// the frames with their exact identifiers and bytes, the wait after the claim, answers to
// requests, contention both ways, giving the address up and taking it back, violations and the
// table of neighbours.

#include <gtest/gtest.h>

#include <algorithm>

#include "teejet/isobus/address_claimer.hpp"

namespace teejet::isobus {
namespace {

using namespace std::chrono_literals;

constexpr SteadyTime kStart{std::chrono::hours(1)};
constexpr Timestamp kWall{std::chrono::hours(24 * 365 * 56)};

// The default NAME with a manufacturer code and an identity number: 0x200880000A000100. The
// contenders differ from it in the identity number alone.
Name gateway_name() {
  Name name = ClaimConfig::default_name();
  name.identity_number = 0x100;
  name.manufacturer_code = 0x50;
  return name;
}
Name lower_priority() {  // a higher value
  Name name = gateway_name();
  name.identity_number = 0x101;
  return name;
}
Name higher_priority() {  // a lower value
  Name name = gateway_name();
  name.identity_number = 0x0FF;
  return name;
}

codec::CanFrame frame(std::uint32_t id, std::vector<std::uint8_t> bytes) {
  codec::CanFrame made;
  made.id = id;
  made.extended = true;
  made.dlc = static_cast<std::uint8_t>(bytes.size());
  std::copy(bytes.begin(), bytes.end(), made.data.begin());
  return made;
}

std::vector<std::uint8_t> bytes_of(const codec::CanFrame& made) {
  return {made.data.begin(), made.data.begin() + made.dlc};
}

std::vector<std::uint32_t> ids_of(const ClaimReaction& reaction) {
  std::vector<std::uint32_t> ids;
  for (const auto& sent : reaction.send) ids.push_back(sent.id);
  return ids;
}

bool said(const ClaimReaction& reaction, const std::string& part) {
  return std::any_of(reaction.notices.begin(), reaction.notices.end(), [&](const auto& notice) {
    return notice.text.find(part) != std::string::npos;
  });
}

class AddressClaimerTest : public ::testing::Test {
 protected:
  AddressClaimer claimer{ClaimConfig{.name = gateway_name()}};

  // Claimed and past the wait.
  void hold() {
    (void)claimer.claim(kStart);
    (void)claimer.tick(kStart + 250ms);
    ASSERT_EQ(claimer.state(), ClaimState::kClaimed);
  }
  ClaimReaction hear(const codec::CanFrame& heard, SteadyTime at = kStart + 1s) {
    return claimer.on_frame(heard, kWall, at);
  }
};

TEST_F(AddressClaimerTest, ClaimsWithARequestToEveryoneThenItsNameFrom0xD5) {
  EXPECT_FALSE(claimer.may_send()) << "nothing before the claim";
  const auto reaction = claimer.claim(kStart);
  ASSERT_EQ(reaction.send.size(), 2u);
  // Request for Address Claimed, PGN 59904 to 0xFF from the null address 0xFE: 00 EE 00.
  EXPECT_EQ(reaction.send[0].id, 0x18EAFFFEu);
  EXPECT_EQ(bytes_of(reaction.send[0]), (std::vector<std::uint8_t>{0x00, 0xEE, 0x00}));
  // Address Claimed, PGN 60928 to 0xFF from 0xD5: the NAME 0x200880000A000100, LSB first.
  EXPECT_EQ(to_value(gateway_name()), 0x200880000A000100ULL);
  EXPECT_EQ(reaction.send[1].id, 0x18EEFFD5u);
  EXPECT_EQ(bytes_of(reaction.send[1]),
            (std::vector<std::uint8_t>{0x00, 0x01, 0x00, 0x0A, 0x00, 0x80, 0x08, 0x20}));
  EXPECT_EQ(claimer.counters().claims_sent, 1u);
}

TEST_F(AddressClaimerTest, SendsNothingElseFor250msAfterTheClaim) {
  (void)claimer.claim(kStart);
  EXPECT_EQ(claimer.state(), ClaimState::kClaiming);
  EXPECT_EQ(claimer.next_deadline(), kStart + 250ms);
  EXPECT_FALSE(claimer.tick(kStart + 249ms).became_claimed);
  EXPECT_FALSE(claimer.may_send());
  ASSERT_TRUE(claimer.refusal());
  EXPECT_NE(claimer.refusal()->find("claiming its address 0xD5"), std::string::npos);
  const auto held = claimer.tick(kStart + 250ms);
  EXPECT_TRUE(held.became_claimed);
  EXPECT_TRUE(claimer.may_send());
  EXPECT_FALSE(claimer.refusal());
  EXPECT_EQ(claimer.next_deadline(), std::nullopt);
}

TEST_F(AddressClaimerTest, AnswersRequestsToEveryoneAndTo0xD5Only) {
  hold();
  EXPECT_EQ(ids_of(hear(request_for_address_claimed(0xFF, 0x80))),
            std::vector<std::uint32_t>{0x18EEFFD5u});
  EXPECT_EQ(ids_of(hear(request_for_address_claimed(0xD5, 0x80))),
            std::vector<std::uint32_t>{0x18EEFFD5u});
  EXPECT_TRUE(hear(request_for_address_claimed(0x26, 0x80)).send.empty());
  // A request for another PGN is not one for address claims.
  EXPECT_TRUE(hear(frame(0x18EAD580, {0x00, 0xEF, 0x00})).send.empty());
}

TEST_F(AddressClaimerTest, ALowerPriorityContenderIsAnsweredWithTheClaimAgain) {
  hold();
  const auto reaction = hear(address_claimed(lower_priority(), 0xD5));
  EXPECT_EQ(ids_of(reaction), std::vector<std::uint32_t>{0x18EEFFD5u});
  EXPECT_EQ(claimer.state(), ClaimState::kClaimed);
  EXPECT_TRUE(claimer.may_send());
  EXPECT_EQ(claimer.counters().contentions_won, 1u);
}

TEST_F(AddressClaimerTest, AHigherPriorityContenderTakesTheAddressAndCommandsAreRefused) {
  hold();
  const auto reaction = hear(address_claimed(higher_priority(), 0xD5));
  ASSERT_EQ(reaction.send.size(), 1u);
  EXPECT_EQ(reaction.send[0].id, 0x18EEFFFEu) << "Cannot Claim Address, from the null address";
  EXPECT_EQ(bytes_of(reaction.send[0]),
            (std::vector<std::uint8_t>{0x00, 0x01, 0x00, 0x0A, 0x00, 0x80, 0x08, 0x20}));
  EXPECT_EQ(claimer.state(), ClaimState::kYielded);
  EXPECT_FALSE(claimer.may_send());
  EXPECT_EQ(claimer.holder(), higher_priority());
  ASSERT_TRUE(claimer.refusal());
  EXPECT_NE(claimer.refusal()->find("NAME 0x200880000A0000FF"), std::string::npos)
      << *claimer.refusal();
  EXPECT_TRUE(said(reaction, "gave up address 0xD5 to NAME 0x200880000A0000FF"));
  EXPECT_EQ(claimer.counters().contentions_lost, 1u);
  // Asked by everyone, it says it has no address; the holder answers for 0xD5.
  EXPECT_EQ(ids_of(hear(request_for_address_claimed(0xFF, 0x80))),
            std::vector<std::uint32_t>{0x18EEFFFEu});
  EXPECT_TRUE(hear(request_for_address_claimed(0xD5, 0x80)).send.empty());
  // The holder's own traffic from 0xD5 is no violation.
  EXPECT_TRUE(hear(frame(0x18EFD9D5, {0x04})).send.empty());
  EXPECT_EQ(claimer.counters().address_violations, 0u);
}

TEST_F(AddressClaimerTest, TakesTheAddressBackWhenTheHolderStopsAnswering) {
  hold();
  const SteadyTime lost = kStart + 1s;
  (void)hear(address_claimed(higher_priority(), 0xD5), lost);
  EXPECT_EQ(claimer.next_deadline(), lost + 5s);
  // Every 5 s a request to 0xD5 from the null address: 0x18EAD5FE.
  EXPECT_EQ(ids_of(claimer.tick(lost + 5s)), std::vector<std::uint32_t>{0x18EAD5FEu});
  // The holder answers: still its.
  (void)hear(address_claimed(higher_priority(), 0xD5), lost + 5s + 100ms);
  EXPECT_TRUE(claimer.tick(lost + 7s).send.empty());
  EXPECT_EQ(claimer.state(), ClaimState::kYielded);
  // The next request goes unanswered for 1.25 s: the address is free.
  EXPECT_EQ(ids_of(claimer.tick(lost + 10s)), std::vector<std::uint32_t>{0x18EAD5FEu});
  EXPECT_TRUE(claimer.tick(lost + 11s).send.empty());
  const auto taken = claimer.tick(lost + 11250ms);
  EXPECT_EQ(ids_of(taken), std::vector<std::uint32_t>{0x18EEFFD5u});
  EXPECT_TRUE(said(taken, "no longer answers for 0xD5"));
  EXPECT_EQ(claimer.state(), ClaimState::kClaiming);
  EXPECT_TRUE(claimer.tick(lost + 11500ms).became_claimed);
}

TEST_F(AddressClaimerTest, TheWaitRunsFromWhenTheClaimWentOut) {
  const auto reaction = claimer.claim(kStart);
  EXPECT_TRUE(reaction.claim_sent);
  claimer.wait_from(kStart + 8ms);  // the request before it took 8 ms
  EXPECT_FALSE(claimer.tick(kStart + 250ms).became_claimed);
  EXPECT_TRUE(claimer.tick(kStart + 258ms).became_claimed);
}

TEST_F(AddressClaimerTest, OnlyTheHolderOfOurAddressIsANeighbourThere) {
  hold();
  (void)hear(address_claimed(lower_priority(), 0xD5));
  EXPECT_FALSE(claimer.claimed_by_neighbour(0xD5)) << "the contender lost: not there";
  (void)hear(address_claimed(higher_priority(), 0xD5), kStart + 2s);
  EXPECT_TRUE(claimer.claimed_by_neighbour(0xD5)) << "the holder";
  (void)claimer.tick(kStart + 7s);      // the probe
  (void)claimer.tick(kStart + 8250ms);  // unanswered: taken back
  EXPECT_EQ(claimer.state(), ClaimState::kClaiming);
  EXPECT_FALSE(claimer.claimed_by_neighbour(0xD5)) << "the silent holder is gone";
}

TEST_F(AddressClaimerTest, TakesTheAddressBackWhenTheHolderCannotClaimOrMoves) {
  hold();
  (void)hear(address_claimed(higher_priority(), 0xD5));
  EXPECT_EQ(ids_of(hear(cannot_claim_address(higher_priority()))),
            std::vector<std::uint32_t>{0x18EEFFD5u});
  EXPECT_EQ(claimer.state(), ClaimState::kClaiming);
  (void)claimer.tick(kStart + 2s);
  (void)hear(address_claimed(higher_priority(), 0xD5), kStart + 3s);
  EXPECT_EQ(claimer.state(), ClaimState::kYielded);
  EXPECT_EQ(ids_of(hear(address_claimed(higher_priority(), 0x90), kStart + 4s)),
            std::vector<std::uint32_t>{0x18EEFFD5u});
  EXPECT_EQ(claimer.state(), ClaimState::kClaiming);
}

TEST_F(AddressClaimerTest, AFrameFrom0xD5ThatIsNotOursIsAViolationAndTheClaimIsRepeated) {
  hold();
  const auto reaction = hear(frame(0x18EFD9D5, {0x04}));
  EXPECT_EQ(ids_of(reaction), std::vector<std::uint32_t>{0x18EEFFD5u});
  EXPECT_TRUE(said(reaction, "address violation: frame 0x18EFD9D5 from 0xD5"));
  EXPECT_EQ(claimer.counters().address_violations, 1u);
  EXPECT_EQ(claimer.state(), ClaimState::kClaimed);
}

TEST_F(AddressClaimerTest, KeepsEveryNeighbourByAddressAndWarnsOfClaimsWhereValvesLive) {
  hold();
  Name terminal;
  terminal.identity_number = 7;
  terminal.function = 29;  // a virtual terminal
  terminal.industry_group = 2;
  EXPECT_TRUE(hear(address_claimed(terminal, 0x26)).notices.empty());
  const auto in_valve_range = hear(address_claimed(lower_priority(), 0xE0));
  EXPECT_TRUE(in_valve_range.notices.at(0).warning);
  EXPECT_TRUE(said(in_valve_range, "claimed 0xE0, an address valves pick"));
  EXPECT_EQ(claimer.counters().claims_in_valve_range, 1u);
  EXPECT_TRUE(claimer.claimed_by_neighbour(0xE0));
  EXPECT_FALSE(claimer.claimed_by_neighbour(0xE1));
  auto neighbours = claimer.neighbours();
  ASSERT_EQ(neighbours.size(), 2u);
  EXPECT_EQ(neighbours[0].address, 0x26);
  EXPECT_EQ(neighbours[0].name, terminal);
  EXPECT_EQ(neighbours[0].last_seen, kWall);
  EXPECT_EQ(neighbours[1].address, 0xE0);
  // The same NAME claiming elsewhere has moved; Cannot Claim takes it off the table.
  (void)hear(address_claimed(lower_priority(), 0x81));
  EXPECT_FALSE(claimer.claimed_by_neighbour(0xE0));
  EXPECT_TRUE(claimer.claimed_by_neighbour(0x81));
  (void)hear(cannot_claim_address(terminal));
  neighbours = claimer.neighbours();
  ASSERT_EQ(neighbours.size(), 1u);
  EXPECT_EQ(neighbours[0].address, 0x81);
}

TEST(AddressClaimerOff, ClaimsAndAnswersNothingButStillKnowsItsNeighbours) {
  AddressClaimer claimer{ClaimConfig{.claim = false}};
  EXPECT_EQ(claimer.state(), ClaimState::kOff);
  EXPECT_TRUE(claimer.may_send());
  EXPECT_TRUE(claimer.claim(kStart).send.empty());
  EXPECT_TRUE(
      claimer.on_frame(request_for_address_claimed(0xFF, 0x80), kWall, kStart).send.empty());
  const auto contender = claimer.on_frame(address_claimed(higher_priority(), 0xD5), kWall, kStart);
  EXPECT_TRUE(contender.send.empty());
  EXPECT_TRUE(said(contender, "isobus.claim is off"));
  EXPECT_TRUE(claimer.may_send());
  EXPECT_EQ(claimer.neighbours().size(), 1u);
}

}  // namespace
}  // namespace teejet::isobus
