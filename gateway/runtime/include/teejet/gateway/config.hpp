#pragma once

// Everything the gateway is told: command-line flags over a YAML file over defaults. The file
// format is documented with examples in docs/gateway.md; config/gateway.example.yaml shows
// every key with its default.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "teejet/bridge/bridge.hpp"
#include "teejet/core/result.hpp"
#include "teejet/sim/valve_config.hpp"

namespace teejet::gateway {

enum class OnCommanderLost { kStopItsValves, kIgnore };

struct GatewayConfig {
  std::string can = "";  // SocketCAN interface, "virtual:NAME", or "sim:N"
  int domain = 0;
  std::string profile_file;
  bool stop_valves_on_exit = true;
  OnCommanderLost on_commander_lost = OnCommanderLost::kStopItsValves;
  // On a bus this busy (frames a second, over the last second and its last tenth; 0: any), while
  // frames arrive closer together than receive_coalesce, the bus reader waits that long after a
  // batch before taking the next one (interrupt moderation): one wake-up carries several frames. A
  // full 500 kbit/s bus is ~3,900 frames/s; below the rate every frame wakes the reader at once.
  // receive_coalesce 0: never. docs/performance.md has the trade.
  Duration receive_coalesce = std::chrono::microseconds(4000);
  unsigned receive_coalesce_above = 3000;
  // Publish every frame the gateway sends and receives on teejet/can/frame. Off: no frame
  // topic or writer exists at all.
  bool record_frames = false;
  // For --can sim:N: the embedded simulator's N valves, serials from sim_first_serial up, or
  // these N serials (simulator.serials).
  std::uint32_t sim_first_serial = 1;
  std::vector<std::uint32_t> sim_serials;
  double sim_degrees_per_second = 90.0;
  double sim_closed_degrees = 0.0;
  double sim_opened_degrees = 90.0;
  std::vector<sim::SerialError> sim_errors;  // latched at power-up, as valve-sim --inject-error
  // Every period one simulated valve, picked at random (the same for the same seed), goes off
  // and comes back sim_churn_off_time() later, so the bank is re-ranked. 0: off.
  Duration sim_churn_period{0};
  std::uint32_t sim_churn_seed = 0;
  // Long enough for the gateway to see the valve go offline, and a second to spare.
  Duration sim_churn_off_time() const { return bridge.offline_after + std::chrono::seconds(1); }
  bridge::BridgeConfig bridge;  // bridge.layout: where each valve sits (docs/layout.md)
  // The layout file, read at start (read_layout_file). Empty: the layout is the configuration's
  // `layout:` section, or none.
  std::string layout_file;
  bool layout_in_config = false;  // the configuration has a `layout:` section
};

// Reads a YAML file over `base`. Unknown keys, keys given twice and values outside their range
// are errors naming the file, line and key, so a typo never silently does nothing.
Result<GatewayConfig> load_config_file(const std::string& path, GatewayConfig base);

// Same, from text (for tests and error messages naming the source).
Result<GatewayConfig> parse_config(const std::string& yaml, const std::string& source,
                                   GatewayConfig base);

// Reads config.layout_file, when there is one, into config.bridge.layout; refused when the
// configuration has a layout of its own too.
Status read_layout_file(GatewayConfig& config);

}  // namespace teejet::gateway
