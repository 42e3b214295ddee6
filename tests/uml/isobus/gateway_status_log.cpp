// Test peer for address_claim.sh: every GatewayStatus the gateways of a domain publish, one line
// each, so that a script can wait for what the gateway says about its address claim. valvectl
// shows the same fields to people once per refresh, which can miss the 250 ms of CLAIM_CLAIMING;
// this prints every sample, read from the generated type itself:
//   status gateway=G bus=error_active claim=claimed address=0xD5 name=0x200880000541B2C3
//     holder=0x0000000000000000 violations=0 valve_range_claims=0 frames_in=N frames_out=N
//     decode_errors=0 neighbours=0x80:0xA00C81045A20021B,0xE0:0x...
// (one line). Runs until SIGTERM or SIGINT.
// Usage: gateway_status_log DOMAIN

#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <string>
#include <thread>

#include "teejet/dds/names.hpp"
#include "teejet/dds/participant.hpp"
#include "teejet/dds/topics.hpp"
#include "teejet/valvePubSubTypes.h"

namespace {

using eprosima::fastdds::dds::DataReader;
using eprosima::fastdds::dds::SampleInfo;
using ReturnCode = eprosima::fastrtps::types::ReturnCode_t;

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

std::string hex(unsigned long long value, int digits) {
  char text[24];
  std::snprintf(text, sizeof text, "0x%0*llX", digits, value);
  return text;
}

// Printed on Fast DDS's thread as each sample arrives; stdout is line-buffered.
class Printer final : public eprosima::fastdds::dds::DataReaderListener {
 public:
  void on_data_available(DataReader* reader) override {
    teejet::GatewayStatus status;
    SampleInfo info;
    while (reader->take_next_sample(&status, &info) == ReturnCode::RETCODE_OK) {
      if (!info.valid_data) continue;
      std::string neighbours;
      for (const auto& neighbour : status.neighbours()) {
        if (!neighbours.empty()) neighbours += ',';
        neighbours += hex(neighbour.address(), 2) + ':' + hex(neighbour.name(), 16);
      }
      std::printf(
          "status gateway=%s bus=%s claim=%s address=%s name=%s holder=%s violations=%llu "
          "valve_range_claims=%llu frames_in=%llu frames_out=%llu decode_errors=%llu "
          "neighbours=%s\n",
          status.gateway().c_str(), std::string(teejet::dds::to_string(status.bus_state())).c_str(),
          std::string(teejet::dds::to_string(status.address_claim())).c_str(),
          hex(status.source_address(), 2).c_str(), hex(status.name(), 16).c_str(),
          hex(status.address_holder(), 16).c_str(),
          static_cast<unsigned long long>(status.address_violations()),
          static_cast<unsigned long long>(status.claims_in_valve_range()),
          static_cast<unsigned long long>(status.frames_in()),
          static_cast<unsigned long long>(status.frames_out()),
          static_cast<unsigned long long>(status.decode_errors()),
          neighbours.empty() ? "none" : neighbours.c_str());
    }
  }
};

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: gateway_status_log DOMAIN\n");
    return 64;
  }
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  std::signal(SIGTERM, on_signal);
  std::signal(SIGINT, on_signal);
  auto participant = teejet::dds::Participant::create(
      {.domain = std::atoi(argv[1]), .name = "gateway-status-log"});
  if (!participant) {
    std::fprintf(stderr, "gateway_status_log: %s\n", participant.error().reason.c_str());
    return 1;
  }
  auto topic =
      (*participant)->topic<teejet::GatewayStatusPubSubType>(teejet::dds::topics::kGatewayStatus);
  if (!topic) {
    std::fprintf(stderr, "gateway_status_log: %s\n", topic.error().reason.c_str());
    return 1;
  }
  Printer printer;
  auto reader = (*participant)
                    ->reader(*topic, teejet::dds::topics::state_reader_qos(), &printer,
                             eprosima::fastdds::dds::StatusMask::data_available());
  if (!reader) {
    std::fprintf(stderr, "gateway_status_log: %s\n", reader.error().reason.c_str());
    return 1;
  }
  while (!g_stop) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  (*participant)->delete_reader(*reader);  // no callback runs once this returns
  return 0;
}
