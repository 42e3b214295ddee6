#include "teejet/client/valve_table.hpp"

#include <algorithm>

#include "teejet/codec/table.hpp"

namespace teejet::client {
namespace {

std::optional<double> number_in(const Reply* reply, std::string_view field) {
  if (reply == nullptr) return std::nullopt;
  const auto value = codec::field_value(reply->message, field);
  if (!value) return std::nullopt;
  if (const auto* real = std::get_if<double>(&*value)) return *real;
  if (const auto* integer = std::get_if<std::int64_t>(&*value)) {
    return static_cast<double>(*integer);
  }
  return std::nullopt;
}

}  // namespace

const Reply* ValveRow::reply(std::string_view subject) const {
  const auto it = telemetry.find(subject);
  return it == telemetry.end() ? nullptr : &it->second;
}

std::optional<double> ValveRow::position_degrees() const {
  return number_in(reply("position"), "degrees");
}

std::optional<int> ValveRow::temperature_c() const {
  const auto celsius = number_in(reply("temperature"), "valve_c");
  if (!celsius) return std::nullopt;
  return static_cast<int>(*celsius);
}

std::optional<double> ValveRow::volts() const { return number_in(reply("voltage"), "volts"); }

std::set<std::string> column_subjects() { return {"position", "temperature", "voltage"}; }

ValveTable::Entry& ValveTable::entry(std::uint32_t serial) {
  Entry& found = rows_[serial];
  found.row.serial = serial;
  return found;
}

void ValveTable::on_presence(const ValvePresence& presence, const std::string& participant) {
  const std::string key =
      participant.empty() ? "gateway " + presence.gateway().to_string() : participant;
  Entry& found = entry(presence.serial());
  const auto [it, first] = found.reports.try_emplace(key);
  Report& report = it->second;
  // A valve's presence comes again every second with only its last-seen time new. With a
  // second reporter the newest report may change which one is shown.
  const bool shown_alike = !first && found.reports.size() == 1 &&
                           report.presence.address() == presence.address() &&
                           report.presence.online() == presence.online() &&
                           report.presence.boot_mode() == presence.boot_mode() &&
                           report.presence.gateway() == presence.gateway() &&
                           report.presence.location() == presence.location();
  report = Report{presence, participant, ++reports_};
  if (!shown_alike) changed(found);
}

void ValveTable::on_telemetry(std::uint32_t serial, const codec::FromValveMessage& message,
                              std::uint64_t received_ns) {
  const auto subject = codec::subject(message);
  if (subject.empty()) return;  // not a reply: errors and I'm Here have their own ways
  Entry& found = entry(serial);
  auto& telemetry = found.row.telemetry;
  if (const auto it = telemetry.find(subject); it != telemetry.end()) {
    const bool alike = it->second.message == message;
    it->second = Reply{received_ns, message};
    if (!alike) changed(found);
    return;
  }
  telemetry.emplace(std::string(subject), Reply{received_ns, message});
  changed(found);
}

void ValveTable::on_telemetry_history(std::uint32_t serial, const codec::FromValveMessage& message,
                                      std::uint64_t received_ns) {
  if (const auto row = rows_.find(serial); row != rows_.end()) {
    const auto& telemetry = row->second.row.telemetry;
    const auto it = telemetry.find(codec::subject(message));
    if (it != telemetry.end() && it->second.received_ns >= received_ns) return;
  }
  on_telemetry(serial, message, received_ns);
}

void ValveTable::on_error(std::uint32_t serial, ErrorKind kind) {
  Entry& found = entry(serial);
  if (found.row.errors.insert(kind).second) changed(found);
}

void ValveTable::on_error_cleared(std::uint32_t serial, ErrorKind kind) {
  Entry& found = entry(serial);
  if (found.row.errors.erase(kind) > 0) changed(found);
}

void ValveTable::on_gateway_status(const GatewayStatus& status, const std::string& participant) {
  GatewaySummary& summary = gateways_[status.gateway().to_string()];
  summary.name = status.gateway().to_string();
  summary.can_interface = status.can_interface().to_string();
  summary.bus_state = status.bus_state();
  summary.valves_online = status.valves_online();
  summary.valves_known = status.valves_known();
  summary.frames_in = status.frames_in();
  summary.frames_out = status.frames_out();
  summary.decode_errors = status.decode_errors();
  summary.tx_errors = status.tx_errors();
  summary.rx_errors = status.rx_errors();
  summary.rx_dropped = status.rx_dropped();
  summary.gateways_seen = status.gateways_seen();
  summary.locations_known = status.locations_known();
  summary.address_claim = status.address_claim();
  summary.source_address = status.source_address();
  summary.isobus_name = status.name();
  summary.address_holder = status.address_holder();
  summary.address_violations = status.address_violations();
  summary.claims_in_valve_range = status.claims_in_valve_range();
  summary.neighbours = status.neighbours();
  if (!participant.empty()) summary.participants.insert(participant);
}

void ValveTable::on_participant_liveliness(const std::string& participant, bool alive) {
  const bool news = alive ? lost_participants_.erase(participant) > 0
                          : lost_participants_.insert(participant).second;
  if (news) every_row_changed_ = ++revision_;
}

void ValveTable::on_location(const ValveLocation& location, const std::string& participant) {
  LocationRow row;
  row.name = location.location().to_string();
  row.gateway = location.gateway().to_string();
  row.participant = participant;
  row.order = location.order();
  row.role = location.role();
  if (location.assigned()) row.serial = location.serial();
  row.state = location.state();
  if (location.mechanics_known()) {
    row.closed_degrees = location.closed_degrees();
    row.opened_degrees = location.opened_degrees();
  }
  locations_.insert_or_assign({row.name, row.gateway}, std::move(row));
}

std::vector<LocationRow> ValveTable::locations() const {
  std::vector<LocationRow> out;
  for (const auto& [key, row] : locations_) {
    out.push_back(row);
    out.back().gateway_lost = lost(row.participant);
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const LocationRow& a, const LocationRow& b) { return a.order < b.order; });
  return out;
}

