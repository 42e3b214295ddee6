#pragma once

// Command-line rules every program of the project keeps (CLI11): an empty value is an error, and
// a bad command line exits with the program's documented usage status, never CLI11's own codes.

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdlib>
#include <optional>
#include <sstream>
#include <string>

namespace teejet::command_line {

// CLI11 turns an empty value into 0 or "" without a word: `--domain ""` would join domain 0,
// `--to ""` move a valve to 0 degrees. Applies to `app` and every subcommand it has so far.
inline void refuse_empty_values(CLI::App& app) {
  const CLI::Validator not_empty(
      [](std::string& value) { return value.empty() ? std::string("the value is empty") : ""; }, "",
      "NOT_EMPTY");
  for (CLI::Option* option : app.get_options([](CLI::Option*) { return true; })) {
    if (option->get_items_expected_min() > 0) option->check(not_empty);
  }
  for (CLI::App* subcommand : app.get_subcommands([](CLI::App*) { return true; })) {
    refuse_empty_values(*subcommand);
  }
}

// A number from `min` to `max`, both finite. CLI::Range lets "nan" through (every comparison
// with NaN is false) and CLI::NonNegativeNumber "inf" and 1e300: a rate of NaN replayed a file at
// once, a duration of 1e300 overflowed the deadline and ended a recording at its start.
inline CLI::Validator finite_range(double min, double max) {
  std::ostringstream range;
  range << min << " to " << max;
  return CLI::Validator(
      [min, max, range = range.str()](std::string& value) -> std::string {
        char* end = nullptr;
        const double number = std::strtod(value.c_str(), &end);
        if (value.empty() || end == nullptr || *end != '\0' || !std::isfinite(number) ||
            number < min || number > max) {
          return value + " is not a number from " + range;
        }
        return "";
      },
      "NUMBER " + range.str(), "FINITE_RANGE");
}

// Parses the command line. Nothing when the program goes on; otherwise the status to exit with:
// 0 after --help or --version, `usage_status` after any other parse error (CLI11's codes, 105,
// 109, ..., are not part of any program's interface). CLI11 has printed the message.
inline std::optional<int> parse(CLI::App& app, int argc, char** argv, int usage_status) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    return app.exit(error) == 0 ? 0 : usage_status;
  }
  return std::nullopt;
}

}  // namespace teejet::command_line
