// The command token against guessing: exact counts of what is checked, on a clock the test
// moves, and the token file's checks.

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>
#include <filesystem>
#include <fstream>

#include "token_file.hpp"
#include "token_guard.hpp"

namespace teejet::web {
namespace {

using namespace std::chrono_literals;
using Verdict = TokenGuard::Verdict;

struct FakeClock {
  std::chrono::steady_clock::time_point now{std::chrono::hours(1)};
  TokenGuard::Clock clock() {
    return [this] { return now; };
  }
};

TEST(WebToken, TokensAreEqualOnlyWhenEveryByteAndTheLengthAre) {
  EXPECT_TRUE(tokens_equal("s3cret", "s3cret"));
  EXPECT_FALSE(tokens_equal("s3cre", "s3cret"));
  EXPECT_FALSE(tokens_equal("s3crett", "s3cret"));
  EXPECT_FALSE(tokens_equal("s3cres", "s3cret"));
  EXPECT_FALSE(tokens_equal("s3crets3cret", "s3cret"));
  EXPECT_FALSE(tokens_equal("", "s3cret"));
}

TEST(WebToken, TheOperatorWithOneTypoIsNotHurt) {
  FakeClock time;
  TokenGuard guard("s3cret", time.clock());
  const auto typo = guard.check(1, "s3crte");
  EXPECT_EQ(typo.verdict, Verdict::kWrong);
  EXPECT_EQ(typo.log, "wrong token");
  EXPECT_EQ(TokenGuard::reason(typo), "missing or wrong \"token\"");
  EXPECT_EQ(guard.check(1, "s3cret").verdict, Verdict::kAccepted);
  // The count starts again after a right token: four more typos are still checked.
  for (int i = 0; i < 4; ++i) EXPECT_EQ(guard.check(1, "x").verdict, Verdict::kWrong);
  EXPECT_EQ(guard.check(1, "s3cret").verdict, Verdict::kAccepted);
}

TEST(WebToken, AfterFiveWrongTokensAConnectionIsLockedOutForADoublingTime) {
  FakeClock time;
  TokenGuard guard("s3cret", time.clock());
  for (int i = 1; i <= 4; ++i) {
    const auto answer = guard.check(1, "guess");
    EXPECT_EQ(answer.verdict, Verdict::kWrong);
    EXPECT_EQ(answer.log, i == 1 ? "wrong token" : "");
  }
  const auto fifth = guard.check(1, "guess");
  EXPECT_EQ(fifth.verdict, Verdict::kWrong);
  EXPECT_EQ(fifth.wait, 1000ms);
  EXPECT_EQ(fifth.log, "5 wrong tokens on one connection: its tokens are not checked for 1 s");
  time.now += 999ms;
  const auto locked = guard.check(1, "s3cret");  // even the right one: it is not checked
  EXPECT_EQ(locked.verdict, Verdict::kLockedOut);
  EXPECT_EQ(locked.wait, 1ms);
  EXPECT_EQ(locked.log, "");
  EXPECT_EQ(TokenGuard::reason(locked),
            "too many wrong tokens on this connection: not checked for 1 s");
  EXPECT_EQ(guard.check(2, "s3cret").verdict, Verdict::kAccepted);  // another connection
  time.now += 1ms;
  const auto sixth = guard.check(1, "guess");
  EXPECT_EQ(sixth.verdict, Verdict::kWrong);
  EXPECT_EQ(sixth.wait, 2000ms);
  std::vector<long> lockouts;
  for (int i = 0; i < 8; ++i) {
    time.now += guard.check(1, "s3cret").wait;  // locked: its wait is what is left
    const auto wrong = guard.check(1, "guess");
    lockouts.push_back(static_cast<long>(wrong.wait.count()));
  }
  EXPECT_EQ(lockouts, (std::vector<long>{4000, 8000, 16000, 32000, 60000, 60000, 60000, 60000}));
  guard.forget(1);
  EXPECT_EQ(guard.check(1, "s3cret").verdict, Verdict::kAccepted);
}

TEST(WebToken, OneConnectionGuessingEveryMillisecondForTenSecondsIsChecked8Times) {
  FakeClock time;
  TokenGuard guard("s3cret", time.clock());
  int checked = 0;
  for (int attempt = 0; attempt < 10000; ++attempt, time.now += 1ms) {
    if (guard.check(7, "guess").verdict == Verdict::kWrong) ++checked;
  }
  // 5 at once, then one after each lockout of 1, 2 and 4 s; the next is at 15 s.
  EXPECT_EQ(checked, 8);
}

TEST(WebToken, OverAllConnectionsTenWrongTokensASecondAreChecked) {
  FakeClock time;
  TokenGuard guard("s3cret", time.clock());
  int checked = 0;
  for (std::uint64_t connection = 0; connection < 100; ++connection) {
    if (guard.check(connection, "guess").verdict == Verdict::kWrong) ++checked;
  }
  EXPECT_EQ(checked, 10);
  time.now += 400ms;
  const auto busy = guard.check(500, "s3cret");
  EXPECT_EQ(busy.verdict, Verdict::kServerBusy);
  EXPECT_EQ(busy.wait, 600ms);
  EXPECT_EQ(busy.log, "");  // logged once, at the first refusal of this second
  EXPECT_EQ(TokenGuard::reason(busy), "too many wrong tokens on this server: not checked for 1 s");
  time.now += 600ms;
  EXPECT_EQ(guard.check(500, "s3cret").verdict, Verdict::kAccepted);
}

TEST(WebToken, TheFirstRefusalOfABusySecondIsLogged) {
  FakeClock time;
  TokenGuard guard("s3cret", time.clock());
  std::vector<std::string> logs;
  for (std::uint64_t connection = 0; connection < 12; ++connection) {
    const auto answer = guard.check(connection, "guess");
    if (!answer.log.empty()) logs.push_back(answer.log);
  }
  EXPECT_EQ(logs.size(), 11u);  // "wrong token" of each new connection, then the busy second
  EXPECT_EQ(logs.back(),
            "10 wrong tokens in a second over all connections: no token is checked for 1 s");
}

class WebTokenFile : public ::testing::Test {
 protected:
  std::filesystem::path write(const std::string& content, mode_t mode) {
    std::ofstream(path_, std::ios::binary | std::ios::trunc) << content;
    ::chmod(path_.c_str(), mode);
    return path_;
  }
  std::string refusal(const std::filesystem::path& path) {
    const auto token = read_token_file(path);
    EXPECT_FALSE(token) << path;
    return token ? "" : token.error().reason;
  }
  void TearDown() override { std::filesystem::remove(path_); }
  std::filesystem::path path_ = std::filesystem::temp_directory_path() /
                                ("teejet-web-token-" + std::to_string(::getpid()) + "-" +
                                 ::testing::UnitTest::GetInstance()->current_test_info()->name());
};

TEST_F(WebTokenFile, TheTokenIsTheFileWithoutItsTrailingNewline) {
  EXPECT_EQ(*read_token_file(write("s3cret\n", 0600)), "s3cret");
  EXPECT_EQ(*read_token_file(write("s3cret\r\n", 0400)), "s3cret");
  EXPECT_EQ(*read_token_file(write("s3cret", 0600)), "s3cret");
}

TEST_F(WebTokenFile, AFileOthersMayReadOrAnEmptyOneIsRefused) {
  EXPECT_EQ(refusal(write("s3cret\n", 0644)), "--token-file " + path_.string() +
                                                  ": group or others may access it (mode "
                                                  "0644): chmod 600 " +
                                                  path_.string());
  EXPECT_EQ(refusal(write("s3cret\n", 0620)), "--token-file " + path_.string() +
                                                  ": group or others may access it (mode "
                                                  "0620): chmod 600 " +
                                                  path_.string());
  EXPECT_EQ(refusal(write("\n", 0600)), "--token-file " + path_.string() + ": the token is empty");
  EXPECT_EQ(
      refusal(std::filesystem::temp_directory_path()),
      "--token-file " + std::filesystem::temp_directory_path().string() + ": not a regular file");
  EXPECT_EQ(refusal(path_.string() + ".missing"),
            "--token-file " + path_.string() + ".missing: cannot read it");
}

}  // namespace
}  // namespace teejet::web
