// Host and Origin: which names a request may give teejet-web, against DNS rebinding.

#include <gtest/gtest.h>

#include <map>
#include <string>
#include <string_view>

#include "request_guard.hpp"

namespace teejet::web {
namespace {

TEST(WebRequestGuard, ALoopbackServerAnswersItsAddressAndLocalhostOnItsPort) {
  const AllowedHosts allowed = allowed_hosts("127.0.0.1:8080", {"192.0.2.7"}, {});
  EXPECT_EQ(allowed.addresses, std::vector<std::string>{"127.0.0.1"});
  EXPECT_EQ(allowed.names, std::vector<std::string>{"localhost"});
  EXPECT_TRUE(host_allowed("127.0.0.1:8080", allowed));
  EXPECT_TRUE(host_allowed("localhost:8080", allowed));
  EXPECT_TRUE(host_allowed("LocalHost:8080", allowed));
  EXPECT_FALSE(host_allowed("127.0.0.1:8081", allowed));
  EXPECT_FALSE(host_allowed("127.0.0.1", allowed));  // port 80
  EXPECT_FALSE(host_allowed("192.0.2.7:8080", allowed));
  EXPECT_FALSE(host_allowed("attacker.example:8080", allowed));
  EXPECT_FALSE(host_allowed("127.0.0.1.attacker.example:8080", allowed));
  EXPECT_FALSE(host_allowed("localhost.:8080", allowed));
  EXPECT_FALSE(host_allowed("2130706433:8080", allowed));
  for (const char* malformed : {"", ":8080", "127.0.0.1:", "127.0.0.1:80x", "127.0.0.1:8080:1",
                                "[127.0.0.1]:8080", "[::1:8080"}) {
    EXPECT_FALSE(host_allowed(malformed, allowed)) << malformed;
  }
}

TEST(WebRequestGuard, AnIpv6ServerComparesAddressesNotSpellings) {
  const AllowedHosts allowed = allowed_hosts("[::1]:8080", {}, {});
  EXPECT_TRUE(host_allowed("[::1]:8080", allowed));
  EXPECT_TRUE(host_allowed("[0:0::1]:8080", allowed));
  EXPECT_TRUE(host_allowed("localhost:8080", allowed));
  EXPECT_FALSE(host_allowed("[::1]", allowed));
  EXPECT_FALSE(host_allowed("[::1]x:8080", allowed));
  EXPECT_FALSE(host_allowed("127.0.0.1:8080", allowed));
}

TEST(WebRequestGuard, ABenchNetworkAddressAllowsNoLocalhostButTheNamesGiven) {
  const AllowedHosts allowed = allowed_hosts("192.0.2.7:80", {}, {"Bench-PC"});
  EXPECT_TRUE(host_allowed("192.0.2.7", allowed));
  EXPECT_TRUE(host_allowed("192.0.2.7:80", allowed));
  EXPECT_TRUE(host_allowed("bench-pc", allowed));
  EXPECT_TRUE(host_allowed("BENCH-PC:80", allowed));
  EXPECT_FALSE(host_allowed("localhost", allowed));
  EXPECT_FALSE(host_allowed("bench-pc.attacker.example", allowed));
}

TEST(WebRequestGuard, EveryInterfaceMeansEveryLocalAddressAndLocalhost) {
  const AllowedHosts allowed =
      allowed_hosts("0.0.0.0:8080", {"127.0.0.1", "192.0.2.7", "fe80:0::1", "not an address"}, {});
  EXPECT_EQ(allowed.addresses, (std::vector<std::string>{"127.0.0.1", "192.0.2.7", "fe80::1"}));
  EXPECT_TRUE(host_allowed("192.0.2.7:8080", allowed));
  EXPECT_TRUE(host_allowed("[fe80::1]:8080", allowed));
  EXPECT_TRUE(host_allowed("localhost:8080", allowed));
  EXPECT_FALSE(host_allowed("0.0.0.0:8080", allowed));
  EXPECT_FALSE(host_allowed("198.51.100.1:8080", allowed));
  EXPECT_EQ(allowed_hosts("[::]:8080", {"::1"}, {}).addresses, std::vector<std::string>{"::1"});
}

TEST(WebRequestGuard, AnOriginMustBeAPageOfAnAllowedHost) {
  const AllowedHosts allowed = allowed_hosts("127.0.0.1:18090", {}, {"bench"});
  EXPECT_TRUE(origin_allowed("http://127.0.0.1:18090", allowed, Scheme::kHttp));
  EXPECT_TRUE(origin_allowed("http://localhost:18090", allowed, Scheme::kHttp));
  EXPECT_TRUE(origin_allowed("http://bench:18090", allowed, Scheme::kHttp));
  // DNS rebinding: the attacker's name, with its own Origin, on our port.
  EXPECT_FALSE(origin_allowed("http://attacker.example:18090", allowed, Scheme::kHttp));
  EXPECT_FALSE(origin_allowed("https://127.0.0.1:18090", allowed, Scheme::kHttp));
  EXPECT_FALSE(origin_allowed("http://127.0.0.1:18091", allowed, Scheme::kHttp));
  EXPECT_FALSE(origin_allowed("http://127.0.0.1:18090/", allowed, Scheme::kHttp));
  EXPECT_FALSE(origin_allowed("null", allowed, Scheme::kHttp));
  EXPECT_FALSE(origin_allowed("", allowed, Scheme::kHttp));
}

TEST(WebRequestGuard, ATlsServersOriginIsHttpsAndAnAllowedHost) {
  const AllowedHosts allowed = allowed_hosts("127.0.0.1:18090", {}, {"bench"});
  EXPECT_TRUE(origin_allowed("https://127.0.0.1:18090", allowed, Scheme::kHttps));
  EXPECT_TRUE(origin_allowed("https://bench:18090", allowed, Scheme::kHttps));
  // The same page over plain http is another origin: a downgraded or foreign page.
  EXPECT_FALSE(origin_allowed("http://127.0.0.1:18090", allowed, Scheme::kHttps));
  EXPECT_FALSE(origin_allowed("https://attacker.example:18090", allowed, Scheme::kHttps));
}

TEST(WebRequestGuard, AllowedHostNamesAreNamesWithoutPort) {
  EXPECT_EQ(*parse_allowed_host("Bench-PC.example"), "bench-pc.example");
  for (const char* bad : {"", "bench:8080", "192.0.2.7", ".bench", "bench.", "be nch", "*"}) {
    const auto parsed = parse_allowed_host(bad);
    ASSERT_FALSE(parsed) << bad;
    EXPECT_EQ(parsed.error().reason,
              "--allowed-host '" + std::string(bad) +
                  "': expected a host name like bench-pc or bench.example (no port, no address: "
                  "the addresses teejet-web listens on are allowed already)");
  }
}

TEST(WebRequestGuard, EveryAnswerForbidsFramingAndForeignScripts) {
  std::map<std::string_view, std::string_view> headers;
  for (const Header& header : kSecurityHeaders) headers[header.name] = header.value;
  EXPECT_EQ(headers["X-Frame-Options"], "DENY");
  EXPECT_EQ(headers["Content-Security-Policy"],
            "default-src 'self'; connect-src 'self'; frame-ancestors 'none'; base-uri 'none'; "
            "form-action 'none'; object-src 'none'");
}

TEST(WebRequestGuard, AForeignHostGetsA403WithTheHeadersAndTheWayOut) {
  EXPECT_EQ(forbidden_host_answer(),
            "HTTP/1.1 403 Forbidden\r\nX-Frame-Options: DENY\r\nContent-Security-Policy: "
            "default-src 'self'; connect-src 'self'; frame-ancestors 'none'; base-uri 'none'; "
            "form-action 'none'; object-src 'none'\r\nX-Content-Type-Options: nosniff\r\n"
            "Referrer-Policy: no-referrer\r\nContent-Type: text/plain; charset=utf-8\r\n"
            "Content-Length: 117\r\n"
            "Connection: close\r\n\r\nteejet-web does not serve this Host name: open it "
            "by the address it listens on, or start it with --allowed-host NAME\n");
}

}  // namespace
}  // namespace teejet::web
