// gateway_latency: the latency and footprint figures of teejet-gateway (docs/performance.md,
// "Gateway latency and footprint"). bench/run-gateway-bench.sh runs every mode inside
// user-mode-linux and prints the table.
//
// Every mode that creates a DDS participant must run inside tests/uml/uml-run or
// tests/netns/isolated: DDS traffic never leaves the host.
//
//   gateway    command->frame and frame->sample through a running teejet-gateway: this process
//              plays the valve (CAN socket) and the ECU (DDS participant)   gateway_mode.cpp
//   baseline   bare Fast DDS publish->receive of the same types and QoS, to a child process
//   receive    the baseline's receiving child (started by `baseline`)       baseline_mode.cpp
//   resources  CPU and memory of running processes over a window, and the bus frame rate
//                                                                           resources_mode.cpp
//
// Results are printed as `KIND key=value ...` lines. Nothing throws: whatever is refused is
// reported on stderr and the exit status is 1 (2 for a bad command line).

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cstdio>

#include "modes.hpp"
#include "options.hpp"

int main(int argc, char** argv) {
  using teejet::bench::Options;
  CLI::App app{
      "Latency and footprint of teejet-gateway (docs/performance.md). Modes that use DDS "
      "must run in tests/uml/uml-run or tests/netns/isolated.",
      "gateway_latency"};
  app.require_subcommand(1);
  Options options;

  const auto add_dds = [&](CLI::App* mode) {
    mode->add_option("--domain", options.domain, "DDS domain id");
    mode->add_option("--profile", options.profile, "Fast DDS XML profile file")
        ->check(CLI::ExistingFile);
  };
  const auto add_series = [&](CLI::App* mode) {
    mode->add_option("--label", options.label, "name of this run in the output");
    mode->add_option("--samples", options.samples, "measured samples per series");
    mode->add_option("--warmup", options.warmup, "samples sent first and not measured");
    mode->add_option("--pace-min-ms", options.pace_min_ms, "shortest gap between samples");
    mode->add_option("--pace-max-ms", options.pace_max_ms, "longest gap between samples");
    mode->add_option("--raw-dir", options.raw_dir, "write every latency (ns) to files here");
    mode->add_option("--serial", options.serial, "serial of the bench valve");
    mode->add_option("--load-valves", options.load_valves,
                     "run a gateway in this process with this many simulated valves on a "
                     "virtual bus (the host, without CAN): the load, and for `gateway` the "
                     "gateway measured")
        ->check(CLI::Range(1, 31));
    mode->add_option("--load-config", options.load_config,
                     "that gateway's YAML configuration (e.g. bench/full-poll.yaml)")
        ->check(CLI::ExistingFile);
  };

  auto* gateway = app.add_subcommand(
      "gateway", "command->frame and frame->sample through a running teejet-gateway");
  add_dds(gateway);
  add_series(gateway);
  gateway->add_option("--can", options.can, "CAN interface the gateway is on");
  gateway->add_option("--address", options.address,
                      "CAN address of the bench valve (0xD8..0xF7); free of simulated valves");

  auto* baseline = app.add_subcommand(
      "baseline", "bare Fast DDS publish->receive of ValvePosition and ValveCommand");
  add_dds(baseline);
  add_series(baseline);

  auto* receive = app.add_subcommand("receive", "the baseline's receiving process (internal)");
  add_dds(receive);
  receive->add_option("--topic", options.topic)
      ->required()
      ->check(CLI::IsMember({"position", "command"}));
  receive->add_option("--count", options.count)->required();
  receive->add_option("--timeout-s", options.timeout_s);
  receive->add_option("--serial", options.serial, "take samples of this serial only");

  auto* resources = app.add_subcommand(
      "resources", "CPU and memory of processes over a window, and the bus frame rate");
  add_dds(resources);
  resources->add_option("--label", options.label, "name of this run in the output");
  resources->add_option("--pid", options.pids, "process to measure (repeatable)")->required();
  resources->add_option("--window-s", options.window_s, "measured window");
  resources->add_option("--settle-s", options.settle_s, "wait before the window");
  resources->add_option("--interface", options.interface, "count the frames on this interface");
  resources->add_flag("--subscribe", options.subscribe,
                      "read every gateway topic meanwhile, as an ECU would");
  resources
      ->add_option("--commands-per-second", options.commands_per_second,
                   "with --subscribe: move valves TJV000001..--valves in turn at this rate")
      ->check(CLI::Range(0.0, 1000.0));
  resources->add_option("--valves", options.moved_valves, "how many valves the ECU moves")
      ->check(CLI::Range(1, 999999));
  resources
      ->add_option("--rss-every-s", options.rss_every_s,
                   "sample VmRSS, open fds, threads and CPU this often in the window")
      ->check(CLI::Range(0.0, 3600.0));
  resources
      ->add_option("--compare-s", options.compare_s,
                   "compare the first and last this many seconds of the samples (flat?)")
      ->check(CLI::Range(0.0, 86400.0));
  resources
      ->add_option("--drain-s", options.drain_s,
                   "after the window, wait this long at most for every command's final state")
      ->check(CLI::Range(0.0, 600.0));
  resources->add_flag("--check", options.check,
                      "exit 1 when a command got no final state or the footprint grew");

  CLI11_PARSE(app, argc, argv);
  // The CAN layer logs opening and closing at info; the output here is the results only.
  spdlog::set_level(spdlog::level::warn);
  if (options.pace_min_ms < 0 || options.pace_max_ms < options.pace_min_ms || options.samples < 1 ||
      options.warmup < 0) {
    std::fprintf(stderr, "gateway_latency: bad --samples/--warmup/--pace-*-ms\n");
    return 2;
  }
  if (*gateway) return teejet::bench::run_gateway(options);
  if (*baseline) return teejet::bench::run_baseline(options);
  if (*receive) return teejet::bench::run_receive(options);
  return teejet::bench::run_resources(options);
}
