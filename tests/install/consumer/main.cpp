// Uses only installed headers: the generated types, their type objects and the codec.
#include <teejet/valvePubSubTypes.h>
#include <teejet/valveTypeObject.h>

#include <fastdds/dds/topic/TypeSupport.hpp>
#include <iostream>
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
  teejet::ValvePosition position;
  position.serial(*teejet::codec::parse_serial("TJV123456"));
  position.degrees(123.4f);
  std::cout << teejet::codec::format_serial(position.serial()) << " " << position.degrees() << "\n";
  return 0;
}