std::vector<LocationRow> ValveTable::locations_named(std::string_view name) const {
  std::vector<LocationRow> out;
  for (auto it = locations_.lower_bound({std::string(name), std::string()});
       it != locations_.end() && it->first.first == name; ++it) {
    out.push_back(it->second);
    out.back().gateway_lost = lost(it->second.participant);
  }
  return out;
}

bool ValveTable::lost(const std::string& participant) const {
  return !participant.empty() && lost_participants_.contains(participant);
}

ValveRow ValveTable::shown(const Entry& found) const {
  const Report* primary = nullptr;
  const auto better = [this](const Report& report, const Report* than) {
    if (than == nullptr) return true;
    const bool counts = report.presence.online() && !lost(report.participant);
    const bool than_counts = than->presence.online() && !lost(than->participant);
    if (counts != than_counts) return counts;
    return report.order > than->order;
  };
  for (const auto& [key, report] : found.reports) {
    if (better(report, primary)) primary = &report;
  }
  ValveRow row = found.row;
  if (primary == nullptr) return row;
  row.address = primary->presence.address();
  row.online = primary->presence.online();
  row.boot_mode = primary->presence.boot_mode();
  row.gateway = primary->presence.gateway().to_string();
  row.location = primary->presence.location().to_string();
  row.participant = primary->participant;
  row.gateway_lost = lost(primary->participant);
  for (const auto& [key, report] : found.reports) {
    if (&report != primary && report.presence.online() && !lost(report.participant)) {
      row.also_reported_by.push_back(report.presence.gateway().to_string());
    }
  }
  return row;
}

std::vector<ValveRow> ValveTable::rows() const {
  std::vector<ValveRow> out;
  for (const auto& [serial, found] : rows_) {
    if (!found.reports.empty()) out.push_back(shown(found));
  }
  return out;
}

