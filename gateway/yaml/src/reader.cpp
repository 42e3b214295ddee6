#include "teejet/yaml/reader.hpp"

#include <array>
#include <charconv>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

namespace teejet::yaml {

std::string number_text(double value) {
  std::array<char, 32> text{};
  const auto [end, ec] = std::to_chars(text.data(), text.data() + text.size(), value);
  return ec == std::errc() ? std::string(text.data(), end) : std::string("?");
}

void Reader::fail(const YAML::Node& node, std::string_view key, std::string_view what) const {
  std::string text = origin_;
  if (node.Mark().line >= 0) {
    text += ':';  // appended: GCC 12 reports a false -Wrestrict on ":" + std::to_string(...)
    text += std::to_string(node.Mark().line + 1);
  }
  text += ": ";
  if (!key.empty()) {
    text += key;
    text += ": ";
  }
  text += what;
  throw Failure{std::move(text)};
}

void Reader::check_duplicates(const YAML::Node& map, std::string_view section) const {
  std::set<std::string> seen;
  for (const auto& entry : map) {
    const std::string key = scalar(entry.first, section);
    if (!seen.insert(key).second) fail(entry.first, section, "'" + key + "' is given twice");
  }
}

void Reader::expect_mapping(const YAML::Node& map, std::string_view section) const {
  if (!map.IsMap()) fail(map, section, "expected a mapping");
  check_duplicates(map, section);
}

void Reader::expect_list(const YAML::Node& list, std::string_view key,
                         std::string_view of_what) const {
  if (list.IsSequence()) return;
  std::string what = "expected a list of ";
  what += of_what;
  fail(list, key, what);
}

void Reader::expect_keys(const YAML::Node& map, std::string_view section,
                         std::initializer_list<std::string_view> allowed) const {
  expect_keys(map, section, std::span(allowed.begin(), allowed.size()));
}

void Reader::expect_keys(const YAML::Node& map, std::string_view section,
                         std::span<const std::string_view> allowed) const {
  expect_mapping(map, section);
  for (const auto& entry : map) {
    const std::string key = entry.first.Scalar();
    bool known = false;
    for (const auto candidate : allowed) known = known || candidate == key;
    if (!known) {
      std::string words;
      for (const auto candidate : allowed) {
        words += words.empty() ? "" : ", ";
        words += candidate;
      }
      fail(entry.first, section, "unknown key '" + key + "' (" + words + ")");
    }
  }
}

std::string Reader::scalar(const YAML::Node& node, std::string_view key) const {
  if (!node.IsScalar()) fail(node, key, "expected a single value");
  return node.Scalar();
}

bool Reader::flag(const YAML::Node& node, std::string_view key) const {
  const std::string text = scalar(node, key);
  if (text == "true") return true;
  if (text == "false") return false;
  fail(node, key, "'" + text + "' is neither true nor false");
}

std::string Reader::word(const YAML::Node& node, std::string_view key,
                         std::initializer_list<std::string_view> words) const {
  const std::string text = scalar(node, key);
  std::string allowed;
  for (const auto candidate : words) {
    if (candidate == text) return text;
    allowed += allowed.empty() ? "'" : " or '";
    allowed += candidate;
    allowed += "'";
  }
  fail(node, key, "'" + text + "' is not " + allowed);
}

double Reader::finite(const YAML::Node& node, std::string_view key) const {
  const std::string text = scalar(node, key);
  double value = 0;
  const char* begin = text.data();
  const char* end = begin + text.size();
  if (begin != end && *begin == '+') ++begin;
  const auto [stop, ec] = std::from_chars(begin, end, value);
  // .inf, .nan (YAML) and inf, nan (from_chars) are all refused here.
  if (text.empty() || ec != std::errc() || stop != end || !std::isfinite(value)) {
    fail(node, key, "'" + text + "' is not a number");
  }
  return value;
}

double Reader::number(const YAML::Node& node, std::string_view key, double min, double max) const {
  const double value = finite(node, key);
  if (value < min || value > max) {
    fail(node, key,
         scalar(node, key) + " is outside " + number_text(min) + " to " + number_text(max));
  }
  return value;
}

long long Reader::integer(const YAML::Node& node, std::string_view key, long long min,
                          long long max) const {
  const double value = finite(node, key);
  if (value != std::floor(value) || value < static_cast<double>(min) ||
      value > static_cast<double>(max)) {
    fail(node, key,
         scalar(node, key) + " is not a whole number from " + std::to_string(min) + " to " +
             std::to_string(max));
  }
  return static_cast<long long>(value);
}

double Reader::seconds(const YAML::Node& node, std::string_view key, double max) const {
  const double value = finite(node, key);
  if (!(value > 0) || value > max) {
    fail(node, key,
         scalar(node, key) + " s is outside the allowed range: more than 0, at most " +
             number_text(max) + " s");
  }
  // Durations count nanoseconds: anything shorter would silently become a timeout of zero.
  if (value < 1e-9) fail(node, key, scalar(node, key) + " s is shorter than 1 ns");
  return value;
}

Result<std::string> read_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) return Error{ErrorCode::kInvalidValue, "cannot read config file '" + path + "'"};
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) return Error{ErrorCode::kInvalidValue, "error reading config file '" + path + "'"};
  return text.str();
}

}  // namespace teejet::yaml
