// What a sample of the generated types costs to build, and what the gateway spends on one frame
// from the bus before it reaches DDS (decode, directory, command tracking, sample). Issue 8:
// fastddsgen 2.3's -typeobject made every sample's constructor re-register every type object
// (~20 us); idl/patch_generated.cmake moved that to once per process.
#include <benchmark/benchmark.h>

#include "teejet/bridge/bridge.hpp"
#include "teejet/can/virtual_bus.hpp"
#include "teejet/valve.h"

namespace {

using namespace teejet;

void ConstructValvePosition(benchmark::State& state) {
  for (auto _ : state) {
    ValvePosition sample;
    benchmark::DoNotOptimize(sample);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(ConstructValvePosition);

void ConstructCommandStatus(benchmark::State& state) {
  for (auto _ : state) {
    CommandStatus sample;  // two bounded strings
    benchmark::DoNotOptimize(sample);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(ConstructCommandStatus);

// Counts what the bridge publishes; DDS writes are measured by bench/gateway_latency.
struct CountingSink final : bridge::Sink {
  std::uint64_t samples = 0;
  void presence(const ValvePresence&) override { ++samples; }
  void location(const ValveLocation&) override { ++samples; }
  void telemetry(const dds::TelemetrySample&) override { ++samples; }
  void error_cleared(std::uint32_t, ErrorKind) override {}
  void command_status(const CommandStatus&) override {}
  void layout_change_status(const LayoutChangeStatus&) override {}
  void gateway_status(const GatewayStatus&) override {}
};

// A Position frame of one of 32 online valves, through the bridge into a sample.
void BridgePositionFrame(benchmark::State& state) {
  can::VirtualBus bus("types-bench", {.filters = can::controller_side_filters()});
  (void)bus.open();
  CountingSink sink;
  bridge::Bridge bridge({}, bus, sink);
  for (std::uint8_t i = 0; i < 32; ++i) {
    const auto address = static_cast<std::uint8_t>(0xD8 + i);
    bridge.on_frame(
        {codec::encode(address, codec::FromValveMessage{codec::IAmHere{0, i + 1u}}).value(),
         Timestamp{}});
  }
  const can::TimedFrame position{
      codec::encode(0xE7, codec::FromValveMessage{codec::Position{123.4}}).value(), Timestamp{}};
  for (auto _ : state) bridge.on_frame(position);
  state.SetItemsProcessed(state.iterations());
  if (sink.samples < static_cast<std::uint64_t>(state.iterations())) {
    state.SkipWithError("frames were not published");
  }
}
BENCHMARK(BridgePositionFrame);

}  // namespace
