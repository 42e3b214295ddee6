// Stands in for a gateway that a person keeps changing the layout of, for layout_kill_tests: a
// bridge on a virtual bus with eight valves online, saving to the layout file FILE through the
// gateway's own store, applying the changes of layout_churn.hpp one after another until killed.
// Prints "answered N" once the status of change N is published, after the bridge saved it.
// Usage: layout_churn FILE

#include "layout_churn.hpp"

#include <cstdio>

#include "teejet/bridge/bridge.hpp"
#include "teejet/can/virtual_bus.hpp"
#include "teejet/layout/layout_file.hpp"

namespace {

using namespace teejet;

class AnswerPrinter final : public bridge::Sink {
 public:
  void presence(const ValvePresence&) override {}
  void location(const ValveLocation&) override {}
  void telemetry(const dds::TelemetrySample&) override {}
  void error_cleared(std::uint32_t, ErrorKind) override {}
  void command_status(const CommandStatus&) override {}
  void gateway_status(const GatewayStatus&) override {}
  void layout_change_status(const LayoutChangeStatus& status) override {
    if (status.state() != LAYOUT_CHANGE_APPLIED) {
      std::printf("refused %u: %s\n", status.change_id(), status.reason().c_str());
    }
    std::printf("answered %u\n", status.change_id());
    std::fflush(stdout);
  }
};

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: layout_churn FILE\n");
    return 64;
  }
  auto start = layout::load_layout_file(argv[1]);
  if (!start) {
    std::fprintf(stderr, "layout_churn: %s\n", start.error().reason.c_str());
    return 1;
  }
  bridge::BridgeConfig config;
  config.gateway_name = "churn";
  config.isobus.claim = false;
  config.layout = *start;
  can::VirtualBus bus("layout-churn", {.filters = can::controller_side_filters()});
  if (!bus.open()) return 1;
  AnswerPrinter printer;
  layout::LayoutFileStore store(argv[1]);
  bridge::Bridge bridge(config, bus, printer, system_clock(), nullptr, &store);
  for (std::uint32_t serial = 1; serial <= testing::churn::kValves; ++serial) {
    const auto address = static_cast<std::uint8_t>(0xD7 + serial);
    bridge.on_frame({codec::encode(address, codec::IAmHere{0x000123, serial, false}).value(),
                     system_clock()->wall()});
  }
  std::printf("ready\n");
  std::fflush(stdout);
  for (std::uint64_t index = 0;; ++index) {
    const auto next = testing::churn::change(index);
    LayoutChange change;
    change.location(next.location);
    change.gateway("churn");
    change.change_id(static_cast<std::uint32_t>(index));
    change.kind(LAYOUT_ASSIGN);
    change.serial(next.serial);
    change.move(true);
    bridge.on_layout_change(change);
  }
}
