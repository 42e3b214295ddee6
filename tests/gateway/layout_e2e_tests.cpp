// Where each valve sits, as an ECU that joins late sees it on DDS: every place of the gateway's
// layout with its serial and state, and each valve's presence naming its place.

#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "gateway_fixture.hpp"
#include "support/dds_peer.hpp"
#include "support/scratch_dir.hpp"
#include "support/subprocess.hpp"
#include "teejet/layout/layout_file.hpp"

namespace teejet::gateway {
namespace {

using namespace std::chrono_literals;
using fixture::make_gateway;
using fixture::sim_config;
using fixture::start_and_wait_online;
using teejet::testing::DdsPeer;
using teejet::testing::eventually;
using teejet::testing::latest_by;
using teejet::testing::latest_by_serial;

// Six places for six simulated valves (TJV000001..6): five hold 1..5, the sixth a serial that
// is not on the bus; TJV000006 sits nowhere.
layout::Layout six_places() {
  std::vector<layout::Location> places;
  for (unsigned i = 1; i <= 5; ++i) {
    places.push_back({.name = "section-0" + std::to_string(i), .order = i + 1, .serial = i});
  }
  places.push_back({.name = "left-master",
                    .order = 1,
                    .role = layout::Role::kMaster,
                    .serial = 99,
                    .mechanics = layout::Mechanics{0, 360}});
  return *layout::Layout::make(places, layout::Mechanics{0, 90});
}

// An ECU of the test's own that follows where each valve sits.
struct PlaceWatcher {
  PlaceWatcher(int domain, const std::string& name)
      : peer(domain, name),
        locations(peer.reader<ValveLocation>()),
        presence(peer.reader<ValvePresence>()) {}
  bool ready() const { return locations != nullptr && presence != nullptr; }
  DdsPeer peer;
  eprosima::fastdds::dds::DataReader* locations;
  eprosima::fastdds::dds::DataReader* presence;
};

// The gateway of `config` with its layout in `file`, written first, started with its valves
// online. Call it with ASSERT_NO_FATAL_FAILURE.
void start_with_layout_file(GatewayConfig config, const std::string& file,
                            const layout::Layout& layout, std::unique_ptr<Gateway>& gateway) {
  ASSERT_TRUE(layout::save_layout_file(file, layout));
  config.layout_file = file;
  ASSERT_TRUE(read_layout_file(config));
  gateway = make_gateway(config);
  const auto valves = simulated_valve_count(config.can);
  ASSERT_TRUE(valves && *valves);
  ASSERT_NO_FATAL_FAILURE(start_and_wait_online(*gateway, static_cast<std::size_t>(**valves)));
}

TEST(LayoutEndToEnd, ALateEcuResolvesEveryPlaceAndSeesWhichAreMissing) {
  auto config = sim_config("gw-layout", 6);
  config.bridge.layout = six_places();
  auto gateway = make_gateway(config);
  ASSERT_NO_FATAL_FAILURE(start_and_wait_online(*gateway, 6));

  PlaceWatcher ecu(config.domain, "late-ecu");
  ASSERT_TRUE(ecu.ready());
  auto* locations = ecu.locations;
  auto* presence = ecu.presence;
  std::map<std::string, ValveLocation> places;
  const auto settled = [&] {
    latest_by(locations, places,
              [](const ValveLocation& place) { return place.location().to_string(); });
    if (places.size() != 6) return false;
    for (unsigned i = 1; i <= 5; ++i) {
      if (places["section-0" + std::to_string(i)].state() != LOCATION_OK) return false;
    }
    return true;
  };
  ASSERT_TRUE(eventually(settled, 15s)) << places.size() << " places seen";
  const auto& master = places.at("left-master");
  EXPECT_EQ(master.state(), LOCATION_MISSING);
  EXPECT_EQ(master.serial(), 99u);
  EXPECT_EQ(master.role(), ROLE_MASTER);
  EXPECT_EQ(master.order(), 1u);
  EXPECT_EQ(master.opened_degrees(), 360.0f);
  EXPECT_EQ(master.gateway().to_string(), "gw-layout");
  EXPECT_EQ(places.at("section-03").serial(), 3u);
  EXPECT_EQ(places.at("section-03").order(), 4u);

  std::map<std::uint32_t, ValvePresence> valves;
  ASSERT_TRUE(eventually([&] { return latest_by_serial(presence, valves).size() == 6; }, 15s));
  EXPECT_EQ(valves.at(3).location().to_string(), "section-03");
  EXPECT_EQ(valves.at(6).location().to_string(), "");  // online, in no place

  // The same through valvectl, as the person at the machine reads it.
  teejet::testing::Subprocess valvectl(
      {VALVECTL_PATH, "--domain", std::to_string(config.domain), "--json", "layout"});
  const auto listed = valvectl.wait(30s);
  ASSERT_EQ(listed.exit_code, 0) << listed.out << listed.err;
  const auto json = nlohmann::json::parse(listed.out);
  std::vector<std::string> order;
  for (const auto& row : json["locations"]) order.push_back(row["location"]);
  EXPECT_EQ(order, (std::vector<std::string>{"left-master", "section-01", "section-02",
                                             "section-03", "section-04", "section-05"}));
  EXPECT_EQ(json["locations"][0]["state"], "missing");
  EXPECT_EQ(json["locations"][0]["serial"], "TJV000099");
  EXPECT_EQ(json["locations"][3]["state"], "ok");
  EXPECT_EQ(json["locations"][3]["serial"], "TJV000003");
  EXPECT_EQ(json["locations"][3]["address"], 0xDA);
  EXPECT_EQ(json["unassigned"].dump(), R"(["TJV000006"])");
  gateway->stop();
}

// valvectl run to its end; its exit status and what it printed.
teejet::testing::Finished valvectl(int domain, std::vector<std::string> arguments);

TEST(LayoutEndToEnd, APlaceNamesItsValveWhereverASerialWouldAndIdentifyJogsItBack) {
  auto config = sim_config("gw-layout", 6);
  config.bridge.layout = six_places();
  auto gateway = make_gateway(config);
  ASSERT_NO_FATAL_FAILURE(start_and_wait_online(*gateway, 6));
  const int domain = config.domain;

  // 0..90 by the layout's default: 120 is clamped, and the completion says so.
  const auto moved = valvectl(domain, {"move", "section-01", "--to", "120", "--wait"});
  EXPECT_EQ(moved.exit_code, 0) << describe(moved);
  EXPECT_NE(moved.out.find("TJV000001 target_degrees #"), std::string::npos) << moved.out;
  EXPECT_NE(moved.out.find(": COMPLETED: stopped at 90.0, the Opened Degrees of section-01 "
                           "(asked 120.0)\n"),
            std::string::npos)
      << moved.out;

  const auto identified = valvectl(domain, {"identify", "section-03"});
  EXPECT_EQ(identified.exit_code, 0) << describe(identified);
  std::size_t completed = 0;
  for (std::size_t at = 0; (at = identified.out.find(": COMPLETED", at)) != std::string::npos;
       ++at) {
    ++completed;
  }
  EXPECT_EQ(completed, 4u) << identified.out;  // two jogs out and back
  EXPECT_NE(identified.out.find("TJV000003 at section-03: identified, back at 0.0\n"),
            std::string::npos)
      << identified.out;

  const auto missing = valvectl(domain, {"stop", "left-master"});
  EXPECT_EQ(missing.exit_code, 2) << describe(missing);
  EXPECT_NE(missing.err.find("TJV000099"), std::string::npos) << missing.err;
  const auto typo = valvectl(domain, {"stop", "Section-01"});
  EXPECT_EQ(typo.exit_code, 64) << describe(typo);
  gateway->stop();
}

teejet::testing::Finished valvectl(int domain, std::vector<std::string> arguments) {
  arguments.insert(arguments.begin(), {VALVECTL_PATH, "--domain", std::to_string(domain)});
  teejet::testing::Subprocess run(arguments);
  return run.wait(60s);
}

TEST(LayoutEndToEnd, AReplacementIsAssignedOverDdsSavedAndKeptAcrossARestart) {
  teejet::testing::ScratchDir dir;
  const std::string file = dir / "boom.yaml";
  const auto config = sim_config("gw-layout", 6);
  std::unique_ptr<Gateway> gateway;
  ASSERT_NO_FATAL_FAILURE(start_with_layout_file(config, file, six_places(), gateway));
  PlaceWatcher ecu(config.domain, "boom-ecu");
  ASSERT_TRUE(ecu.ready());
  auto* locations = ecu.locations;
  std::map<std::string, ValveLocation> places;
  const auto place = [&](const std::string& name) {
    latest_by(locations, places,
              [](const ValveLocation& sample) { return sample.location().to_string(); });
    return places[name];
  };
  ASSERT_TRUE(eventually([&] { return place("left-master").state() == LOCATION_MISSING; }, 15s));

  // The master valve TJV000099 was replaced by TJV000006, which sits nowhere yet.
  const auto assigned = valvectl(config.domain, {"assign", "left-master", "TJV000006"});
  EXPECT_EQ(assigned.exit_code, 0) << describe(assigned);
  EXPECT_EQ(assigned.out,
            "left-master on gw-layout: APPLIED: TJV000006 sits there (TJV000099 left "
            "it)\n");
  ASSERT_TRUE(eventually([&] { return place("left-master").state() == LOCATION_OK; }, 15s));
  EXPECT_EQ(place("left-master").serial(), 6u);
  const auto saved = layout::load_layout_file(file);
  ASSERT_TRUE(saved);
  EXPECT_EQ(saved->find("left-master")->serial, 6u);
  EXPECT_EQ(saved->find("left-master")->mechanics, (layout::Mechanics{0, 360}));

  // Refusals say why, and change nothing.
  const auto taken = valvectl(config.domain, {"assign", "section-01", "TJV000003"});
  EXPECT_EQ(taken.exit_code, 3) << describe(taken);
  EXPECT_EQ(taken.out,
            "section-01 on gw-layout: REJECTED: TJV000003 sits at section-03; unassign "
            "it there first, or move it\n");
  const auto absent = valvectl(config.domain, {"assign", "section-02", "TJV000042"});
  EXPECT_EQ(absent.exit_code, 3) << describe(absent);
  EXPECT_NE(absent.out.find("REJECTED: TJV000042 is not online on sim:6 (gateway gw-layout)"),
            std::string::npos)
      << absent.out;
  const auto unknown = valvectl(config.domain, {"unassign", "section-09"});
  EXPECT_EQ(unknown.exit_code, 2) << describe(unknown);
  EXPECT_NE(unknown.err.find("no gateway on domain " + std::to_string(config.domain) +
                             " has a location 'section-09' in its layout"),
            std::string::npos)
      << unknown.err;
  EXPECT_EQ(layout::load_layout_file(file)->find("section-01")->serial, 1u);

  // A restart reads the file it wrote.
  gateway->stop();
  gateway.reset();
  auto again = sim_config("gw-layout", 6);
  again.domain = config.domain;
  again.layout_file = file;
  ASSERT_TRUE(read_layout_file(again));
  EXPECT_EQ(again.bridge.layout.find("left-master")->serial, 6u);
  gateway = make_gateway(again);
  ASSERT_NO_FATAL_FAILURE(start_and_wait_online(*gateway, 6));
  const auto listed = valvectl(config.domain, {"--json", "layout"});
  ASSERT_EQ(listed.exit_code, 0) << describe(listed);
  const auto json = nlohmann::json::parse(listed.out);
  EXPECT_EQ(json["locations"][0]["location"], "left-master");
  EXPECT_EQ(json["locations"][0]["serial"], "TJV000006");
  EXPECT_EQ(json["locations"][0]["state"], "ok");
  EXPECT_EQ(json["unassigned"].dump(), "[]");
  gateway->stop();
}

TEST(LayoutEndToEnd, AnEcuSeesAReplacementAsItHappensAndAnAssignmentPutsTheNewValveInPlace) {
  teejet::testing::ScratchDir dir;
  const std::string file = dir / "boom.yaml";
  std::vector<layout::Location> places;
  for (unsigned i = 1; i <= 6; ++i) {
    places.push_back({.name = "section-0" + std::to_string(i), .order = i, .serial = 100 + i});
  }
  auto config = sim_config("gw-boom", 6);
  config.sim_serials = {101, 102, 103, 104, 105, 106};
  std::unique_ptr<Gateway> gateway;
  ASSERT_NO_FATAL_FAILURE(
      start_with_layout_file(config, file, *layout::Layout::make(places), gateway));
  PlaceWatcher ecu(config.domain, "boom-ecu");
  ASSERT_TRUE(ecu.ready());
  auto* locations = ecu.locations;
  auto* presence = ecu.presence;
  std::map<std::string, ValveLocation> seen;
  std::map<std::uint32_t, ValvePresence> valves;
  const auto place = [&] {
    latest_by(locations, seen,
              [](const ValveLocation& sample) { return sample.location().to_string(); });
    // Before the first sample, none: a default ValveLocation would read LOCATION_OK.
    return seen.contains("section-03") ? seen.at("section-03") : ValveLocation{};
  };
  const auto holds = [&](std::uint32_t serial, LocationState state) {
    const auto now = place();
    return now.serial() == serial && now.state() == state;
  };
  ASSERT_TRUE(eventually([&] { return holds(103, LOCATION_OK); }, 15s));

  // The valve at section-03 is taken off and another, TJV000203, fitted in its place.
  ASSERT_TRUE(gateway->simulator()->replace_valve(103, 203));
  ASSERT_TRUE(eventually([&] { return holds(103, LOCATION_MISSING); }, 15s));
  ASSERT_TRUE(eventually(
      [&] {
        latest_by_serial(presence, valves);
        return valves.contains(203) && valves.at(203).online();
      },
      15s));
  EXPECT_EQ(valves.at(203).location().to_string(), "");

  const auto assigned = valvectl(config.domain, {"assign", "section-03", "TJV000203"});
  EXPECT_EQ(assigned.exit_code, 0) << describe(assigned);
  EXPECT_EQ(assigned.out,
            "section-03 on gw-boom: APPLIED: TJV000203 sits there (TJV000103 left it)\n");
  ASSERT_TRUE(eventually([&] { return holds(203, LOCATION_OK); }, 15s));
  ASSERT_TRUE(eventually(
      [&] { return latest_by_serial(presence, valves).at(203).location() == "section-03"; }, 15s));
  gateway->stop();
}

TEST(LayoutEndToEnd, ANameTwoGatewaysClaimIsReportedByBoth) {
  // Both gateways log through the process's default logger; the test reads it too.
  std::ostringstream log;
  auto sink = std::make_shared<spdlog::sinks::ostream_sink_mt>(log);
  spdlog::default_logger()->sinks().push_back(sink);
  const auto logged = [&] {
    sink->flush();
    return log.str();
  };
  auto left = sim_config("boom-left", 2);
  left.bridge.layout = *layout::Layout::make(
      {{.name = "section-01", .order = 1, .serial = 1}, {.name = "left-end", .order = 2}});
  auto right = sim_config("boom-right", 2, 101);
  right.domain = left.domain;
  right.bridge.layout = *layout::Layout::make({{.name = "section-01", .order = 1, .serial = 101}});
  auto a = make_gateway(left);
  auto b = make_gateway(right);
  ASSERT_NO_FATAL_FAILURE(start_and_wait_online(*a, 2));
  ASSERT_NO_FATAL_FAILURE(start_and_wait_online(*b, 2));
  const std::string by_right =
      "location section-01 of this gateway's layout is claimed by gateway boom-right too";
  const std::string by_left =
      "location section-01 of this gateway's layout is claimed by gateway boom-left too";
  EXPECT_TRUE(eventually(
      [&] {
        const auto text = logged();
        return text.find(by_right) != std::string::npos && text.find(by_left) != std::string::npos;
      },
      15s))
      << logged();
  EXPECT_EQ(logged().find("left-end of this gateway"), std::string::npos);

  // valvectl refuses to guess which valve the name means.
  const auto stopped = valvectl(left.domain, {"stop", "section-01"});
  EXPECT_EQ(stopped.exit_code, 3) << describe(stopped);
  EXPECT_NE(stopped.err.find("location 'section-01' is in the layouts of 2 gateways (boom-left, "
                             "boom-right)"),
            std::string::npos)
      << stopped.err;
  a->stop();
  b->stop();
  auto& sinks = spdlog::default_logger()->sinks();
  sinks.erase(std::remove(sinks.begin(), sinks.end(), sink), sinks.end());
}

}  // namespace
}  // namespace teejet::gateway
