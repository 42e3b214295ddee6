// The YAML reading rules every configuration file of the project follows.

#include <gtest/gtest.h>

#include "teejet/yaml/reader.hpp"

namespace teejet::yaml {
namespace {

// Reads `key` of a one-entry mapping with `read`, returning the error text or "".
template <class Read>
std::string refusal(const std::string& text, Read read) {
  const auto result =
      parse<int>("test.yaml", text, [&](const Reader& reader, const YAML::Node& root) {
        reader.expect_mapping(root, "the file");
        read(reader, root["key"]);
        return 0;
      });
  return result ? "" : result.error().reason;
}

TEST(YamlReader, ErrorsNameTheFileTheLineAndTheKey) {
  EXPECT_EQ(refusal("other: 1\nkey: fast\n",
                    [](const Reader& r, const YAML::Node& n) { (void)r.number(n, "key", 0, 9); }),
            "test.yaml:2: key: 'fast' is not a number");
}

TEST(YamlReader, KeysGivenTwiceAreRefusedNotSilentlyTakenFirst) {
  EXPECT_EQ(refusal("key: 1\nkey: 2\n", [](const Reader&, const YAML::Node&) {}),
            "test.yaml:2: the file: 'key' is given twice");
}

TEST(YamlReader, UnknownKeysAreRefusedNamingTheKnownOnes) {
  const auto result =
      parse<int>("test.yaml", "a: 1\nb: 2\n", [](const Reader& r, const YAML::Node& n) {
        r.expect_keys(n, "section", {"a", "c"});
        return 0;
      });
  ASSERT_FALSE(result);
  EXPECT_EQ(result.error().reason, "test.yaml:2: section: unknown key 'b' (a, c)");
}

TEST(YamlReader, NumbersMustBeFiniteAndInRange) {
  const auto number = [](const Reader& r, const YAML::Node& n) { (void)r.number(n, "key", -5, 5); };
  EXPECT_EQ(refusal("key: .nan\n", number), "test.yaml:1: key: '.nan' is not a number");
  EXPECT_EQ(refusal("key: .inf\n", number), "test.yaml:1: key: '.inf' is not a number");
  EXPECT_EQ(refusal("key: 1e300\n", number), "test.yaml:1: key: 1e300 is outside -5 to 5");
  EXPECT_EQ(refusal("key: -5.5\n", number), "test.yaml:1: key: -5.5 is outside -5 to 5");
  EXPECT_EQ(refusal("key: 5\n", number), "");
  EXPECT_EQ(refusal("key: +2.5\n", number), "");
}

TEST(YamlReader, IntegersMustBeWhole) {
  const auto integer = [](const Reader& r, const YAML::Node& n) {
    (void)r.integer(n, "key", 0, 232);
  };
  EXPECT_EQ(refusal("key: -1\n", integer),
            "test.yaml:1: key: -1 is not a whole number from 0 to 232");
  EXPECT_EQ(refusal("key: 1.5\n", integer),
            "test.yaml:1: key: 1.5 is not a whole number from 0 to 232");
  EXPECT_EQ(refusal("key: 232\n", integer), "");
}

TEST(YamlReader, SecondsArePositiveAndBounded) {
  const auto seconds = [](const Reader& r, const YAML::Node& n) {
    (void)r.seconds(n, "key", 3600);
  };
  EXPECT_NE(refusal("key: 0\n", seconds), "");
  EXPECT_NE(refusal("key: -1\n", seconds), "");
  EXPECT_EQ(refusal("key: 1e30\n", seconds),
            "test.yaml:1: key: 1e30 s is outside the allowed range: more than 0, at most 3600 s");
  EXPECT_EQ(refusal("key: 0.5\n", seconds), "");
}

// Found by fuzz_gateway_config: 1e-10 passed "more than 0" and became a Duration of 0 ns, a
// reply timeout or offline time of zero.
TEST(YamlReader, SecondsShorterThanOneNanosecondAreRefused) {
  const auto seconds = [](const Reader& r, const YAML::Node& n) {
    (void)r.seconds(n, "key", 3600);
  };
  EXPECT_EQ(refusal("key: 1e-10\n", seconds), "test.yaml:1: key: 1e-10 s is shorter than 1 ns");
  EXPECT_EQ(refusal("key: 4.9e-324\n", seconds),
            "test.yaml:1: key: 4.9e-324 s is shorter than 1 ns");
  EXPECT_EQ(refusal("key: 1e-9\n", seconds), "");
}

TEST(YamlReader, WordsAndFlagsNameWhatIsAllowed) {
  EXPECT_EQ(
      refusal("key: maybe\n", [](const Reader& r, const YAML::Node& n) { (void)r.flag(n, "key"); }),
      "test.yaml:1: key: 'maybe' is neither true nor false");
  EXPECT_EQ(refusal("key: halt\n",
                    [](const Reader& r, const YAML::Node& n) {
                      (void)r.word(n, "key", {"stop", "ignore"});
                    }),
            "test.yaml:1: key: 'halt' is not 'stop' or 'ignore'");
}

TEST(YamlReader, SyntaxErrorsNameTheFile) {
  const auto result =
      parse<int>("test.yaml", "key: [1\n", [](const Reader&, const YAML::Node&) { return 0; });
  ASSERT_FALSE(result);
  EXPECT_EQ(result.error().reason.rfind("test.yaml: ", 0), 0u) << result.error().reason;
}

TEST(YamlReader, AMissingFileSaysWhichOne) {
  const auto text = read_file("/nonexistent/teejet.yaml");
  ASSERT_FALSE(text);
  EXPECT_EQ(text.error().reason, "cannot read config file '/nonexistent/teejet.yaml'");
}

}  // namespace
}  // namespace teejet::yaml
