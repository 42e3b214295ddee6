#pragma once

// The latest known state of every valve and gateway on a domain, as clients show it. Pure data:
// ValveView fills it from DDS samples, the renderers and the tests read it. Telemetry is kept as
// the codec's messages, one per subject ("position", "current", ...), so that every client names,
// ranges and prints every value through the codec's table, whatever message it is.

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "teejet/codec/codec.hpp"
#include "teejet/valve.h"

namespace teejet::client {

// A valve's latest message of one subject, as the valve sent it.
struct Reply {
  std::uint64_t received_ns = 0;
  codec::FromValveMessage message;

  friend bool operator==(const Reply&, const Reply&) = default;
};

// One line of `valvectl list`.
struct ValveRow {
  std::uint32_t serial = 0;
  std::uint8_t address = 0;
  bool online = false;
  bool boot_mode = false;
  std::string gateway;
  std::string location;  // where it sits in its gateway's layout; empty: in no place
  // The DDS participant that publishes it (its GUID prefix, "01.0f.…"): the gateway whose
  // command reader must hear a command to it.
  std::string participant;
  // Its gateway vanished (its writers' liveliness lapsed, or it left): what the row says is the
  // last word, and whether the valve is online is unknown.
  bool gateway_lost = false;
  // Other gateways, alive, that report this serial online on their own bus: two valves carry
  // one serial, or something replays it. The gateways refuse its commands meanwhile.
  std::vector<std::string> also_reported_by;
  std::set<ErrorKind> errors;                           // latched, until Clear Errors
  std::map<std::string, Reply, std::less<>> telemetry;  // by subject, the latest of each

  // The values `list` shows in columns, from the telemetry (the subjects of column_subjects()).
  std::optional<double> position_degrees() const;
  std::optional<int> temperature_c() const;  // the valve's own, not its angle sensor's
  std::optional<double> volts() const;
  const Reply* reply(std::string_view subject) const;  // nullptr before the first
};

// The telemetry subjects ValveRow's columns come from: a client that shows only those (a text
// list or watch) need follow no other.
std::set<std::string> column_subjects();

struct GatewaySummary {
  std::string name;
  std::string can_interface;
  BusState bus_state = BUS_ERROR_ACTIVE;
  std::uint32_t valves_online = 0;
  std::uint32_t valves_known = 0;
  std::uint64_t frames_in = 0;
  std::uint64_t frames_out = 0;
  std::uint64_t decode_errors = 0;
  std::uint16_t tx_errors = 0;  // the CAN controller's error counters
  std::uint16_t rx_errors = 0;
  std::uint64_t rx_dropped = 0;
  std::uint32_t gateways_seen = 0;    // on the domain by its own count, itself included
  std::uint32_t locations_known = 0;  // places in its layout
  // ISO 11783-5 address claiming on its bus (docs/isobus.md): the state of its claim of
  // source_address, its NAME (isobus_name), the NAME it yielded the address to (0: none), and the
  // ECUs that claimed addresses there.
  AddressClaimState address_claim = CLAIM_OFF;
  std::uint8_t source_address = 0;
  std::uint64_t isobus_name = 0;
  std::uint64_t address_holder = 0;
  std::uint64_t address_violations = 0;
  std::uint64_t claims_in_valve_range = 0;
  std::vector<BusNeighbour> neighbours;
  // The participants publishing status under this name: more than one is two gateways
  // sharing a name.
  std::set<std::string> participants;
  bool lost = false;  // every participant under this name vanished
};

// One place of a gateway's layout (teejet/valve/location): one line of `valvectl layout`.
struct LocationRow {
  std::string name;
  std::string gateway;
  std::string participant;  // the publishing gateway's, as in ValveRow
  unsigned order = 0;
  LocationRole role = ROLE_SECTION;
  std::optional<std::uint32_t> serial;
  LocationState state = LOCATION_EMPTY;
  std::optional<double> closed_degrees;  // both known, or neither
  std::optional<double> opened_degrees;
  bool gateway_lost = false;  // its gateway vanished: the state is the last word
};

// "a, b": the gateways whose layouts hold `places` (several when two claim one name).
std::string gateway_names(const std::vector<LocationRow>& places);
// A change of `place` for the gateway whose layout holds it: LAYOUT_ASSIGN puts `serial` there
// (taken from the place it sits at when `move`), LAYOUT_UNASSIGN leaves it empty.
LayoutChange layout_change_of(const LocationRow& place, LayoutChangeKind kind,
                              std::uint32_t serial = 0, bool move = false);

class ValveTable {
 public:
  // `participant` is the publishing participant's GUID prefix (dds::participant_of).
  void on_presence(const ValvePresence& presence, const std::string& participant = {});
  // Any telemetry message, kept as the latest of its subject.
  void on_telemetry(std::uint32_t serial, const codec::FromValveMessage& message,
                    std::uint64_t received_ns);
  // A writer's last sample, delivered as it matched (ViewTopics::best_effort): kept only where
  // the table holds nothing received later of its subject.
  void on_telemetry_history(std::uint32_t serial, const codec::FromValveMessage& message,
                            std::uint64_t received_ns);
  void on_error(std::uint32_t serial, ErrorKind kind);
  void on_error_cleared(std::uint32_t serial, ErrorKind kind);
  void on_gateway_status(const GatewayStatus& status, const std::string& participant = {});
  void on_location(const ValveLocation& location, const std::string& participant = {});
  // A gateway's participant whose writers lost their liveliness or left (alive false), or came
  // back (true).
  void on_participant_liveliness(const std::string& participant, bool alive);

