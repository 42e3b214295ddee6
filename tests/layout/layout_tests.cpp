// The layout's rules and its changes: names, orders and serials given once, machine order, the
// mechanics of each place, and what assigning and unassigning a serial does.

#include <gtest/gtest.h>

#include "teejet/layout/layout.hpp"

namespace teejet::layout {
namespace {

Location place(std::string name, unsigned order, std::optional<std::uint32_t> serial = {}) {
  return Location{.name = std::move(name), .order = order, .serial = serial};
}

std::string refusal(std::vector<Location> locations) {
  const auto layout = Layout::make(std::move(locations));
  return layout ? "" : layout.error().reason;
}

Layout boom() {
  return *Layout::make({place("section-02", 3, 12), place("left-master", 1, 10),
                        place("section-01", 2, 11), place("section-03", 4)},
                       Mechanics{.closed_degrees = 0, .opened_degrees = 90});
}

TEST(Layout, KeepsTheLocationsInMachineOrder) {
  const auto layout = boom();
  std::vector<std::string> names;
  for (const auto& location : layout.locations()) names.push_back(location.name);
  EXPECT_EQ(names,
            (std::vector<std::string>{"left-master", "section-01", "section-02", "section-03"}));
}

TEST(Layout, NamesAreLowerCaseWordsOfAtMost32Characters) {
  EXPECT_TRUE(check_name("section-01"));
  EXPECT_TRUE(check_name(std::string(32, 'a')));
  EXPECT_EQ(check_name(std::string(33, 'a')).error().complaint,
            "'" + std::string(33, 'a') + "' is 33 characters long, more than 32");
  EXPECT_EQ(check_name("").error().complaint, "is empty");
  EXPECT_EQ(check_name("Section-01").error().complaint,
            "'Section-01' is not lower-case letters, digits and '-' starting with a letter");
  EXPECT_EQ(check_name("1st").error().complaint,
            "'1st' is not lower-case letters, digits and '-' starting with a letter");
  EXPECT_EQ(check_name("section 1").error().field, "name");
}

TEST(Layout, ANameThatReadsAsASerialIsRefused) {
  EXPECT_EQ(check_name("tjv000017").error().complaint,
            "'tjv000017' reads as a serial, and a valve is named by either");
  EXPECT_TRUE(check_name("tjv"));
  EXPECT_TRUE(check_name("tjv-17"));
}

TEST(Layout, RefusesANameAnOrderOrASerialGivenTwice) {
  EXPECT_EQ(refusal({place("a", 1), place("a", 2)}), "location a: name is given twice");
  EXPECT_EQ(refusal({place("a", 1), place("b", 1)}), "location b: order 1 is a's order too");
  EXPECT_EQ(refusal({place("a", 1, 7), place("b", 2, 7)}),
            "location b: serial TJV000007 sits at a already");
}

TEST(Layout, RefusesAnOrderOutsideItsRangeAndImpossibleMechanics) {
  EXPECT_EQ(refusal({place("a", 0)}), "location a: order 0 is outside 1 to 9999");
  auto odd = place("a", 1);
  odd.mechanics = Mechanics{.closed_degrees = 0, .opened_degrees = 350};
  EXPECT_EQ(
      refusal({odd}),
      "location a: opened_degrees 350 is neither 360 (full turn) nor at most 340 (the sheet)");
  odd.mechanics = Mechanics{.closed_degrees = 90, .opened_degrees = 90};
  EXPECT_EQ(refusal({odd}),
            "location a: closed_degrees 90 must be at least 0 and below opened_degrees 90");
}

TEST(Layout, APlaceWithoutMechanicsHasTheDefaultAndAValveInNoPlaceToo) {
  auto master = place("left-master", 1, 10);
  master.mechanics = Mechanics{.closed_degrees = 0, .opened_degrees = 360};
  const auto layout =
      *Layout::make({master, place("section-01", 2, 11)}, Mechanics{.opened_degrees = 45});
  EXPECT_EQ(layout.mechanics_of_serial(10), (Mechanics{0, 360}));
  EXPECT_EQ(layout.mechanics_of_serial(11), (Mechanics{0, 45}));
  EXPECT_EQ(layout.mechanics_of_serial(99), (Mechanics{0, 45}));
  const auto unknown = *Layout::make({place("section-01", 1, 11)});
  EXPECT_EQ(unknown.mechanics_of_serial(11), std::nullopt);
}

TEST(Layout, AssigningASerialReplacesTheOneThatSatThere) {
  auto layout = boom();
  const auto assigned = layout.assign("section-01", 21, false);
  ASSERT_TRUE(assigned) << assigned.error().reason;
  EXPECT_EQ(assigned->displaced, 11u);
  EXPECT_EQ(assigned->moved_from, std::nullopt);
  EXPECT_EQ(layout.find("section-01")->serial, 21u);
  EXPECT_EQ(layout.find_serial(11), nullptr);
}

TEST(Layout, ASerialAtAnotherPlaceMovesOnlyWhenAsked) {
  auto layout = boom();
  const auto refused = layout.assign("section-03", 12, false);
  ASSERT_FALSE(refused);
  EXPECT_EQ(refused.error().reason,
            "serial TJV000012 sits at section-02; unassign it there first, or move it");
  EXPECT_EQ(layout, boom());
  const auto moved = layout.assign("section-03", 12, true);
  ASSERT_TRUE(moved);
  EXPECT_EQ(moved->moved_from, "section-02");
  EXPECT_EQ(moved->displaced, std::nullopt);
  EXPECT_EQ(layout.find("section-02")->serial, std::nullopt);
  EXPECT_EQ(layout.find("section-03")->serial, 12u);
}

TEST(Layout, AssigningTheSerialThatSitsThereChangesNothing) {
  auto layout = boom();
  const auto same = layout.assign("section-01", 11, false);
  ASSERT_TRUE(same);
  EXPECT_FALSE(same->changed);
  EXPECT_EQ(layout, boom());
}

TEST(Layout, AnUnknownLocationIsRefusedByName) {
  auto layout = boom();
  EXPECT_EQ(layout.assign("section-09", 21, false).error().reason,
            "location 'section-09' is not in this gateway's layout");
  EXPECT_EQ(layout.unassign("section-09").error().reason,
            "location 'section-09' is not in this gateway's layout");
}

TEST(Layout, UnassigningEmptiesThePlaceAndSaysWhoLeft) {
  auto layout = boom();
  EXPECT_EQ(*layout.unassign("section-02"), 12u);
  EXPECT_EQ(*layout.unassign("section-02"), std::nullopt);
  EXPECT_EQ(layout.find("section-02")->serial, std::nullopt);
}

}  // namespace
}  // namespace teejet::layout
