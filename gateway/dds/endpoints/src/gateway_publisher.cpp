#include "teejet/dds/gateway_publisher.hpp"

#include <spdlog/spdlog.h>

#include <atomic>

#include "teejet/dds/participant.hpp"

namespace teejet::dds {

using namespace eprosima::fastdds::dds;

namespace {

// A failed write loses a sample that consumers expect: say so, without flooding the log.
void report(const std::string& topic, const ReturnCode_t& result) {
  if (result == ReturnCode_t::RETCODE_OK) return;
  static std::atomic<std::uint64_t> failures{0};
  const auto count = ++failures;
  if (count == 1 || count % 1000 == 0) {
    spdlog::error("DDS write on {} failed (code {}); {} failed write(s) so far", topic, result(),
                  count);
  }
}

}  // namespace

Result<std::unique_ptr<GatewayPublisher>> GatewayPublisher::create(
    Participant& participant, const std::string& gateway_name,
    const std::set<std::string>& locations) {
  std::unique_ptr<GatewayPublisher> made(new GatewayPublisher());
  if (auto created = made->telemetry_.create(participant, topics::state_writer_qos()); !created) {
    return created.error();
  }
  if (auto created = made->state_.create(participant, topics::state_writer_qos()); !created) {
    return created.error();
  }
  if (auto created = made->command_status_.create(participant, topics::status_writer_qos());
      !created) {
    return created.error();
  }
  if (auto created = made->layout_status_.create(participant, topics::status_writer_qos());
      created) {
    made->layout_status_ready_ = true;
  } else {
    spdlog::warn(
        "cannot write {} ({}): this gateway takes no layout changes over DDS (valvectl assign); "
        "give the gateway role publish permission for it (config/security/roles/gateway.xml)",
        topics::kLayoutChangeStatus, created.error().reason);
  }
  auto peers =
      PeerGateways::create(participant, gateway_name, made->state_.writer<GatewayStatus>()->guid());
  if (peers) {
    made->peers_ = std::move(*peers);
  } else {
    // Permissions made before gateways read each other's status: run, and say what is missing.
    spdlog::warn(
        "cannot read {} ({}): this gateway counts only itself in gateways_seen, so clients may "
        "call a valve unknown before they have met every gateway; give the gateway role "
        "subscribe permission for it (config/security/roles/gateway.xml)",
        topics::kGatewayStatus, peers.error().reason);
  }
  if (!locations.empty()) {
    if (auto claims = LocationClaims::create(participant, gateway_name, locations); claims) {
      made->claims_ = std::move(*claims);
    } else {
      spdlog::warn(
          "cannot read {} ({}): a location that another gateway claims too goes unnoticed; give "
          "the gateway role subscribe permission for it (config/security/roles/gateway.xml)",
          topics::kLocation, claims.error().reason);
    }
  }
  return made;
}

void GatewayPublisher::presence(const ValvePresence& sample) {
  report(topics::kPresence, state_.write(sample, sample.last_seen_ns()));
}

void GatewayPublisher::location(const ValveLocation& sample) {
  report(topics::kLocation, state_.write(sample, 0));
}

void GatewayPublisher::telemetry(const TelemetrySample& sample) {
  std::visit(
      [this](const auto& s) {
        report(topics::topic_name<std::decay_t<decltype(s)>>(),
               telemetry_.write(s, s.received_ns()));
      },
      sample);
}

void GatewayPublisher::error_cleared(std::uint32_t serial, ErrorKind kind) {
  ValveError key;
  key.serial(serial);
  key.kind(kind);
  report(topics::kError, telemetry_.dispose(key));
}

void GatewayPublisher::command_status(const CommandStatus& status) {
  report(topics::kCommandStatus, command_status_.write(status, 0));
}

void GatewayPublisher::layout_change_status(const LayoutChangeStatus& status) {
  if (layout_status_ready_) report(topics::kLayoutChangeStatus, layout_status_.write(status, 0));
}

void GatewayPublisher::gateway_status(const GatewayStatus& status) {
  GatewayStatus counted = status;
  counted.gateways_seen(peers_ ? peers_->count() : 1);
  report(topics::kGatewayStatus, state_.write(counted, 0));
}

bool GatewayPublisher::wait_for_statuses(Duration timeout) {
  return command_status_.writer<CommandStatus>()->wait_for_acknowledgments(
             to_dds_duration(timeout)) == ReturnCode_t::RETCODE_OK;
}

}  // namespace teejet::dds
