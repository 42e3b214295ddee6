// Where teejet-web finds its page: --www, the build tree, the install tree; a clear error else.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "web_assets.hpp"

namespace teejet::web {
namespace {

namespace fs = std::filesystem;

class WebAssets : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ =
        fs::temp_directory_path() /
        ("teejet-web-assets-" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
         "-" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(root_);
    fs::create_directories(root_ / "bin");
  }
  void TearDown() override { fs::remove_all(root_); }

  void page_in(const fs::path& dir) {
    fs::create_directories(dir);
    std::ofstream(dir / "index.html") << "<!doctype html>";
  }

  fs::path root_;
};

TEST_F(WebAssets, TheBuildTreeCopyNextToTheExecutableComesFirst) {
  page_in(root_ / "bin" / "www");
  page_in(root_ / "share" / "teejet-web" / "www");
  const auto found = find_www("", root_ / "bin");
  ASSERT_TRUE(found) << found.error().reason;
  EXPECT_EQ(*found, root_ / "bin" / "www");
}

TEST_F(WebAssets, AnInstallTreeIsFoundRelativeToItsBinDirectory) {
  page_in(root_ / "share" / "teejet-web" / "www");
  const auto found = find_www("", root_ / "bin");
  ASSERT_TRUE(found) << found.error().reason;
  EXPECT_EQ(*found, root_ / "share" / "teejet-web" / "www");
}

TEST_F(WebAssets, AnExplicitDirectoryIsTheOnlyOneTried) {
  page_in(root_ / "bin" / "www");
  page_in(root_ / "mine");
  const auto found = find_www((root_ / "mine").string(), root_ / "bin");
  ASSERT_TRUE(found) << found.error().reason;
  EXPECT_EQ(*found, root_ / "mine");
  const auto missing = find_www((root_ / "nowhere").string(), root_ / "bin");
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.error().reason,
            "no dashboard page (index.html) in " + (root_ / "nowhere").string());
}

TEST_F(WebAssets, NoPageAnywhereNamesEveryPathTried) {
  fs::create_directories(root_ / "bin" / "www");  // a directory without index.html is no page
  const auto missing = find_www("", root_ / "bin");
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.error().reason, "no dashboard page (index.html) in " +
                                        (root_ / "bin" / "www").string() + ", " +
                                        (root_ / "share" / "teejet-web" / "www").string() +
                                        " (give its directory with --www DIR)");
}

}  // namespace
}  // namespace teejet::web
