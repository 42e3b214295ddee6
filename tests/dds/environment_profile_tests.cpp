// A profiles file the environment names (FASTRTPS_DEFAULT_PROFILES_FILE) that Fast DDS cannot
// load stops every program before it joins the domain: Fast DDS itself would only log it and run
// on its defaults (every interface, multicast, no DDS-Security). Run inside a private network
// namespace, each program as a user starts it.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "support/subprocess.hpp"
#include "support/test_domain.hpp"

namespace teejet::dds {
namespace {

using namespace std::chrono_literals;
using teejet::testing::Finished;
using teejet::testing::Subprocess;
using teejet::testing::test_domain;

// `program` started with FASTRTPS_DEFAULT_PROFILES_FILE=`file`, to its end.
Finished run_with_profiles_file(const std::string& file, std::vector<std::string> program) {
  std::vector<std::string> argv = {"/usr/bin/env", "FASTRTPS_DEFAULT_PROFILES_FILE=" + file};
  argv.insert(argv.end(), program.begin(), program.end());
  Subprocess process(argv);
  return process.wait(30s);
}

struct BrokenFile {
  std::string path;
  std::string says;  // what the refusal says about it
};

std::vector<BrokenFile> broken_files() {
  const std::string scratch = ::testing::TempDir() + "environment-profiles";
  std::filesystem::create_directories(scratch + "/a-directory");
  std::ofstream(scratch + "/garbage.xml") << "<profiles><participant";
  return {
      {scratch + "/missing.xml", "names '" + scratch + "/missing.xml', which does not exist"},
      {scratch + "/garbage.xml",
       "Fast DDS cannot load the profiles of "
       "FASTRTPS_DEFAULT_PROFILES_FILE ('" +
           scratch + "/garbage.xml'"},
      {"/dev/null", "names '/dev/null', which is not a regular file"},
      {scratch + "/a-directory",
       "names '" + scratch + "/a-directory', which is not a regular file"},
  };
}

constexpr const char* kDefaults =
    "the program would run on Fast DDS's defaults (every interface, multicast, no DDS-Security)";

TEST(EnvironmentProfile, ValvectlRefusesAFileFastDdsCannotLoad) {
  for (const auto& broken : broken_files()) {
    const auto ended = run_with_profiles_file(
        broken.path,
        {VALVECTL_PATH, "--domain", std::to_string(test_domain()), "--timeout", "2", "list"});
    EXPECT_EQ(ended.exit_code, 1) << broken.path << ": " << ended.err;
    EXPECT_NE(ended.err.find(broken.says), std::string::npos) << ended.err;
    EXPECT_NE(ended.err.find(kDefaults), std::string::npos) << ended.err;
  }
}

TEST(EnvironmentProfile, TheGatewayRefusesAFileFastDdsCannotLoad) {
  for (const auto& broken : broken_files()) {
    const auto ended = run_with_profiles_file(
        broken.path,
        {TEEJET_GATEWAY_PATH, "--can", "sim:2", "--domain", std::to_string(test_domain())});
    EXPECT_EQ(ended.exit_code, 1) << broken.path << ": " << ended.out << ended.err;
    const std::string log = ended.out + ended.err;
    EXPECT_NE(log.find(broken.says), std::string::npos) << log;
    EXPECT_EQ(log.find("in DDS domain"), std::string::npos) << "it started: " << log;
  }
}

// The file tests/netns/isolated gives every test loads: the programs start on it, and say so.
TEST(EnvironmentProfile, TheGatewaySaysWhichProfileItRunsAndThatSecurityIsOff) {
  const char* file = std::getenv("FASTRTPS_DEFAULT_PROFILES_FILE");
  if (file == nullptr) GTEST_SKIP() << "runs under tests/netns/isolated, which sets it";
  Subprocess gateway(
      {TEEJET_GATEWAY_PATH, "--can", "sim:2", "--domain", std::to_string(test_domain())});
  ASSERT_TRUE(gateway.wait_for_stdout("in DDS domain", 30s)) << gateway.out() << gateway.err();
  EXPECT_NE(gateway.out().find(std::string("; profile ") + file +
                               " (FASTRTPS_DEFAULT_PROFILES_FILE); DDS-Security off"),
            std::string::npos)
      << gateway.out();
}

}  // namespace
}  // namespace teejet::dds
