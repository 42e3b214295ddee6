// Who may open a page (Origin and the page limit) and the page's files as served from memory:
// the rules the transport asks, without a network.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <string_view>

#include "page_admission.hpp"
#include "page_files.hpp"

namespace teejet::web {
namespace {

const AllowedHosts kLoopback = allowed_hosts("127.0.0.1:8080", {}, {});
constexpr std::string_view kOwnPage = "http://127.0.0.1:8080";

TEST(WebPageAdmission, APageOfThisServerIsAdmittedUpToTheLimit) {
  EXPECT_EQ(refuse_page(kOwnPage, kLoopback, Scheme::kHttp, 0), std::nullopt);
  EXPECT_EQ(refuse_page("http://localhost:8080", kLoopback, Scheme::kHttp, 0), std::nullopt);
  EXPECT_EQ(refuse_page(kOwnPage, kLoopback, Scheme::kHttp, kMaxPages - 1), std::nullopt);
  EXPECT_EQ(refuse_page(kOwnPage, kLoopback, Scheme::kHttp, kMaxPages),
            (PageRefusal{503, "already 48 pages open"}));
}

TEST(WebPageAdmission, AClientWithoutOriginIsNotABrowserAndIsAdmitted) {
  EXPECT_EQ(refuse_page(std::nullopt, kLoopback, Scheme::kHttp, 0), std::nullopt);
}

TEST(WebPageAdmission, APageOfAnotherOriginIsRefused) {
  const PageRefusal refused{403, "a page of another origin may not open the dashboard's WebSocket"};
  EXPECT_EQ(refuse_page("http://example.com", kLoopback, Scheme::kHttp, 0), refused);
  EXPECT_EQ(refuse_page("https://127.0.0.1:8080", kLoopback, Scheme::kHttp, 0), refused);
  EXPECT_EQ(refuse_page("http://127.0.0.1:8081", kLoopback, Scheme::kHttp, 0), refused);
  EXPECT_EQ(refuse_page("", kLoopback, Scheme::kHttp, 0), refused);
}

TEST(WebPageAdmission, OnATlsServerOnlyAnHttpsPageOfThisServerIsAdmitted) {
  EXPECT_EQ(refuse_page("https://127.0.0.1:8080", kLoopback, Scheme::kHttps, 0), std::nullopt);
  EXPECT_EQ(refuse_page(kOwnPage, kLoopback, Scheme::kHttps, 0),
            (PageRefusal{403, "a page of another origin may not open the dashboard's WebSocket"}));
}

class WebPageFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    std::filesystem::create_directories(www / "sub");
    std::ofstream(www / "index.html") << "<html>";
    std::ofstream(www / "dashboard.js") << "let x;";
    std::ofstream(www / "sub" / "hidden.css") << "p{}";
    std::ofstream(dir / "secret.txt") << "secret";
  }
  void TearDown() override { std::filesystem::remove_all(dir); }

  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() /
      ("teejet-web-files-" +
       std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
  const std::filesystem::path www = dir / "www";
};

TEST_F(WebPageFiles, ServesTheFilesOfTheDirectoryWithTheirTypes) {
  const auto files = PageFiles::load(www);
  ASSERT_TRUE(files) << files.error().reason;
  const PageFile* index = files->find("/");
  ASSERT_NE(index, nullptr);
  EXPECT_EQ(index->body, "<html>");
  EXPECT_EQ(index->content_type, "text/html; charset=utf-8");
  ASSERT_NE(files->find("/index.html?reload=1"), nullptr);
  const PageFile* script = files->find("/dashboard.js");
  ASSERT_NE(script, nullptr);
  EXPECT_EQ(script->body, "let x;");
  EXPECT_EQ(script->content_type, "text/javascript; charset=utf-8");
}

TEST_F(WebPageFiles, NoOtherPathReachesAFile) {
  const auto files = PageFiles::load(www);
  ASSERT_TRUE(files) << files.error().reason;
  for (const char* target :
       {"/../secret.txt", "/..%2fsecret.txt", "/%2e%2e/secret.txt", "/sub/hidden.css", "/sub",
        "//index.html", "/./index.html", "/index.html/", "index.html", "/INDEX.HTML", ""}) {
    EXPECT_EQ(files->find(target), nullptr) << target;
  }
}

TEST(WebPageFilesLoad, AMissingDirectoryIsAnError) {
  const auto files = PageFiles::load("/nonexistent/teejet-web/www");
  ASSERT_FALSE(files);
  EXPECT_NE(files.error().reason.find("/nonexistent/teejet-web/www"), std::string::npos);
}

}  // namespace
}  // namespace teejet::web
