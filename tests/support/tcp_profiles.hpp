#pragma once

// The project's TCP profiles (config/fastdds-wan-tcp-*.xml) for tests on one host: the bench's
// copy names 127.0.0.1 as the vehicle's address, the gateway's is used as it is (it listens on
// every address of the test's private network namespace).

#include <gtest/gtest.h>

#include <fstream>
#include <regex>
#include <sstream>
#include <string>

namespace teejet::testing {

// Writes the bench profile of `config_dir`, aimed at 127.0.0.1, to `path`; a failed expectation
// when the file no longer holds the address it replaces.
inline void write_local_tcp_bench_profile(const std::string& config_dir, const std::string& path) {
  std::ifstream file(config_dir + "/fastdds-wan-tcp-bench.xml");
  std::stringstream text;
  text << file.rdbuf();
  const std::string bench = text.str();
  EXPECT_NE(bench.find("192.0.2.2"), std::string::npos) << "the bench profile's address moved";
  std::ofstream(path) << std::regex_replace(bench, std::regex("192\\.0\\.2\\.2"), "127.0.0.1");
}

inline std::string tcp_gateway_profile(const std::string& config_dir) {
  return config_dir + "/fastdds-wan-tcp-gateway.xml";
}

}  // namespace teejet::testing