  // Valves with a presence sample, by serial.
  std::vector<ValveRow> rows() const;
  std::optional<ValveRow> row(std::uint32_t serial) const;
  std::vector<GatewaySummary> gateways() const;  // by name
  // Every place of every gateway's layout in machine order (order, then name, then gateway).
  std::vector<LocationRow> locations() const;
  // The places called `name`: one, or more when several gateways claim it (a mistake).
  std::vector<LocationRow> locations_named(std::string_view name) const;
  std::optional<Reply> reply(std::uint32_t serial, std::string_view subject) const;
  std::size_t online_count() const;  // online and with a gateway alive

  // Grows whenever what a row shows changes (when a reply was received aside): a dashboard
  // sends on the rows changed since the revision it last sent instead of comparing every row.
  std::uint64_t revision() const { return revision_; }
  // The rows (with a presence) that changed after `revision`, every one when a gateway was lost
  // or came back since, and those of `also` whatever their revision; by serial.
  std::vector<ValveRow> rows_changed_since(std::uint64_t revision,
                                           const std::set<std::uint32_t>& also = {}) const;

  // How many gateways discovery has found so far (writers of gateway status matched).
  void set_gateways_matched(std::size_t count) { gateways_matched_ = count; }
  std::size_t gateways_matched() const { return gateways_matched_; }
  // How many participants discovery has found that announce themselves as gateways
  // (dds::kGatewayRole), whether or not their topics have matched yet.
  void set_gateway_participants(std::size_t count) { gateway_participants_ = count; }
  std::size_t gateway_participants() const { return gateway_participants_; }
  // How many participants discovery has found alive, gateways or not: a client that met none
  // has no way to any gateway (network, profile, domain), one that met a gateway's participant
  // but matched none of its topics was not answered by it.
  void set_participants_met(std::size_t count) { participants_met_ = count; }
  std::size_t participants_met() const { return participants_met_; }
  // Whether discovery has gone quiet (dds::Participant::discovery_settled): until it has, a
  // gateway not met yet may still answer. A table filled by hand has nothing more to meet.
  void set_discovery_settled(bool settled) { discovery_settled_ = settled; }
  bool discovery_settled() const { return discovery_settled_; }

  // How many gateways there are to meet: the most that discovery has matched, that announce
  // themselves as gateways, or that any gateway met says it hears on the domain (gateways_seen).
  // A participant is met in a few milliseconds, its topics a discovery round-trip later: until
  // then the gateways already matched may know no more than each other.
  std::size_t gateways_expected() const;
  // Whether the directory is all here: discovery has settled, every gateway expected (at least
  // one) has reported its status, and each has published presence for as many valves, and as
  // many places of its layout, as it says it knows. Presence, places and gateway status are
  // durable, so this holds shortly after discovery.
  bool directory_complete() const;
  // Whether every online valve has reported position, temperature and voltage.
  bool telemetry_complete() const;
  bool empty() const { return rows_.empty() && gateways_.empty(); }

 private:
  // One gateway's word on a valve: its latest presence, and when it came (a count).
  struct Report {
    ValvePresence presence;
    std::string participant;
    std::uint64_t order = 0;
  };
  // Telemetry may arrive before presence; such a row stays hidden until presence arrives. A
  // serial is one DDS instance whoever publishes it: each gateway's report is kept apart, so
  // that one gateway's "offline" never hides another's "online".
  struct Entry {
    ValveRow row;                           // telemetry and errors; the rest comes from reports
    std::map<std::string, Report> reports;  // by participant (by gateway name when unknown)
    std::uint64_t revision = 0;             // when what it shows last changed
  };
  Entry& entry(std::uint32_t serial);
  void changed(Entry& entry) { entry.revision = ++revision_; }
  bool lost(const std::string& participant) const;  // its writers lapsed or left
  // The row as shown: from the latest report of a live gateway that says online, else from the
  // latest report; gateway_lost and also_reported_by filled in.
  ValveRow shown(const Entry& entry) const;

  std::map<std::uint32_t, Entry> rows_;
  std::uint64_t reports_ = 0;
  std::map<std::string, GatewaySummary> gateways_;
  std::map<std::pair<std::string, std::string>, LocationRow> locations_;  // by (name, gateway)
  std::size_t gateways_matched_ = 0;
  std::size_t gateway_participants_ = 0;
  std::size_t participants_met_ = 0;
  bool discovery_settled_ = true;
  std::set<std::string> lost_participants_;
  std::uint64_t revision_ = 0;
  std::uint64_t every_row_changed_ = 0;  // the revision of the last change of lost_participants_
};

}  // namespace teejet::client
