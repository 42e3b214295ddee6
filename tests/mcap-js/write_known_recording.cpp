// Writes recordings of known content for the independent reader's test (read-mcap.mjs): one
// channel for every topic of the DDS contract plus "/disposed" channels, several samples each
// with distinct values chosen to catch the usual decoding slips (float32 vs float64, signed int8,
// uint64 above 2^53, enums, bounded strings at their limit, sequences of every length), each
// serialized by the fastddsgen type support exactly as a DataWriter would put it on the wire.
//
// Usage: write_known_recording OUT_DIR
// Writes into OUT_DIR:
//   known-zstd.mcap, known-lz4.mcap, known-none.mcap  the same messages, three compressions
//   known.json            what read-mcap.mjs must print for each of them, one array element per
//                         message in file order (64-bit integers as decimal strings)
//   unknown-schema.mcap   a channel whose schema names a type the IDL does not define
//   undecodable.mcap      a ValvePosition message cut short after its serial
// The IDL is TEEJET_VALVE_IDL, the source tree's idl/teejet/valve.idl.

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "teejet/dds/topics.hpp"
#include "teejet/mcap/writer.hpp"

namespace {

using nlohmann::json;
using teejet::mcap::Bytes;
namespace topics = teejet::dds::topics;

[[noreturn]] void fail(const std::string& what) {
  std::fprintf(stderr, "write_known_recording: %s\n", what.c_str());
  std::exit(1);
}

template <class R>
auto must(R&& result, const std::string& what) {
  if (!result.ok()) {
    fail(what + ": " + result.error().reason);
  }
  if constexpr (!std::is_same_v<std::decay_t<R>, teejet::Status>) {
    return std::move(*result);
  }
}

// 2026-11-24 00:00:00 UTC in ns: far above 2^53, so a reader that goes through double loses it.
constexpr std::uint64_t kBase = 1'763'942'400'000'000'000ULL;
// 2^53 + 1, the first integer a double cannot hold.
constexpr std::uint64_t kAbove53 = 9'007'199'254'740'993ULL;

std::string u64(std::uint64_t value) { return std::to_string(value); }
double f32(float value) { return static_cast<double>(value); }

// Exactly string<64>'s bound.
constexpr char kLongest[] = "gateway-64-chars-0123456789abcdefghijklmnopqrstuvwxyzABCDEFGHIJK";
static_assert(sizeof(kLongest) == 64 + 1);
const std::string k64 = kLongest;

// The DDS serialized payload as a DataWriter sends it: encapsulation header, then CDR.
template <class Sample>
Bytes serialize(Sample sample) {
  typename teejet::PubSubTypeOf<Sample>::type type;
  eprosima::fastrtps::rtps::SerializedPayload_t payload(type.getSerializedSizeProvider(&sample)());
  if (!type.serialize(&sample, &payload)) {
    fail(std::string("fastddsgen could not serialize a ") + type.getName());
  }
  return Bytes(payload.data, payload.data + payload.length);
}

struct Sample {
  Bytes payload;
  json data;
};

struct ChannelSpec {
  std::string topic;
  std::string schema;  // "teejet::<Type>"
  std::map<std::string, std::string> metadata;
  std::vector<Sample> samples;
};

template <class T>
Sample make(const T& sample, json data) {
  return {serialize(sample), std::move(data)};
}

json version_json(const teejet::SoftwareVersion& v) {
  // char is an unsigned octet in omgidl-serialization: the reader prints its code.
  return {
      {"major", v.major()}, {"minor", v.minor()}, {"test", static_cast<std::uint8_t>(v.test())}};
}

Sample presence(std::uint32_t serial, std::uint8_t address, bool online, std::uint32_t part,
                bool boot, std::uint64_t seen, const std::string& gateway,
                const std::string& location = "") {
  teejet::ValvePresence s;
  s.serial(serial);
  s.address(address);
  s.online(online);
  s.part_number(part);
  s.boot_mode(boot);
  s.last_seen_ns(seen);
  s.gateway(gateway);
  s.location(location);
  return make(s, {{"serial", serial},
                  {"address", address},
                  {"online", online},
                  {"part_number", part},
                  {"boot_mode", boot},
                  {"last_seen_ns", u64(seen)},
                  {"gateway", gateway},
                  {"location", location}});
}

struct LocationValues {
  std::string location;
  std::string gateway;
  std::uint16_t order;
  teejet::LocationRole role;
  bool assigned;
  std::uint32_t serial;
  teejet::LocationState state;
  bool mechanics_known;
  float closed, opened;
};

Sample location(const LocationValues& v) {
  teejet::ValveLocation s;
  s.location(v.location);
  s.gateway(v.gateway);
  s.order(v.order);
  s.role(v.role);
  s.assigned(v.assigned);
  s.serial(v.serial);
  s.state(v.state);
  s.mechanics_known(v.mechanics_known);
  s.closed_degrees(v.closed);
  s.opened_degrees(v.opened);
  return make(s, {{"location", v.location},
                  {"gateway", v.gateway},
                  {"order", v.order},
                  {"role", static_cast<std::uint32_t>(v.role)},
                  {"assigned", v.assigned},
                  {"serial", v.serial},
                  {"state", static_cast<std::uint32_t>(v.state)},
                  {"mechanics_known", v.mechanics_known},
                  {"closed_degrees", v.closed},
                  {"opened_degrees", v.opened}});
}

// What a layout change and its status share.
struct LayoutKey {
  std::string location;
  std::string gateway;
  std::uint32_t id;
  std::string origin;
  teejet::LayoutChangeKind kind;
  std::uint32_t serial;
};

// Sets the shared fields on `s`; returns them as the reader must show them.
template <class T>
json layout_fields(T& s, const LayoutKey& k) {
  s.location(k.location);
  s.gateway(k.gateway);
  s.change_id(k.id);
  s.origin(k.origin);
  s.kind(k.kind);
  s.serial(k.serial);
  return {{"location", k.location},
          {"gateway", k.gateway},
          {"change_id", k.id},
          {"origin", k.origin},
          {"kind", static_cast<std::uint32_t>(k.kind)},
          {"serial", k.serial}};
}

Sample layout_change(const LayoutKey& key, bool move) {
  teejet::LayoutChange s;
  json data = layout_fields(s, key);
  s.move(move);
  data["move"] = move;
  return make(s, std::move(data));
}

Sample layout_status(const LayoutKey& key, teejet::LayoutChangeState state,
                     const std::string& reason, std::uint64_t ns) {
  teejet::LayoutChangeStatus s;
  json data = layout_fields(s, key);
  s.state(state);
  s.reason(reason);
  s.stamp_ns(ns);
  data["state"] = static_cast<std::uint32_t>(state);
  data["reason"] = reason;
  data["stamp_ns"] = u64(ns);
  return make(s, std::move(data));
}

Sample version(std::uint32_t serial, teejet::SoftwareVersion app, teejet::SoftwareVersion boot,
               std::uint64_t ns) {
  teejet::ValveVersion s;
  s.serial(serial);
  s.application(app);
  s.bootloader(boot);
  s.received_ns(ns);
  return make(s, {{"serial", serial},
                  {"application", version_json(app)},
                  {"bootloader", version_json(boot)},
                  {"received_ns", u64(ns)}});
}

teejet::SoftwareVersion software(std::uint8_t major, std::uint8_t minor, char test) {
  teejet::SoftwareVersion v;
  v.major(major);
  v.minor(minor);
  v.test(test);
  return v;
}

Sample position(std::uint32_t serial, float degrees, std::uint64_t ns) {
  teejet::ValvePosition s;
  s.serial(serial);
  s.degrees(degrees);
  s.received_ns(ns);
  return make(s, {{"serial", serial}, {"degrees", f32(degrees)}, {"received_ns", u64(ns)}});
}

Sample temperature(std::uint32_t serial, std::int8_t valve, std::int8_t sensor, std::uint64_t ns) {
  teejet::ValveTemperature s;
  s.serial(serial);
  s.valve_c(valve);
  s.sensor_c(sensor);
  s.received_ns(ns);
  return make(
      s, {{"serial", serial}, {"valve_c", valve}, {"sensor_c", sensor}, {"received_ns", u64(ns)}});
}

Sample voltage(std::uint32_t serial, float volts, std::uint64_t ns) {
  teejet::ValveVoltage s;
  s.serial(serial);
  s.volts(volts);
  s.received_ns(ns);
  return make(s, {{"serial", serial}, {"volts", f32(volts)}, {"received_ns", u64(ns)}});
}

Sample current(std::uint32_t serial, float amps, float last, std::uint64_t ns) {
  teejet::ValveCurrent s;
  s.serial(serial);
  s.amps(amps);
  s.last_running_amps(last);
  s.received_ns(ns);
  return make(s, {{"serial", serial},
                  {"amps", f32(amps)},
                  {"last_running_amps", f32(last)},
                  {"received_ns", u64(ns)}});
}

Sample dps(std::uint32_t serial, std::uint16_t value, teejet::Direction direction,
           std::uint64_t ns) {
  teejet::ValveDegreesPerSecond s;
  s.serial(serial);
  s.dps(value);
  s.direction(direction);
  s.received_ns(ns);
  return make(s, {{"serial", serial},
                  {"dps", value},
                  {"direction", static_cast<std::uint32_t>(direction)},
                  {"received_ns", u64(ns)}});
}

Sample speed(std::uint32_t serial, std::uint8_t percent, teejet::Direction direction,
             teejet::Rotation rotation, std::uint64_t ns) {
  teejet::ValveSpeedDirection s;
  s.serial(serial);
  s.speed_percent(percent);
  s.direction(direction);
  s.opening_direction(rotation);
  s.received_ns(ns);
  return make(s, {{"serial", serial},
                  {"speed_percent", percent},
                  {"direction", static_cast<std::uint32_t>(direction)},
                  {"opening_direction", static_cast<std::uint32_t>(rotation)},
                  {"received_ns", u64(ns)}});
}

Sample run_time(std::uint32_t serial, std::uint32_t seconds, std::uint64_t ns) {
  teejet::ValveRunTime s;
  s.serial(serial);
  s.seconds(seconds);
  s.received_ns(ns);
  return make(s, {{"serial", serial}, {"seconds", seconds}, {"received_ns", u64(ns)}});
}

Sample cycles(std::uint32_t serial, std::uint32_t count, std::uint64_t ns) {
  teejet::ValveCycleCounts s;
  s.serial(serial);
  s.count(count);
  s.received_ns(ns);
  return make(s, {{"serial", serial}, {"count", count}, {"received_ns", u64(ns)}});
}

Sample baud(std::uint32_t serial, std::uint32_t bit_rate, std::uint64_t ns) {
  teejet::ValveBaudRate s;
  s.serial(serial);
  s.bit_rate(bit_rate);
  s.received_ns(ns);
  return make(s, {{"serial", serial}, {"bit_rate", bit_rate}, {"received_ns", u64(ns)}});
}

Sample error(std::uint32_t serial, teejet::ErrorKind kind, float value, float limit,
             teejet::Direction direction, std::uint64_t ns) {
  teejet::ValveError s;
  s.serial(serial);
  s.kind(kind);
  s.value(value);
  s.limit(limit);
  s.direction(direction);
  s.received_ns(ns);
  return make(s, {{"serial", serial},
                  {"kind", static_cast<std::uint32_t>(kind)},
                  {"value", f32(value)},
                  {"limit", f32(limit)},
                  {"direction", static_cast<std::uint32_t>(direction)},
                  {"received_ns", u64(ns)}});
}

struct CommandValues {
  std::uint32_t serial;
  std::uint32_t id;
  std::string origin;
  teejet::CommandKind kind;
  std::uint8_t speed;
  teejet::Direction direction;
  float degrees;
  std::uint16_t milliseconds;
  teejet::Telemetry telemetry;
  std::uint8_t resend;
  std::uint32_t bit_rate;
};

Sample command(const CommandValues& v) {
  teejet::ValveCommand s;
  s.serial(v.serial);
  s.command_id(v.id);
  s.origin(v.origin);
  s.kind(v.kind);
  s.speed_percent(v.speed);
  s.direction(v.direction);
  s.degrees(v.degrees);
  s.milliseconds(v.milliseconds);
  s.telemetry(v.telemetry);
  s.resend_tenths(v.resend);
  s.bit_rate(v.bit_rate);
  return make(s, {{"serial", v.serial},
                  {"command_id", v.id},
                  {"origin", v.origin},
                  {"kind", static_cast<std::uint32_t>(v.kind)},
                  {"speed_percent", v.speed},
                  {"direction", static_cast<std::uint32_t>(v.direction)},
                  {"degrees", f32(v.degrees)},
                  {"milliseconds", v.milliseconds},
                  {"telemetry", static_cast<std::uint32_t>(v.telemetry)},
                  {"resend_tenths", v.resend},
                  {"bit_rate", v.bit_rate}});
}

Sample status(std::uint32_t serial, std::uint32_t id, const std::string& origin,
              teejet::CommandKind kind, teejet::CommandState state, const std::string& reason,
              std::uint64_t ns) {
  teejet::CommandStatus s;
  s.serial(serial);
  s.command_id(id);
  s.origin(origin);
  s.kind(kind);
  s.state(state);
  s.reason(reason);
  s.stamp_ns(ns);
  return make(s, {{"serial", serial},
                  {"command_id", id},
                  {"origin", origin},
                  {"kind", static_cast<std::uint32_t>(kind)},
                  {"state", static_cast<std::uint32_t>(state)},
                  {"reason", reason},
                  {"stamp_ns", u64(ns)}});
}

struct GatewayValues {
  std::string gateway;
  std::string can_interface;
  teejet::BusState bus_state;
  std::uint16_t tx_errors, rx_errors;
  std::uint64_t frames_in, frames_out, decode_errors, rx_dropped;
  std::uint32_t online, known;
  std::uint64_t stamp;
  std::uint32_t gateways_seen;
  std::vector<std::uint32_t> serials_online;
  std::uint32_t locations_known;
  teejet::AddressClaimState address_claim;
  std::uint8_t source_address;
  std::uint64_t name, holder, violations, claims_in_valve_range;
  struct Neighbour {
    std::uint8_t address;
    std::uint64_t name, last_seen;
  };
  std::vector<Neighbour> neighbours;
};

Sample gateway_status(const GatewayValues& v) {
  teejet::GatewayStatus s;
  s.gateway(v.gateway);
  s.can_interface(v.can_interface);
  s.bus_state(v.bus_state);
  s.tx_errors(v.tx_errors);
  s.rx_errors(v.rx_errors);
  s.frames_in(v.frames_in);
  s.frames_out(v.frames_out);
  s.decode_errors(v.decode_errors);
  s.rx_dropped(v.rx_dropped);
  s.valves_online(v.online);
  s.valves_known(v.known);
  s.stamp_ns(v.stamp);
  s.gateways_seen(v.gateways_seen);
  s.serials_online(v.serials_online);
  s.locations_known(v.locations_known);
  s.address_claim(v.address_claim);
  s.source_address(v.source_address);
  s.name(v.name);
  s.address_holder(v.holder);
  s.address_violations(v.violations);
  s.claims_in_valve_range(v.claims_in_valve_range);
  std::vector<teejet::BusNeighbour> neighbours;
  json neighbours_json = json::array();
  for (const auto& n : v.neighbours) {
    teejet::BusNeighbour neighbour;
    neighbour.address(n.address);
    neighbour.name(n.name);
    neighbour.last_seen_ns(n.last_seen);
    neighbours.push_back(neighbour);
    neighbours_json.push_back(
        {{"address", n.address}, {"name", u64(n.name)}, {"last_seen_ns", u64(n.last_seen)}});
  }
  s.neighbours(neighbours);
  return make(s, {{"gateway", v.gateway},
                  {"can_interface", v.can_interface},
                  {"bus_state", static_cast<std::uint32_t>(v.bus_state)},
                  {"tx_errors", v.tx_errors},
                  {"rx_errors", v.rx_errors},
                  {"frames_in", u64(v.frames_in)},
                  {"frames_out", u64(v.frames_out)},
                  {"decode_errors", u64(v.decode_errors)},
                  {"rx_dropped", u64(v.rx_dropped)},
                  {"valves_online", v.online},
                  {"valves_known", v.known},
                  {"stamp_ns", u64(v.stamp)},
                  {"gateways_seen", v.gateways_seen},
                  {"serials_online", v.serials_online},
                  {"locations_known", v.locations_known},
                  {"address_claim", static_cast<std::uint32_t>(v.address_claim)},
                  {"source_address", v.source_address},
                  {"name", u64(v.name)},
                  {"address_holder", u64(v.holder)},
                  {"address_violations", u64(v.violations)},
                  {"claims_in_valve_range", u64(v.claims_in_valve_range)},
                  {"neighbours", neighbours_json}});
}

// A data frame of `data`; a remote frame (remote_dlc) asks for that many bytes and carries none.
Sample frame(const std::string& gateway, const std::string& interface, std::uint32_t id,
             bool extended, const std::vector<std::uint8_t>& data, teejet::FrameDirection direction,
             std::uint64_t ns, std::optional<std::uint8_t> remote_dlc = std::nullopt) {
  const auto dlc = remote_dlc.value_or(static_cast<std::uint8_t>(data.size()));
  teejet::BusFrame s;
  s.gateway(gateway);
  s.can_interface(interface);
  s.id(id);
  s.extended(extended);
  s.remote(remote_dlc.has_value());
  s.dlc(dlc);
  s.data(data);
  s.direction(direction);
  s.stamp_ns(ns);
  return make(s, {{"gateway", gateway},
                  {"can_interface", interface},
                  {"id", id},
                  {"extended", extended},
                  {"remote", remote_dlc.has_value()},
                  {"dlc", dlc},
                  {"data", data},
                  {"direction", static_cast<std::uint32_t>(direction)},
                  {"stamp_ns", u64(ns)}});
}

std::map<std::string, std::string> live(const std::string& topic) { return {{"dds_topic", topic}}; }
std::map<std::string, std::string> disposed(const std::string& topic) {
  return {{"dds_topic", topic}, {"instance_state", "disposed"}};
}

template <class... Samples>
nlohmann::json contract_topics(topics::SampleTypes<Samples...>) {
  return nlohmann::json::array({topics::topic_name<Samples>()...});
}

std::vector<ChannelSpec> known_channels() {
  using namespace teejet;
  constexpr std::uint32_t kA = 0x123456;  // TJV1193046
  constexpr std::uint32_t kB = 0xFFFFFF;  // the largest 24-bit serial
  constexpr std::uint32_t kC = 1;
  std::vector<ChannelSpec> channels;
  auto add = [&](const std::string& topic, const char* type, std::vector<Sample> samples,
                 bool is_disposed = false) {
    const std::string name = is_disposed ? std::string(topic) + "/disposed" : std::string(topic);
    channels.push_back({name, std::string("teejet::") + type,
                        is_disposed ? disposed(topic) : live(topic), std::move(samples)});
  };

  add(topics::kPresence, "ValvePresence",
      {presence(kA, 0xD8, true, 0xABCDEF, false, kBase + 1, "boom-left"),
       presence(kB, 0xF7, false, 0x000001, true, kAbove53, k64),
       presence(kC, 0xE0, true, 0xFFFFFF, false, 0xFFFFFFFFFFFFFFFFULL, "",
                "section-32-chars-abcdefghijklmno")});
  // Offline: the gateway disposes the instance; the sample carries its key only.
  add(topics::kPresence, "ValvePresence", {presence(kB, 0, false, 0, false, 0, "")}, true);
  // string<32>'s bound, the last role and state, a full-turn place.
  add(topics::kLocation, "ValveLocation",
      {location(
           {"left-master", "boom-left", 1, ROLE_MASTER, true, kA, LOCATION_OK, true, 0.0F, 360.0F}),
       location({"section-32-chars-abcdefghijklmno", k64, 9999, ROLE_OTHER, false, 0,
                 LOCATION_EMPTY, false, 0.0F, 0.0F}),
       location({"section-02", "boom-left", 3, ROLE_SECTION, true, 0xFFFFFF, LOCATION_MISSING, true,
                 12.5F, 90.0F})});
  add(topics::topic_name<ValveVersion>(), "ValveVersion",
      {version(kA, software(1, 2, 'e'), software(0, 9, '\0'), kBase + 2),
       version(kB, software(255, 0, 'z'), software(3, 14, 'a'), kAbove53 + 2)});
  add(topics::topic_name<teejet::ValvePosition>(), "ValvePosition",
      {position(kA, 12.3F, kBase + 3), position(kB, 359.9F, kBase + 4),
       position(kC, 0.0F, kAbove53 + 4), position(kA, 0.1F, kBase + 5)});
  add(topics::topic_name<ValveTemperature>(), "ValveTemperature",
      {temperature(kA, -40, 85, kBase + 6), temperature(kB, -127, -1, kBase + 7),
       temperature(kC, 127, 0, kAbove53 + 7)});
  add(topics::topic_name<ValveVoltage>(), "ValveVoltage",
      {voltage(kA, 12.6F, kBase + 8), voltage(kB, 16.5F, kBase + 9),
       voltage(kC, 9.7F, kBase + 10)});
  add(topics::topic_name<ValveCurrent>(), "ValveCurrent",
      {current(kA, 1.23F, 0.45F, kBase + 11), current(kB, 0.0F, 0.0F, kBase + 12),
       current(kC, 2.55F, 2.01F, kBase + 13)});
  add(topics::topic_name<ValveDegreesPerSecond>(), "ValveDegreesPerSecond",
      {dps(kA, 359, DIRECTION_OPEN, kBase + 14), dps(kB, 0, DIRECTION_CLOSE, kBase + 15),
       dps(kC, 90, DIRECTION_SHORTEST, kBase + 16)});
  add(topics::topic_name<ValveSpeedDirection>(), "ValveSpeedDirection",
      {speed(kA, 100, DIRECTION_CLOSE, ROTATION_CLOCKWISE, kBase + 17),
       speed(kB, 0, DIRECTION_OPEN, ROTATION_COUNTERCLOCKWISE, kBase + 18),
       speed(kC, 55, DIRECTION_OPEN, ROTATION_CLOCKWISE, kBase + 19)});
  add(topics::topic_name<ValveRunTime>(), "ValveRunTime",
      {run_time(kA, 4294967295U, kBase + 20), run_time(kB, 12345, kBase + 21),
       run_time(kC, 0, kBase + 22)});
  add(topics::topic_name<ValveCycleCounts>(), "ValveCycleCounts",
      {cycles(kA, 7, kBase + 23), cycles(kB, 123456, kBase + 24),
       cycles(kC, 3000000000U, kBase + 25)});
  add(topics::topic_name<ValveBaudRate>(), "ValveBaudRate",
      {baud(kA, 250000, kBase + 26), baud(kB, 500000, kBase + 27)});
  add(topics::kError, "ValveError",
      {error(kA, ERROR_HIGH_VOLTAGE, 16.9F, 16.5F, DIRECTION_CLOSE, kBase + 28),
       error(kA, ERROR_MIN_DEGREES_PER_SECOND, 3.0F, 12.5F, DIRECTION_OPEN, kBase + 29),
       error(kB, ERROR_HIGH_TEMPERATURE, 96.0F, 95.0F, DIRECTION_CLOSE, kBase + 30)});
  // Clear Errors: one disposal per (serial, kind), both keys set, the rest default.
  add(topics::kError, "ValveError",
      {error(kA, ERROR_HIGH_VOLTAGE, 0.0F, 0.0F, DIRECTION_CLOSE, 0),
       error(kA, ERROR_MIN_DEGREES_PER_SECOND, 0.0F, 0.0F, DIRECTION_CLOSE, 0)},
      true);
  add(topics::kCommand, "ValveCommand",
      {command({kA, 1, "boom-ecu", COMMAND_TARGET_DEGREES, 75, DIRECTION_SHORTEST, 123.4F, 0,
                TELEMETRY_VERSION, 0, 0}),
       command({kB, 4294967295U, k64, COMMAND_MILLISECONDS_TO_RUN, 100, DIRECTION_OPEN, 0.0F, 65535,
                TELEMETRY_VERSION, 0, 0}),
       command({kC, 3, "", COMMAND_REQUEST, 0, DIRECTION_CLOSE, 0.0F, 0, TELEMETRY_CYCLE_COUNTS,
                255, 0}),
       command({kA, 4, "valvectl", COMMAND_SET_BAUD_RATE, 0, DIRECTION_CLOSE, 0.0F, 0,
                TELEMETRY_VERSION, 0, 500000})});
  const std::string long_reason =
      "speed_percent 101 is out of range: allowed 0 .. 100 (0 stops the valve); and this "
      "reason goes on past sixty-four characters so that a reader cutting strings short shows";
  add(topics::kCommandStatus, "CommandStatus",
      {status(kA, 1, "boom-ecu", COMMAND_TARGET_DEGREES, COMMAND_ACCEPTED, "", kBase + 31),
       status(kA, 1, "boom-ecu", COMMAND_TARGET_DEGREES, COMMAND_COMPLETED, "", kBase + 32),
       status(kB, 2, k64, COMMAND_MANUAL, COMMAND_REJECTED, long_reason, kAbove53 + 32),
       status(kC, 3, "x", COMMAND_STOP, COMMAND_TIMED_OUT, "no reply in 2 s", kBase + 33),
       status(kC, 4, "x", COMMAND_STOP, COMMAND_SUPERSEDED, "", kBase + 34)});
  // Both kinds, a move, the longest names, both states.
  add(topics::kLayoutChange, "LayoutChange",
      {layout_change({"left-master", "boom-left", 7, "valvectl", LAYOUT_ASSIGN, kC}, false),
       layout_change(
           {"section-32-chars-abcdefghijklmno", k64, 4294967295U, k64, LAYOUT_ASSIGN, 0xFFFFFF},
           true),
       layout_change({"section-02", "boom-left", 8, "", LAYOUT_UNASSIGN, 0}, false)});
  add(topics::kLayoutChangeStatus, "LayoutChangeStatus",
      {layout_status({"left-master", "boom-left", 7, "valvectl", LAYOUT_ASSIGN, kC},
                     LAYOUT_CHANGE_APPLIED, "TJV000099 left it", kBase + 36),
       layout_status({"section-32-chars-abcdefghijklmno", k64, 4294967295U, k64, LAYOUT_ASSIGN, 0},
                     LAYOUT_CHANGE_REJECTED, long_reason, kAbove53 + 36),
       layout_status({"section-02", "boom-left", 8, "", LAYOUT_UNASSIGN, 0}, LAYOUT_CHANGE_APPLIED,
                     "", kBase + 37)});
  add(topics::kGatewayStatus, "GatewayStatus",
      {gateway_status({"boom-left",
                       "can0",
                       BUS_ERROR_ACTIVE,
                       0,
                       0,
                       kAbove53,
                       42,
                       0,
                       1,
                       24,
                       32,
                       kBase + 35,
                       8,
                       {100001, 100002, 0xFFFFFFFF},
                       6,
                       CLAIM_YIELDED,
                       0xD5,
                       0x2008800000000100ULL,
                       0x20088000000000FFULL,
                       3,
                       1,
                       {{0x26, 0xA00C81045A20021BULL, kBase + 30},
                        {0xE0, 0xFFFFFFFFFFFFFFFFULL, kAbove53 + 30}}}),
       gateway_status({k64,
                       "vcan31",
                       BUS_OFF,
                       65535,
                       255,
                       0,
                       0xFFFFFFFFFFFFFFFFULL,
                       7,
                       0,
                       0,
                       0,
                       kAbove53 + 35,
                       0xFFFFFFFF,
                       {},
                       0xFFFFFFFF,
                       CLAIM_OFF,
                       0,
                       0,
                       0,
                       0xFFFFFFFFFFFFFFFFULL,
                       0,
                       {}})});
  // Every data length 0..8, standard and extended identifiers, both directions.
  std::vector<Sample> frames;
  for (std::uint8_t length = 0; length <= 8; ++length) {
    std::vector<std::uint8_t> data;
    for (std::uint8_t i = 0; i < length; ++i) {
      data.push_back(static_cast<std::uint8_t>(0xF0 + i * 0x11 - length));
    }
    const bool extended = length % 2 == 0;
    frames.push_back(frame("boom-left", length < 4 ? "can0" : "vcan31",
                           extended ? 0x18EF00FFU + length : 0x7F0U + length, extended, data,
                           length % 3 == 0 ? FRAME_SENT : FRAME_RECEIVED, kAbove53 + 100 + length));
  }
  // A remote frame: a dlc of 4 and no data.
  frames.push_back(frame("boom-left", "can0", 0x123, false, {}, FRAME_RECEIVED, kAbove53 + 109, 4));
  add(topics::kBusFrame, "BusFrame", std::move(frames));
  return channels;
}

std::string read_idl() {
  std::ifstream in(TEEJET_VALVE_IDL, std::ios::binary);
  if (!in) {
    fail(std::string("cannot read the IDL ") + TEEJET_VALVE_IDL);
  }
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

struct Message {
  std::size_t channel;  // index into the channel list
  std::uint32_t sequence;
  std::uint64_t log_time, publish_time;
};

// Round robin over the channels, so that chunks hold several topics and each topic spans
// several chunks; log times rise by 1 ms per message, so file order is log time order.
std::vector<Message> interleave(const std::vector<ChannelSpec>& channels) {
  std::vector<Message> order;
  for (std::size_t round = 0;; ++round) {
    bool any = false;
    for (std::size_t c = 0; c < channels.size(); ++c) {
      if (round < channels[c].samples.size()) {
        const std::uint64_t log_time = kBase + 1'000'000ULL * (order.size() + 1);
        order.push_back(
            {c, static_cast<std::uint32_t>(round + 1), log_time, log_time - 250'000ULL - round});
        any = true;
      }
    }
    if (!any) {
      return order;
    }
  }
}

void write_file(const std::string& path, const std::string& compression, const std::string& idl,
                const std::vector<ChannelSpec>& channels, const std::vector<Message>& order) {
  auto writer = must(teejet::mcap::Writer::create(must(teejet::mcap::open_file_sink(path), path),
                                                  {.compression = compression, .chunk_size = 600}),
                     path);
  const Bytes idl_bytes(idl.begin(), idl.end());
  std::map<std::string, std::uint16_t> schema_ids;
  std::vector<std::uint16_t> channel_ids;
  for (const auto& channel : channels) {
    auto [it, added] = schema_ids.try_emplace(channel.schema, 0);
    if (added) {
      it->second = must(writer->add_schema(channel.schema, "omgidl", idl_bytes), path);
    }
    channel_ids.push_back(
        must(writer->add_channel(it->second, channel.topic, "cdr", channel.metadata), path));
  }
  for (const auto& m : order) {
    must(writer->write(channel_ids[m.channel], m.sequence, m.log_time, m.publish_time,
                       channels[m.channel].samples[m.sequence - 1].payload),
         path);
  }
  must(writer->finish(), path);
}

void write_text(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  if (!out.flush()) {
    fail("cannot write " + path);
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    fail("usage: write_known_recording OUT_DIR");
  }
  const std::string dir = argv[1];
  const std::string idl = read_idl();
  const auto channels = known_channels();
  const auto order = interleave(channels);

  for (const char* compression : {"zstd", "lz4", ""}) {
    const std::string name = *compression ? compression : "none";
    write_file(dir + "/known-" + name + ".mcap", compression, idl, channels, order);
  }
  json expected = json::array();
  for (const auto& m : order) {
    const auto& channel = channels[m.channel];
    expected.push_back({{"topic", channel.topic},
                        {"schema", channel.schema},
                        {"sequence", m.sequence},
                        {"log_time", u64(m.log_time)},
                        {"publish_time", u64(m.publish_time)},
                        {"data", channel.samples[m.sequence - 1].data}});
  }
  write_text(dir + "/known.json", expected.dump(1) + "\n");
  // Every topic of the contract, for the check that the known recording covers them all.
  write_text(dir + "/contract-topics.json",
             contract_topics(topics::EverySampleType{}).dump() + "\n");

  // A schema name that valve.idl does not define: the channel cannot be decoded.
  std::vector<ChannelSpec> unknown = {{topics::topic_name<teejet::ValvePosition>(),
                                       "teejet::NoSuchType",
                                       live(topics::topic_name<teejet::ValvePosition>()),
                                       {position(7, 1.5F, kBase)}}};
  write_file(dir + "/unknown-schema.mcap", "zstd", idl, unknown, interleave(unknown));

  // The second message stops after its serial: the float and the stamp are missing.
  std::vector<ChannelSpec> cut = {{topics::topic_name<teejet::ValvePosition>(),
                                   "teejet::ValvePosition",
                                   live(topics::topic_name<teejet::ValvePosition>()),
                                   {position(7, 1.5F, kBase), position(8, 2.5F, kBase)}}};
  cut[0].samples[1].payload.resize(4 + 4);
  write_file(dir + "/undecodable.mcap", "lz4", idl, cut, interleave(cut));
  return 0;
}
