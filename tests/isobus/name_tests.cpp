// The NAME and the frames of address claiming, against values worked out by hand from the
// standard's bit layout (ISO 11783-5 / J1939-81).

#include <gtest/gtest.h>

#include "teejet/isobus/name.hpp"

namespace teejet::isobus {
namespace {

// identity 0x12345, manufacturer 0x2AB, ECU instance 1, function instance 2, function 0x81,
// device class 4, device class instance 0, industry group 2 (agricultural), not arbitrary
// address capable: 0x2008811155612345.
Name known_name() {
  Name name;
  name.identity_number = 0x12345;
  name.manufacturer_code = 0x2AB;
  name.ecu_instance = 1;
  name.function_instance = 2;
  name.function = 0x81;
  name.device_class = 4;
  name.industry_group = 2;
  return name;
}

TEST(IsobusName, FieldsSitWhereTheStandardPutsThem) {
  EXPECT_EQ(to_value(known_name()), 0x2008811155612345ULL);
  EXPECT_EQ(from_value(0x2008811155612345ULL), known_name());
  Name capable;
  capable.arbitrary_address_capable = true;
  EXPECT_EQ(to_value(capable), 0x8000000000000000ULL);
  capable = {};
  capable.device_class_instance = 0xF;
  EXPECT_EQ(to_value(capable), 0x0F00000000000000ULL);
  EXPECT_EQ(from_value(0x0001000000000000ULL), Name{}) << "bit 48 is reserved";
}

TEST(IsobusName, EveryFieldHasItsWidthAndRoundTripsAtItsLargestValue) {
  int bits = 0;
  for (const NameField& field : name_fields()) {
    Name name;
    set_field(name, field, field.max());
    EXPECT_EQ(field_value(name, field), field.max()) << field.name;
    EXPECT_EQ(from_value(to_value(name)), name) << field.name;
    bits += field.bits;
  }
  EXPECT_EQ(bits, 63);  // and the reserved bit
  EXPECT_EQ(name_fields()[0].max(), 0x1FFFFFu);
  EXPECT_EQ(name_fields()[1].max(), 0x7FFu);
}

TEST(IsobusName, TheLowerNameWins) {
  Name lower = known_name();
  Name higher = known_name();
  higher.identity_number += 1;
  EXPECT_TRUE(wins_over(lower, higher));
  EXPECT_FALSE(wins_over(higher, lower));
  EXPECT_FALSE(wins_over(lower, lower));
}

TEST(IsobusName, TextIsSixteenHexDigits) {
  EXPECT_EQ(to_text(known_name()), "0x2008811155612345");
  EXPECT_EQ(parse_name("0x2008811155612345").value(), known_name());
  EXPECT_EQ(parse_name("2008811155612345").value(), known_name());
  EXPECT_EQ(to_value(parse_name("0X20088111556123aB").value()), 0x20088111556123ABULL);
  EXPECT_EQ(parse_name("0x208811155612345").error().reason,
            "a NAME is 16 hexadecimal digits (0xA00C81045A20021B), not \"0x208811155612345\"");
  EXPECT_EQ(parse_name("0x200881115561234G").error().reason,
            "a NAME is 16 hexadecimal digits, \"0x200881115561234G\" is not");
}

TEST(IsobusFrames, AddressClaimedCarriesTheNameLeastSignificantByteFirst) {
  const codec::CanFrame claim = address_claimed(known_name(), 0xD5);
  EXPECT_EQ(claim.id, 0x18EEFFD5u);
  EXPECT_TRUE(claim.extended);
  EXPECT_EQ(claim.dlc, 8);
  EXPECT_EQ(claim.data,
            (std::array<std::uint8_t, 8>{0x45, 0x23, 0x61, 0x55, 0x11, 0x81, 0x08, 0x20}));
  const codec::CanFrame cannot = cannot_claim_address(known_name());
  EXPECT_EQ(cannot.id, 0x18EEFFFEu);
  EXPECT_EQ(cannot.data, claim.data);
}

TEST(IsobusFrames, ARequestForAddressClaimedNamesPgn60928) {
  const codec::CanFrame global = request_for_address_claimed(kGlobalAddress, 0x80);
  EXPECT_EQ(global.id, 0x18EAFF80u);
  EXPECT_EQ(global.dlc, 3);
  EXPECT_EQ(global.data[0], 0x00);
  EXPECT_EQ(global.data[1], 0xEE);
  EXPECT_EQ(global.data[2], 0x00);
  EXPECT_EQ(request_for_address_claimed(0xD5, 0x26).id, 0x18EAD526u);
}

TEST(IsobusFrames, FramesAreClassifiedForAddressClaiming) {
  EXPECT_EQ(classify(address_claimed(known_name(), 0x80)),
            NetworkFrame(AddressClaim{0x80, known_name()}));
  EXPECT_EQ(classify(cannot_claim_address(known_name())),
            NetworkFrame(AddressClaim{kNullAddress, known_name()}));
  EXPECT_EQ(classify(request_for_address_claimed(kGlobalAddress, 0x26)),
            NetworkFrame(ClaimRequest{kGlobalAddress, 0x26}));
  EXPECT_EQ(classify(request_for_address_claimed(0xD5, 0x26)),
            NetworkFrame(ClaimRequest{0xD5, 0x26}));
  // A request for another PGN (software identification, 0xFEDA) is not one for claims.
  codec::CanFrame other_request = request_for_address_claimed(0xD5, 0x26);
  other_request.data = {0xDA, 0xFE, 0x00};
  EXPECT_EQ(classify(other_request), NetworkFrame(OtherFrame{0x26}));
  // A valve's frame, a PDU2 frame, an 11-bit frame, a claim of the wrong length.
  codec::CanFrame valve_frame{.id = 0x18EFD5D8, .dlc = 8};
  EXPECT_EQ(classify(valve_frame), NetworkFrame(OtherFrame{0xD8}));
  EXPECT_EQ(classify(codec::CanFrame{.id = 0x18FEF100, .dlc = 8}), NetworkFrame(OtherFrame{0x00}));
  EXPECT_EQ(classify(codec::CanFrame{.id = 0x123, .extended = false, .dlc = 2}),
            NetworkFrame(OtherFrame{}));
  codec::CanFrame short_claim = address_claimed(known_name(), 0x80);
  short_claim.dlc = 7;
  EXPECT_EQ(classify(short_claim), NetworkFrame(OtherFrame{0x80}));
}

}  // namespace
}  // namespace teejet::isobus