std::vector<ValveRow> ValveTable::rows_changed_since(std::uint64_t revision,
                                                     const std::set<std::uint32_t>& also) const {
  std::vector<ValveRow> out;
  const bool every = every_row_changed_ > revision;
  for (const auto& [serial, found] : rows_) {
    if (found.reports.empty()) continue;
    if (every || found.revision > revision || also.contains(serial)) out.push_back(shown(found));
  }
  return out;
}

std::optional<ValveRow> ValveTable::row(std::uint32_t serial) const {
  const auto it = rows_.find(serial);
  if (it == rows_.end() || it->second.reports.empty()) return std::nullopt;
  return shown(it->second);
}

std::vector<GatewaySummary> ValveTable::gateways() const {
  std::vector<GatewaySummary> out;
  for (const auto& [name, summary] : gateways_) {
    out.push_back(summary);
    out.back().lost =
        !summary.participants.empty() &&
        std::all_of(summary.participants.begin(), summary.participants.end(),
                    [this](const std::string& participant) { return lost(participant); });
  }
  return out;
}

std::optional<Reply> ValveTable::reply(std::uint32_t serial, std::string_view subject) const {
  const auto it = rows_.find(serial);
  if (it == rows_.end()) return std::nullopt;
  const Reply* found = it->second.row.reply(subject);
  if (found == nullptr) return std::nullopt;
  return *found;
}

std::size_t ValveTable::online_count() const {
  return static_cast<std::size_t>(
      std::count_if(rows_.begin(), rows_.end(), [this](const auto& item) {
        const auto& reports = item.second.reports;
        return std::any_of(reports.begin(), reports.end(), [this](const auto& report) {
          return report.second.presence.online() && !lost(report.second.participant);
        });
      }));
}

std::size_t ValveTable::gateways_expected() const {
  std::size_t expected = std::max<std::size_t>({gateways_matched_, gateway_participants_, 1});
  for (const auto& [name, summary] : gateways_) {
    expected = std::max<std::size_t>(expected, summary.gateways_seen);
  }
  return expected;
}

bool ValveTable::directory_complete() const {
  if (!discovery_settled_ || gateways_.size() < gateways_expected()) return false;
  for (const auto& [name, summary] : gateways_) {
    // Captured by name: clang before 16 cannot capture a structured binding.
    const auto known =
        std::count_if(rows_.begin(), rows_.end(), [&gateway = name](const auto& item) {
          const auto& reports = item.second.reports;
          return std::any_of(reports.begin(), reports.end(), [&gateway](const auto& report) {
            return report.second.presence.gateway().to_string() == gateway;
          });
        });
    if (static_cast<std::uint64_t>(known) < summary.valves_known) return false;
    const auto places =
        std::count_if(locations_.begin(), locations_.end(),
                      [&gateway = name](const auto& item) { return item.first.second == gateway; });
    if (static_cast<std::uint64_t>(places) < summary.locations_known) return false;
  }
  return true;
}

std::string gateway_names(const std::vector<LocationRow>& places) {
  std::string names;
  for (const auto& place : places) names += (names.empty() ? "" : ", ") + place.gateway;
  return names;
}

LayoutChange layout_change_of(const LocationRow& place, LayoutChangeKind kind, std::uint32_t serial,
                              bool move) {
  LayoutChange change;
  change.location(place.name);
  change.gateway(place.gateway);
  change.kind(kind);
  change.serial(serial);
  change.move(move);
  return change;
}

bool ValveTable::telemetry_complete() const {
  return std::all_of(rows_.begin(), rows_.end(), [this](const auto& item) {
    const ValveRow row = shown(item.second);
    return item.second.reports.empty() || !row.online ||
           (row.position_degrees() && row.temperature_c() && row.volts());
  });
}

}  // namespace teejet::client
