// valvectl's command line: what each subcommand becomes, and every invalid value refused with
// exit status 64 before anything is sent.

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "cli.hpp"
#include "exit_codes.hpp"

namespace teejet::valvectl {
namespace {

using namespace std::chrono_literals;

ParseOutcome parse(std::vector<std::string> args) {
  args.insert(args.begin(), "valvectl");
  std::vector<const char*> argv;
  for (const auto& arg : args) argv.push_back(arg.c_str());
  return parse_command_line(static_cast<int>(argv.size()), argv.data());
}

// The command of a successful parse.
CommandRequest command_of(std::vector<std::string> args) {
  const auto outcome = parse(std::move(args));
  EXPECT_TRUE(outcome.invocation.has_value()) << outcome.err;
  if (!outcome.invocation) return {};
  EXPECT_EQ(outcome.invocation->subcommand, Subcommand::kCommand);
  return outcome.invocation->command;
}

// The error message of a refused parse, which must exit 64 and send nothing.
std::string usage_error(std::vector<std::string> args) {
  const auto outcome = parse(std::move(args));
  EXPECT_FALSE(outcome.invocation.has_value());
  EXPECT_EQ(outcome.exit_code, kExitUsage);
  return outcome.err;
}

TEST(ValvectlCommandLine, MoveTakesASerialWithOrWithoutPrefixAndDefaultsToFullSpeedOpening) {
  const auto prefixed = command_of({"move", "TJV123456", "--to", "45"});
  const auto plain = command_of({"move", "123456", "--to", "45"});
  ASSERT_EQ(prefixed.serials, std::vector<std::uint32_t>{123456});
  EXPECT_EQ(plain.serials, prefixed.serials);
  EXPECT_EQ(prefixed.subcommand, "move");
  EXPECT_EQ(prefixed.command.kind(), COMMAND_TARGET_DEGREES);
  EXPECT_FLOAT_EQ(prefixed.command.degrees(), 45.0f);
  EXPECT_EQ(prefixed.command.speed_percent(), 100);
  EXPECT_EQ(prefixed.command.direction(), DIRECTION_OPEN);
  EXPECT_FALSE(prefixed.wait);
  EXPECT_EQ(prefixed.wait_timeout, 60s);
}

TEST(ValvectlCommandLine, MoveTakesSpeedDirectionAndWait) {
  const auto request = command_of({"move", "tjv000007", "--to", "359.9", "--speed", "30",
                                   "--direction", "shortest", "--wait", "--wait-timeout", "90"});
  EXPECT_EQ(request.serials, std::vector<std::uint32_t>{7});
  EXPECT_FLOAT_EQ(request.command.degrees(), 359.9f);
  EXPECT_EQ(request.command.speed_percent(), 30);
  EXPECT_EQ(request.command.direction(), DIRECTION_SHORTEST);
  EXPECT_TRUE(request.wait);
  EXPECT_EQ(request.wait_timeout, 90s);
}

TEST(ValvectlCommandLine, GlobalOptionsGoBeforeOrAfterTheSubcommand) {
  for (const auto& args : std::vector<std::vector<std::string>>{
           {"--domain", "7", "--json", "--timeout", "2.5", "list", "--wait-for", "3"},
           {"list", "--wait-for", "3", "--domain", "7", "--json", "--timeout", "2.5"}}) {
    const auto outcome = parse(args);
    ASSERT_TRUE(outcome.invocation) << outcome.err;
    EXPECT_EQ(outcome.invocation->subcommand, Subcommand::kList);
    EXPECT_EQ(outcome.invocation->global.domain, 7);
    EXPECT_TRUE(outcome.invocation->global.json);
    EXPECT_EQ(outcome.invocation->global.timeout, 2500ms);
    EXPECT_EQ(outcome.invocation->list.wait_for_online, 3u);
  }
}

TEST(ValvectlCommandLine, DefaultsAreDomainZeroAndFiveSeconds) {
  const auto outcome = parse({"list"});
  ASSERT_TRUE(outcome.invocation);
  EXPECT_EQ(outcome.invocation->global.domain, 0);
  EXPECT_EQ(outcome.invocation->global.timeout, 5s);
  EXPECT_FALSE(outcome.invocation->global.json);
  EXPECT_TRUE(outcome.invocation->global.profile_file.empty());
}

TEST(ValvectlCommandLine, WatchTakesIntervalAndDuration) {
  const auto outcome = parse({"watch", "--interval", "200", "--duration", "1.5"});
  ASSERT_TRUE(outcome.invocation) << outcome.err;
  EXPECT_EQ(outcome.invocation->subcommand, Subcommand::kWatch);
  EXPECT_EQ(outcome.invocation->watch.interval, 200ms);
  EXPECT_EQ(outcome.invocation->watch.duration, 1500ms);
  const auto forever = parse({"watch"});
  ASSERT_TRUE(forever.invocation);
  EXPECT_EQ(forever.invocation->watch.interval, 1000ms);
  EXPECT_FALSE(forever.invocation->watch.duration);
}

TEST(ValvectlCommandLine, StopTakesOneSerialOrAll) {
  const auto one = command_of({"stop", "42"});
  EXPECT_EQ(one.command.kind(), COMMAND_STOP);
  EXPECT_EQ(one.serials, std::vector<std::uint32_t>{42});
  EXPECT_FALSE(one.every_online_valve);
  const auto all = command_of({"stop", "--all"});
  EXPECT_TRUE(all.every_online_valve);
  EXPECT_TRUE(all.serials.empty());
  EXPECT_NE(usage_error({"stop"}).find("SERIAL or --all"), std::string::npos);
  EXPECT_NE(usage_error({"stop", "42", "--all"}).find("SERIAL or --all"), std::string::npos);
}

TEST(ValvectlCommandLine, ManualNeedsSpeedAndOpenOrClose) {
  const auto manual = command_of({"manual", "5", "--speed", "40", "--direction", "close"});
  EXPECT_EQ(manual.command.kind(), COMMAND_MANUAL);
  EXPECT_EQ(manual.command.speed_percent(), 40);
  EXPECT_EQ(manual.command.direction(), DIRECTION_CLOSE);
  usage_error({"manual", "5", "--direction", "open"});
  usage_error({"manual", "5", "--speed", "40"});
  EXPECT_NE(usage_error({"manual", "5", "--speed", "40", "--direction", "shortest"})
                .find("open or close"),
            std::string::npos);
}

TEST(ValvectlCommandLine, JogRunsForMillisecondsAndWaitsLongEnough) {
  const auto jog = command_of({"jog", "5", "--ms", "65535", "--direction", "close", "--wait"});
  EXPECT_EQ(jog.command.kind(), COMMAND_MILLISECONDS_TO_RUN);
  EXPECT_EQ(jog.command.milliseconds(), 65535);
  EXPECT_EQ(jog.command.speed_percent(), 100);
  EXPECT_EQ(jog.command.direction(), DIRECTION_CLOSE);
  EXPECT_EQ(jog.wait_timeout, 60s + 65535ms);  // the default backstop covers the run itself
  EXPECT_EQ(command_of({"jog", "5", "--ms", "100", "--wait-timeout", "3"}).wait_timeout, 3s);
  EXPECT_NE(usage_error({"jog", "5", "--ms", "65536"}).find("0 to 65535"), std::string::npos);
  usage_error({"jog", "5", "--ms", "-1"});
}

TEST(ValvectlCommandLine, ClearErrorsAndBaud) {
  EXPECT_EQ(command_of({"clear-errors", "TJV000009"}).command.kind(), COMMAND_CLEAR_ERRORS);
  EXPECT_EQ(command_of({"baud", "9", "--request"}).command.kind(), COMMAND_REQUEST_BAUD_RATE);
  const auto set = command_of({"baud", "9", "--set", "500000"});
  EXPECT_EQ(set.command.kind(), COMMAND_SET_BAUD_RATE);
  EXPECT_EQ(set.command.bit_rate(), 500000u);
  EXPECT_NE(usage_error({"baud", "9", "--set", "125000"}).find("neither 250000 nor 500000"),
            std::string::npos);
  usage_error({"baud", "9"});
  usage_error({"baud", "9", "--request", "--set", "250000"});
}

TEST(ValvectlCommandLine, RequestNamesWhatAndAResendPeriod) {
  const auto request = command_of({"request", "3", "voltage", "--every", "10"});
  EXPECT_EQ(request.command.kind(), COMMAND_REQUEST);
  EXPECT_EQ(request.command.telemetry(), TELEMETRY_VOLTAGE);
  EXPECT_EQ(request.command.resend_tenths(), 10);
  const std::vector<std::pair<std::string, Telemetry>> words = {
      {"version", TELEMETRY_VERSION},          {"position", TELEMETRY_POSITION},
      {"temperature", TELEMETRY_TEMPERATURE},  {"voltage", TELEMETRY_VOLTAGE},
      {"current", TELEMETRY_CURRENT},          {"dps", TELEMETRY_DEGREES_PER_SECOND},
      {"speed", TELEMETRY_SPEED_DIRECTION},    {"run-time", TELEMETRY_RUN_TIME},
      {"cycle-counts", TELEMETRY_CYCLE_COUNTS}};
  for (const auto& [word, telemetry] : words) {
    EXPECT_EQ(command_of({"request", "3", word}).command.telemetry(), telemetry) << word;
  }
  EXPECT_NE(usage_error({"request", "3", "pressure"}).find("run-time"), std::string::npos);
  EXPECT_NE(usage_error({"request", "3", "version", "--every", "5"}).find("once"),
            std::string::npos);
  EXPECT_NE(usage_error({"request", "3", "position", "--every", "256"}).find("0 to 255"),
            std::string::npos);
}

TEST(ValvectlCommandLine, OutOfRangeValuesAreRefusedWithTheRange) {
  EXPECT_NE(usage_error({"move", "1", "--to", "360"}).find("0 to 359.9"), std::string::npos);
  EXPECT_NE(usage_error({"move", "1", "--to", "359.96"}).find("0 to 359.9"), std::string::npos);
  EXPECT_NE(usage_error({"move", "1", "--to", "-0.5"}).find("0 to 359.9"), std::string::npos);
  EXPECT_NE(usage_error({"move", "1", "--to", "nan"}).find("0 to 359.9"), std::string::npos);
  EXPECT_NE(usage_error({"move", "1", "--to", "10", "--speed", "101"}).find("0 to 100"),
            std::string::npos);
  EXPECT_NE(usage_error({"move", "1", "--to", "10", "--direction", "up"}).find("shortest"),
            std::string::npos);
  usage_error({"move", "1"});  // --to is required
  usage_error({"move", "1", "--to", "ten"});
  usage_error({"--timeout", "0", "list"});
  usage_error({"--domain", "300", "list"});
}

TEST(ValvectlCommandLine, BadSerialsAreRefused) {
  EXPECT_NE(usage_error({"move", "TJVabc", "--to", "1"}).find("invalid SERIAL"), std::string::npos);
  EXPECT_NE(usage_error({"move", "16777216", "--to", "1"}).find("24 bits"), std::string::npos);
  usage_error({"clear-errors", "TJ123"});
}

TEST(ValvectlCommandLine, ErrorsNameTheProgramAndPointAtHelp) {
  const std::string error = usage_error({"move", "1", "--to", "400"});
  EXPECT_EQ(error.rfind("valvectl: ", 0), 0u) << error;
  EXPECT_NE(error.find("--help"), std::string::npos);
  usage_error({});  // a subcommand is required
  usage_error({"frobnicate"});
}

TEST(ValvectlCommandLine, HelpExitsZeroOnStandardOutput) {
  const auto help = parse({"--help"});
  EXPECT_FALSE(help.invocation);
  EXPECT_EQ(help.exit_code, kExitOk);
  EXPECT_NE(help.out.find("move"), std::string::npos);
  const auto move_help = parse({"move", "--help"});
  EXPECT_EQ(move_help.exit_code, kExitOk);
  EXPECT_NE(move_help.out.find("--direction"), std::string::npos);
}

}  // namespace
}  // namespace teejet::valvectl
