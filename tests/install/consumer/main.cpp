// Uses only installed headers: the generated types, their type objects, the codec and the DDS
// client library (its table and its command check; no participant, so no network).
#include <teejet/valvePubSubTypes.h>
#include <teejet/valveTypeObject.h>

#include <fastdds/dds/topic/TypeSupport.hpp>
#include <iostream>
#include <teejet/client/command_check.hpp>
#include <teejet/client/valve_table.hpp>
#include <teejet/codec/codec.hpp>

int main() {
  registervalveTypes();
  eprosima::fastdds::dds::TypeSupport presence(new teejet::ValvePresencePubSubType());
  if (presence.get_type_name() != "teejet::ValvePresence" || !presence->m_isGetKeyDefined) {
    std::cerr << "ValvePresence type support is wrong: " << presence.get_type_name() << "\n";
    return 1;
  }
  if (teejet::GetValvePresenceObject(true) == nullptr) {
    std::cerr << "no complete TypeObject for ValvePresence (fastddsgen -typeobject missing?)\n";
    return 1;
  }
  const auto serial = *teejet::codec::parse_serial("TJV123456");
  teejet::ValvePresence sample;
  sample.serial(serial);
  sample.online(true);
  teejet::client::ValveTable table;
  table.on_presence(sample);
  table.on_telemetry(serial, teejet::codec::Position{123.4}, 0);
  const auto row = table.row(serial);
  if (!row || !row->position_degrees()) {
    std::cerr << "the client's table lost the valve\n";
    return 1;
  }
  const auto refused = teejet::client::checked_command(teejet::codec::Manual{101, {}});
  if (refused) {
    std::cerr << "the client's command check let speed 101 through\n";
    return 1;
  }
  std::cout << teejet::codec::format_serial(row->serial) << " " << *row->position_degrees() << "\n";
  return 0;
}
