// gateway::parse_config, the gateway's YAML configuration (docs/gateway.md).
//
// Input: the text of a configuration file, any bytes.
//
// Properties: parse_config returns a configuration or an error, never throws (an escaping
// exception aborts here and libFuzzer reports it); an error names the file; a configuration it
// returns holds only values inside the documented ranges.

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <string>
#include <variant>

#include "fuzz_input.hpp"
#include "teejet/codec/codec.hpp"
#include "teejet/dds/participant.hpp"
#include "teejet/gateway/config.hpp"

namespace {

using namespace teejet;
using namespace std::chrono_literals;

constexpr auto kSource = "fuzz.yaml";

void check_limits(const layout::Mechanics& limits, const std::string& where) {
  FUZZ_CHECK(limits.closed_degrees >= 0 && limits.closed_degrees < limits.opened_degrees, where);
  FUZZ_CHECK(limits.opened_degrees <= 340 || limits.opened_degrees == 360, where);
}

void check_duration(Duration value, const std::string& key) {
  FUZZ_CHECK(value > Duration{0} && value <= 3600s,
             key + " = " + std::to_string(value.count()) + " ns");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fuzz::Input input(data, size);
  const std::string text(input.rest());
  const auto config = gateway::parse_config(text, kSource, gateway::GatewayConfig{});
  if (!config) {
    FUZZ_CHECK(config.error().reason.starts_with(kSource), config.error().reason);
    return 0;
  }
  FUZZ_CHECK(config->domain >= 0 && config->domain <= teejet::dds::kMaxDomain, "domain");
  FUZZ_CHECK(config->receive_coalesce >= 0us && config->receive_coalesce <= 10'000us,
             "receive_coalesce_us");
  FUZZ_CHECK(config->receive_coalesce_above <= 10'000, "receive_coalesce_above_fps");
  const auto& bridge = config->bridge;
  check_duration(bridge.offline_after, "gateway.offline_after_s");
  check_duration(bridge.reply_timeout, "commands.reply_timeout_s");
  check_duration(bridge.move_margin, "commands.move_margin_s");
  FUZZ_CHECK(bridge.completion_tolerance_degrees >= 0 && bridge.completion_tolerance_degrees <= 45,
             "commands.completion_tolerance_deg");
  FUZZ_CHECK(bridge.assumed_dps >= 1 && bridge.assumed_dps <= 359, "commands.assumed_dps");
  const auto& layout = bridge.layout;
  if (layout.default_mechanics()) check_limits(*layout.default_mechanics(), "layout.default");
  for (const auto& location : layout.locations()) {
    FUZZ_CHECK(layout::check_name(location.name).ok(), "layout name " + location.name);
    FUZZ_CHECK(location.order >= 1 && location.order <= layout::kMaxOrder, "layout order");
    FUZZ_CHECK(!location.serial || *location.serial <= 0xFFFFFF, "layout serial");
    if (location.mechanics) check_limits(*location.mechanics, "layout." + location.name);
  }
  // Every poll entry is a request the valve understands, at most once each.
  FUZZ_CHECK(bridge.poll.size() <= 9, "poll");
  for (const auto& request : bridge.poll) {
    FUZZ_CHECK(!codec::is_run_command(request), "a run command in the poll schedule");
    FUZZ_CHECK(codec::encode(codec::kFirstValveAddress, request).ok(),
               std::string(codec::message_name(request)));
  }
  FUZZ_CHECK(config->sim_first_serial <= 0xFFFFFF, "simulator.first_serial");
  FUZZ_CHECK(config->sim_degrees_per_second >= 1 && config->sim_degrees_per_second <= 359,
             "simulator.dps");
  FUZZ_CHECK(config->sim_closed_degrees >= 0 && config->sim_closed_degrees <= 359.9,
             "simulator.closed_deg");
  FUZZ_CHECK(config->sim_opened_degrees >= 0 && config->sim_opened_degrees <= 360,
             "simulator.opened_deg");
  for (const auto& error : config->sim_errors) {
    FUZZ_CHECK(error.serial <= 0xFFFFFF, "simulator.errors serial");
    FUZZ_CHECK(sim::validate(error.error).ok(), "simulator.errors accepted an invalid error");
  }
  return 0;
}
