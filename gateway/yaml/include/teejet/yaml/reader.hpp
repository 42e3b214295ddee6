#pragma once

// Reading a YAML configuration file so that every mistake is refused with the file, the line and
// the key: unknown keys, keys given twice (yaml-cpp would keep the first silently), wrong types,
// numbers that are not finite or outside their range. Shared by the gateway and valve-sim.

#include <yaml-cpp/yaml.h>

#include <initializer_list>
#include <span>
#include <string>
#include <string_view>
#include <utility>

#include "teejet/core/result.hpp"

namespace teejet::yaml {

// Thrown by Reader inside parse() only, which turns it into an Error.
struct Failure {
  std::string reason;
};

class Reader {
 public:
  explicit Reader(std::string origin) : origin_(std::move(origin)) {}

  // "origin:line: key: what".
  [[noreturn]] void fail(const YAML::Node& node, std::string_view key, std::string_view what) const;

  // A mapping whose keys are all in `allowed`, each at most once.
  void expect_keys(const YAML::Node& map, std::string_view section,
                   std::initializer_list<std::string_view> allowed) const;
  void expect_keys(const YAML::Node& map, std::string_view section,
                   std::span<const std::string_view> allowed) const;
  // A mapping with any keys, each at most once.
  void expect_mapping(const YAML::Node& map, std::string_view section) const;
  // A sequence; "expected a list of <of_what>" otherwise.
  void expect_list(const YAML::Node& list, std::string_view key, std::string_view of_what) const;

  std::string scalar(const YAML::Node& node, std::string_view key) const;
  bool flag(const YAML::Node& node, std::string_view key) const;  // true or false
  // One of `words`, named in the message otherwise.
  std::string word(const YAML::Node& node, std::string_view key,
                   std::initializer_list<std::string_view> words) const;
  // A finite number in [min, max].
  double number(const YAML::Node& node, std::string_view key, double min, double max) const;
  // A whole number in [min, max].
  long long integer(const YAML::Node& node, std::string_view key, long long min,
                    long long max) const;
  // Seconds greater than 0 and at most `max`; at least 1 ns, the resolution of a Duration.
  double seconds(const YAML::Node& node, std::string_view key, double max) const;

 private:
  double finite(const YAML::Node& node, std::string_view key) const;
  void check_duplicates(const YAML::Node& map, std::string_view section) const;

  std::string origin_;
};

// Parses `text`, named `origin` in every message, and hands the root to `read(reader, root)`.
// A Failure or a YAML syntax error comes back as an Error (ErrorCode::kInvalidValue).
template <class T, class Read>
Result<T> parse(const std::string& origin, const std::string& text, Read&& read) {
  const Reader reader(origin);
  try {
    return read(reader, YAML::Load(text));
  } catch (const Failure& failure) {
    return Error{ErrorCode::kInvalidValue, failure.reason};
  } catch (const YAML::Exception& error) {
    return Error{ErrorCode::kInvalidValue, origin + ": " + error.what()};
  }
}

// The whole file; "cannot read config file '<path>'" otherwise.
Result<std::string> read_file(const std::string& path);

// The shortest text that reads back as `value`: 0.1 -> "0.1", 1e300 -> "1e+300".
std::string number_text(double value);

}  // namespace teejet::yaml
