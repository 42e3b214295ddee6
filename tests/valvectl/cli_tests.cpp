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
  EXPECT_FALSE(request.progress);
}

TEST(ValvectlCommandLine, ProgressIsForAWaitingMoveOrJog) {
  EXPECT_TRUE(command_of({"move", "7", "--to", "10", "--wait", "--progress"}).progress);
  EXPECT_TRUE(command_of({"jog", "7", "--ms", "100", "--wait", "--progress"}).progress);
  EXPECT_NE(usage_error({"move", "7", "--to", "10", "--progress"}).find("--wait"),
            std::string::npos);
  usage_error({"stop", "7", "--wait", "--progress"});
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

TEST(ValvectlCommandLine, WatchTakesIntervalDurationAndTitle) {
  const auto outcome = parse({"watch", "--interval", "200", "--duration", "1.5"});
  ASSERT_TRUE(outcome.invocation) << outcome.err;
  EXPECT_EQ(outcome.invocation->subcommand, Subcommand::kWatch);
  EXPECT_EQ(outcome.invocation->watch.interval, 200ms);
  EXPECT_EQ(outcome.invocation->watch.duration, 1500ms);
  const auto forever = parse({"watch"});
  ASSERT_TRUE(forever.invocation);
  EXPECT_EQ(forever.invocation->watch.interval, 1000ms);
  EXPECT_FALSE(forever.invocation->watch.duration);
  EXPECT_EQ(forever.invocation->watch.title, "");
  const auto titled = parse({"watch", "--title", "dashboard: http://127.0.0.1:8080/"});
  ASSERT_TRUE(titled.invocation);
  EXPECT_EQ(titled.invocation->watch.title, "dashboard: http://127.0.0.1:8080/");
}

TEST(ValvectlCommandLine, StopTakesOneSerialOrAll) {
  const auto one = command_of({"stop", "42"});
  EXPECT_EQ(one.command.kind(), COMMAND_STOP);
  EXPECT_EQ(one.serials, std::vector<std::uint32_t>{42});
  EXPECT_FALSE(one.every_online_valve);
  const auto all = command_of({"stop", "--all"});
  EXPECT_TRUE(all.every_online_valve);
  EXPECT_TRUE(all.serials.empty());
  EXPECT_NE(usage_error({"stop"}).find("VALVE or --all"), std::string::npos);
  EXPECT_NE(usage_error({"stop", "42", "--all"}).find("VALVE or --all"), std::string::npos);
}

// Moving every section of a boom is what a person does: move, stop, jog and clear-errors take
// --all, and --gateway narrows it to one gateway's bus.
TEST(ValvectlCommandLine, MoveJogAndClearErrorsTakeAllAndAGateway) {
  const auto boom = command_of({"move", "--all", "--gateway", "rig-2", "--to", "20"});
  EXPECT_EQ(boom.command.kind(), COMMAND_TARGET_DEGREES);
  EXPECT_TRUE(boom.every_online_valve);
  EXPECT_EQ(boom.only_gateway, "rig-2");
  EXPECT_TRUE(boom.serials.empty());
  EXPECT_TRUE(command_of({"jog", "--all", "--ms", "100"}).every_online_valve);
  EXPECT_TRUE(command_of({"clear-errors", "--all"}).every_online_valve);
  EXPECT_EQ(command_of({"stop", "--all", "--gateway", "rig-1"}).only_gateway, "rig-1");
  EXPECT_NE(usage_error({"move", "--to", "20"}).find("move: give either a VALVE or --all"),
            std::string::npos);
  EXPECT_NE(usage_error({"move", "5", "--gateway", "rig-2", "--to", "20"})
                .find("move: --gateway selects valves for --all"),
            std::string::npos);
  // A manual drive runs until told otherwise: one valve at a time.
  EXPECT_NE(usage_error({"manual", "--all", "--speed", "40"}).find("VALVE is required"),
            std::string::npos);
}

TEST(ValvectlCommandLine, ManualNeedsSpeedAndOpenOrClose) {
  const auto manual = command_of({"manual", "5", "--speed", "40", "--direction", "close"});
  EXPECT_EQ(manual.command.kind(), COMMAND_MANUAL);
  EXPECT_EQ(manual.command.speed_percent(), 40);
  EXPECT_EQ(manual.command.direction(), DIRECTION_CLOSE);
  usage_error({"manual", "5", "--direction", "open"});
  usage_error({"manual", "5", "--speed", "40"});
  EXPECT_NE(usage_error({"manual", "5", "--speed", "40", "--direction", "shortest"})
                .find("--direction \"shortest\" is not one of close, open"),
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
      {"version", TELEMETRY_VERSION},
      {"position", TELEMETRY_POSITION},
      {"temperature", TELEMETRY_TEMPERATURE},
      {"voltage", TELEMETRY_VOLTAGE},
      {"current", TELEMETRY_CURRENT},
      {"dps", TELEMETRY_DEGREES_PER_SECOND},
      {"speed", TELEMETRY_SPEED_DIRECTION},
      {"run-time", TELEMETRY_RUN_TIME},
      {"cycle-counts", TELEMETRY_CYCLE_COUNTS},
      {"cycle_counts", TELEMETRY_CYCLE_COUNTS},
      {"run_time", TELEMETRY_RUN_TIME},
      {"degrees_per_second", TELEMETRY_DEGREES_PER_SECOND},
      {"speed_direction", TELEMETRY_SPEED_DIRECTION}};
  for (const auto& [word, telemetry] : words) {
    EXPECT_EQ(command_of({"request", "3", word}).command.telemetry(), telemetry) << word;
  }
  // The codec's names, as the help says them.
  EXPECT_NE(usage_error({"request", "3", "pressure"})
                .find("'pressure' is not one of version position temperature voltage current "
                      "degrees_per_second speed_direction run_time cycle_counts"),
            std::string::npos);
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
  EXPECT_NE(usage_error({"move", "TJVabc", "--to", "1"}).find("invalid VALVE 'TJVabc'"),
            std::string::npos);
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

// `move "" --to 10` exited 0 having sent nothing, and `--to ""` moved the valve to 0 degrees:
// CLI11 makes 0 of an empty value.
TEST(ValvectlCommandLine, EmptyValuesAreRefusedNamingTheOption) {
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases{
      {{"move", "", "--to", "10"}, "VALVE: the value is empty"},
      {{"stop", ""}, "VALVE: the value is empty"},
      {{"move", "1", "--to", ""}, "--to: the value is empty"},
      {{"move", "1", "--to", "10", "--speed", ""}, "--speed: the value is empty"},
      {{"move", "1", "--to", "10", "--direction", ""}, "--direction: the value is empty"},
      {{"move", "1", "--to", "10", "--wait", "--wait-timeout", ""}, "--wait-timeout: the value"},
      {{"manual", "1", "--speed", "", "--direction", "open"}, "--speed: the value is empty"},
      {{"jog", "1", "--ms", ""}, "--ms: the value is empty"},
      {{"request", "1", ""}, "WHAT: the value is empty"},
      {{"request", "1", "position", "--every", ""}, "--every: the value is empty"},
      {{"baud", "1", "--set", ""}, "--set: the value is empty"},
      {{"list", "--wait-for", ""}, "--wait-for: the value is empty"},
      {{"watch", "--interval", ""}, "--interval: the value is empty"},
      {{"watch", "--duration", ""}, "--duration: the value is empty"},
      {{"watch", "--title", ""}, "--title: the value is empty"},
      {{"--timeout", "", "list"}, "--timeout: the value is empty"},
      {{"--domain", "", "list"}, "--domain: the value is empty"},
      {{"--profile", "", "list"}, "--profile: File does not exist"},
  };
  for (const auto& [args, message] : cases) {
    const std::string error = usage_error(args);
    EXPECT_NE(error.find(message), std::string::npos) << error;
  }
}

// Each numeric option against the classes of bad values: empty, not a number, infinite, huge,
// negative, and C's other bases for the whole numbers. Every one exits 64 naming the option,
// with no invocation: nothing reaches DDS.
TEST(ValvectlCommandLine, EveryNumericOptionRefusesNanInfHugeAndNegative) {
  struct Case {
    std::vector<std::string> before;  // the arguments up to the option
    std::string option;
    std::vector<std::string> after;  // required arguments after it
    std::vector<std::string> bad;
  };
  const std::vector<std::string> whole_bad{
      "",     "nan", "inf", "-1", "1e10", "99999999999999999999", "-18446744073709551615",
      "0x10", "1.5", " 5"};
  const std::vector<std::string> real_bad{"", "nan", "inf", "-inf", "1e10", "1e400", "-1", "x"};
  const std::vector<Case> cases{
      {{"move", "1"}, "--to", {}, real_bad},
      {{"move", "1", "--to", "10"}, "--speed", {}, whole_bad},
      {{"move", "1", "--to", "10"}, "--wait-timeout", {}, real_bad},
      {{"manual", "1", "--direction", "open"}, "--speed", {}, whole_bad},
      {{"jog", "1"}, "--ms", {}, whole_bad},
      {{"jog", "1", "--ms", "10"}, "--speed", {}, whole_bad},
      {{"request", "1", "position"}, "--every", {}, whole_bad},
      {{"baud", "1"}, "--set", {}, whole_bad},
      {{"list"}, "--wait-for", {}, whole_bad},
      {{"watch"}, "--interval", {}, whole_bad},
      {{"watch"}, "--duration", {}, real_bad},
      {{"list"}, "--timeout", {}, real_bad},
      {{"list"}, "--domain", {}, whole_bad},
  };
  for (const auto& [before, option, after, bad] : cases) {
    for (const auto& value : bad) {
      auto args = before;
      args.push_back(option);
      args.push_back(value);
      args.insert(args.end(), after.begin(), after.end());
      const std::string error = usage_error(args);
      EXPECT_NE(error.find(option), std::string::npos) << option << " '" << value << "': " << error;
    }
  }
}

// `list --timeout 1e10` gave up after 150 ms: the deadline overflowed the steady clock.
TEST(ValvectlCommandLine, DurationsAreFromAMillisecondToAnHourOrADayForAWatch) {
  EXPECT_NE(usage_error({"list", "--timeout", "1e10"})
                .find("--timeout 1e+10 is not a number of seconds from 0.001 to 3600"),
            std::string::npos);
  EXPECT_NE(usage_error({"list", "--timeout", "3600.1"}).find("0.001 to 3600"), std::string::npos);
  EXPECT_NE(usage_error({"list", "--timeout", "0.0004"}).find("0.001 to 3600"), std::string::npos);
  EXPECT_EQ(parse({"list", "--timeout", "3600"}).invocation->global.timeout, 3600s);
  EXPECT_EQ(parse({"list", "--timeout", "0.001"}).invocation->global.timeout, 1ms);
  EXPECT_EQ(command_of({"stop", "1", "--wait", "--wait-timeout", "3600"}).wait_timeout, 3600s);
  usage_error({"stop", "1", "--wait", "--wait-timeout", "3601"});
  EXPECT_EQ(parse({"watch", "--duration", "86400"}).invocation->watch.duration, 86400s);
  EXPECT_NE(usage_error({"watch", "--duration", "86401"}).find("0.001 to 86400"),
            std::string::npos);
}

// CLI11 reads integers as C does; a person means decimal.
TEST(ValvectlCommandLine, LeadingZerosAreDecimal) {
  const auto jog = command_of({"jog", "1", "--ms", "0100", "--speed", "010"});
  EXPECT_EQ(jog.command.milliseconds(), 100);
  EXPECT_EQ(jog.command.speed_percent(), 10);
  EXPECT_EQ(command_of({"jog", "1", "--ms", "000"}).command.milliseconds(), 0);
  EXPECT_EQ(parse({"--domain", "010", "list"}).invocation->global.domain, 10);
}

TEST(ValvectlCommandLine, MoveToInfinityIsOutOfRange) {
  EXPECT_NE(usage_error({"move", "1", "--to", "inf"}).find("0 to 359.9"), std::string::npos);
}

// The documented usage status, not CLI11's internal codes (109, 114, ...).
TEST(ValvectlCommandLine, UnknownFlagsBadAndMissingValuesExit64) {
  EXPECT_NE(usage_error({"list", "--no-such-flag"}).find("--no-such-flag"), std::string::npos);
  EXPECT_NE(usage_error({"--domain", "seven", "list"}).find("--domain"), std::string::npos);
  EXPECT_NE(usage_error({"list", "--domain"}).find("--domain"), std::string::npos);
  EXPECT_NE(usage_error({"move", "1", "--to"}).find("--to"), std::string::npos);
  const auto version = parse({"--version"});
  EXPECT_EQ(version.exit_code, kExitOk);
  EXPECT_EQ(version.out.rfind("valvectl ", 0), 0u) << version.out;
}

}  // namespace
}  // namespace teejet::valvectl
