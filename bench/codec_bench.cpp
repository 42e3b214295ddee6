// Codec throughput: how many frames a core decodes and encodes per second.
#include <benchmark/benchmark.h>

#include "teejet/codec/codec.hpp"

namespace {

using namespace teejet::codec;

const CanFrame kPosition = encode(0xD8, FromValveMessage{Position{123.4}}).value();
const CanFrame kIAmHere = encode(0xD8, FromValveMessage{IAmHere{0x12345, 123456, false}}).value();
const CanFrame kMinDps =
    encode(0xD8, FromValveMessage{MinDegreesPerSecondError{12, 20, Direction::kOpen}}).value();

void DecodePosition(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(decode(kPosition));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(DecodePosition);

void DecodeIAmHere(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(decode(kIAmHere));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(DecodeIAmHere);

// The last id in the from-valve table: the worst case of the dispatch by id.
void DecodeLastTableEntry(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(decode(kMinDps));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(DecodeLastTableEntry);

void EncodeTargetDegrees(benchmark::State& state) {
  const ToValveMessage move{TargetDegrees{100, TargetDirection::kShortest, 123.4}};
  for (auto _ : state) benchmark::DoNotOptimize(encode(0xD8, move));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(EncodeTargetDegrees);

void RejectForeignFrame(benchmark::State& state) {
  const CanFrame foreign{.id = 0x18FEF100, .dlc = 8};
  for (auto _ : state) benchmark::DoNotOptimize(decode(foreign));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(RejectForeignFrame);

}  // namespace
