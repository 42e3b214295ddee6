// A layout as YAML: every mistake refused with file, line and key; what the gateway writes reads
// back the same; a save replaces the file whole or not at all.

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>

#include "support/scratch_dir.hpp"
#include "teejet/layout/layout_file.hpp"

namespace teejet::layout {
namespace {

const char* const kBoom = R"(default: {closed_deg: 0, opened_deg: 90}
locations:
  - {name: section-02, order: 3, role: section, serial: TJV000102}
  - name: left-master
    order: 1
    role: master
    serial: TJV000101
    opened_deg: 360
  - {name: section-01, order: 2, serial: 103}
  - {name: section-03, order: 4, serial: null}
)";

std::string refusal(const std::string& text) {
  const auto layout = parse_layout("boom.yaml", text);
  return layout ? "" : layout.error().reason;
}

TEST(LayoutFile, ReadsEveryFieldOfEveryPlace) {
  const auto layout = parse_layout("boom.yaml", kBoom);
  ASSERT_TRUE(layout) << layout.error().reason;
  ASSERT_EQ(layout->locations().size(), 4u);
  const auto& master = layout->locations()[0];
  EXPECT_EQ(master.name, "left-master");
  EXPECT_EQ(master.order, 1u);
  EXPECT_EQ(master.role, Role::kMaster);
  EXPECT_EQ(master.serial, 101u);
  EXPECT_EQ(master.mechanics, (Mechanics{0, 360}));
  EXPECT_EQ(layout->locations()[1].role, Role::kSection);  // the default role
  EXPECT_EQ(layout->locations()[1].serial, 103u);
  EXPECT_EQ(layout->locations()[1].mechanics, std::nullopt);
  EXPECT_EQ(layout->locations()[3].serial, std::nullopt);
  EXPECT_EQ(layout->default_mechanics(), (Mechanics{0, 90}));
}

TEST(LayoutFile, RefusesEveryMistakeWithTheLineAndTheKey) {
  EXPECT_EQ(refusal("locations:\n  - {name: a, order: 1}\n  - {name: a, order: 2}\n"),
            "boom.yaml:3: layout.a.name: is given twice");
  EXPECT_EQ(refusal("locations:\n  - {name: a, order: 1}\n  - {name: b, order: 1}\n"),
            "boom.yaml:3: layout.b.order: 1 is a's order too");
  EXPECT_EQ(refusal("locations:\n  - {name: a, order: 1, serial: TJV000007}\n"
                    "  - {name: b, order: 2,\n     serial: TJV000007}\n"),
            "boom.yaml:4: layout.b.serial: TJV000007 sits at a already");
  EXPECT_EQ(refusal("locations:\n  - {name: Boom-1, order: 1}\n"),
            "boom.yaml:2: layout.locations[0].name: 'Boom-1' is not lower-case letters, digits "
            "and '-' starting with a letter");
  EXPECT_EQ(refusal("locations:\n  - {name: a, order: 1}\n  - {order: 2}\n"),
            "boom.yaml:3: layout.locations[1].name: is missing");
  EXPECT_EQ(refusal("locations:\n  - {name: a}\n"), "boom.yaml:2: layout.a.order: is missing");
  EXPECT_EQ(refusal("locations:\n  - {name: a, order: 0}\n"),
            "boom.yaml:2: layout.a.order: 0 is not a whole number from 1 to 9999");
  EXPECT_EQ(refusal("locations:\n  - {name: a, order: 1, role: boom}\n"),
            "boom.yaml:2: layout.a.role: 'boom' is not one of section, master, rate, other");
  EXPECT_EQ(refusal("locations:\n  - {name: a, order: 1, serial: XYZ1}\n"),
            "boom.yaml:2: layout.a.serial: serial 'XYZ1' is not TJV followed by digits, nor "
            "digits alone");
  EXPECT_EQ(refusal("locations:\n  - {name: a, order: 1,\n     opened_deg: 350}\n"),
            "boom.yaml:3: layout.a.opened_deg: 350 is neither 360 (full turn) "
            "nor at most 340 (the sheet)");
  EXPECT_EQ(refusal("locations:\n  - {name: a, order: 1, closed_deg: 95}\n"),
            "boom.yaml:2: layout.a.closed_deg: 95 must be at least 0 and below "
            "opened_degrees 90");
  EXPECT_EQ(refusal("default: {opened_deg: 400}\n"),
            "boom.yaml:1: layout.default.opened_deg: 400 is outside 0 to 360");
  EXPECT_EQ(refusal("locations:\n  - {name: a, order: 1, colour: red}\n"),
            "boom.yaml:2: layout.locations[0]: unknown key 'colour' (name, order, role, serial, "
            "closed_deg, opened_deg)");
  EXPECT_EQ(refusal("locations: {name: a}\n"),
            "boom.yaml:1: layout.locations: expected a list "
            "of locations");
}

TEST(LayoutFile, APlaceWithOneMechanicsKeyTakesTheOtherFromTheDefault) {
  const auto layout = parse_layout("boom.yaml",
                                   "default: {closed_deg: 10, opened_deg: 80}\n"
                                   "locations:\n  - {name: a, order: 1, opened_deg: 70}\n");
  ASSERT_TRUE(layout) << layout.error().reason;
  EXPECT_EQ(layout->locations()[0].mechanics, (Mechanics{10, 70}));
}

TEST(LayoutFile, WhatTheGatewayWritesReadsBackTheSame) {
  auto layout = *parse_layout("boom.yaml", kBoom);
  ASSERT_TRUE(layout.assign("section-03", 0xFFFFFF, false));
  auto odd = *Layout::make({Location{.name = "null", .order = 1},
                            Location{.name = "true", .order = 9999, .role = Role::kOther}});
  for (const auto& original : {layout, odd, Layout{}}) {
    const auto text = to_yaml(original);
    const auto again = parse_layout("written.yaml", text);
    ASSERT_TRUE(again) << again.error().reason << "\n" << text;
    EXPECT_EQ(*again, original) << text;
  }
}

TEST(LayoutFile, ASaveReplacesTheFileAndKeepsItsPermissions) {
  testing::ScratchDir dir;
  const auto path = (dir / "layout.yaml").string();
  auto layout = *parse_layout("boom.yaml", kBoom);
  ASSERT_TRUE(save_layout_file(path, layout));
  struct stat written {};
  ASSERT_EQ(::stat(path.c_str(), &written), 0);
  EXPECT_EQ(written.st_mode & 0777, 0644u);
  ASSERT_EQ(::chmod(path.c_str(), 0600), 0);
  ASSERT_TRUE(layout.unassign("left-master"));
  ASSERT_TRUE(save_layout_file(path, layout));
  EXPECT_EQ(*load_layout_file(path), layout);
  ASSERT_EQ(::stat(path.c_str(), &written), 0);
  EXPECT_EQ(written.st_mode & 0777, 0600u);
  // Nothing beside it: the temporary file became the file.
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()),
                          std::filesystem::directory_iterator{}),
            1);
}

TEST(LayoutFile, ASaveThatCannotBeWrittenSaysWhyAndLeavesNothing) {
  testing::ScratchDir dir;
  const auto missing = (dir / "missing" / "layout.yaml").string();
  const auto saved = save_layout_file(missing, Layout{});
  ASSERT_FALSE(saved);
  EXPECT_EQ(saved.error().code, ErrorCode::kSystem);
  EXPECT_NE(saved.error().reason.find("cannot create a file beside '" + missing + "'"),
            std::string::npos)
      << saved.error().reason;
  // Written whole, then refused at the rename (a directory is in the way): the written file goes.
  std::filesystem::create_directory(dir / "layout.yaml");
  const auto blocked = save_layout_file((dir / "layout.yaml").string(), Layout{});
  ASSERT_FALSE(blocked);
  EXPECT_NE(blocked.error().reason.find("cannot replace"), std::string::npos)
      << blocked.error().reason;
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()),
                          std::filesystem::directory_iterator{}),
            1);
}

}  // namespace
}  // namespace teejet::layout
