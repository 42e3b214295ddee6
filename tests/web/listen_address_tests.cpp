// --listen: where the dashboard's server may listen.

#include <gtest/gtest.h>

#include "listen_address.hpp"

namespace teejet::web {
namespace {

std::string accepted(std::string_view text) {
  const auto listen = parse_listen(text);
  EXPECT_TRUE(listen) << text;
  return listen ? *listen : "";
}

std::string refused(std::string_view text) {
  const auto listen = parse_listen(text);
  EXPECT_FALSE(listen) << text;
  return listen ? "" : listen.error().reason;
}

TEST(WebListen, LiteralAddressesAndPortsAreAccepted) {
  EXPECT_EQ(accepted(kDefaultListen), "127.0.0.1:8080");
  EXPECT_EQ(accepted("0.0.0.0:80"), "0.0.0.0:80");
  EXPECT_EQ(accepted("[::1]:65535"), "[::1]:65535");
}

TEST(WebListen, EverythingElseIsRefusedWithTheReason) {
  EXPECT_EQ(refused("8080"), "--listen '8080': expected ADDR:PORT, e.g. 127.0.0.1:8080");
  EXPECT_EQ(refused("127.0.0.1:0"),
            "--listen '127.0.0.1:0': the port must be a number from 1 to 65535");
  EXPECT_EQ(refused("127.0.0.1:65536"),
            "--listen '127.0.0.1:65536': the port must be a number from 1 to 65535");
  EXPECT_EQ(refused("127.0.0.1:80x"),
            "--listen '127.0.0.1:80x': the port must be a number from 1 to 65535");
  EXPECT_EQ(refused(":8080"),
            "--listen ':8080': '' is not an IPv4 address (IPv6 in brackets: [::1]:8080)");
  EXPECT_EQ(refused("localhost:8080"),
            "--listen 'localhost:8080': 'localhost' is not an IPv4 address (IPv6 in brackets: "
            "[::1]:8080)");
  EXPECT_EQ(refused("[::g]:8080"), "--listen '[::g]:8080': '[::g]' is not an IPv6 address");
}

}  // namespace
}  // namespace teejet::web
