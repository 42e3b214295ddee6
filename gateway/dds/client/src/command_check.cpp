#include "teejet/client/command_check.hpp"

#include "teejet/codec/can_id.hpp"
#include "teejet/codec/table.hpp"
#include "teejet/dds/conversions.hpp"

namespace teejet::client {

Result<codec::ToValveMessage> with_fields(codec::ToValveMessage message,
                                          const FieldValues& fields) {
  for (const auto& [name, value] : fields) {
    if (auto set = codec::set_field(message, name, value); !set) return set.error();
  }
  return message;
}

Result<ValveCommand> checked_command(const codec::ToValveMessage& message) {
  // Any valve address will do: the range rules do not depend on it.
  const auto frame = codec::encode(codec::kFirstValveAddress, message);
  if (!frame) return frame.error();
  return dds::to_command(message);
}

}  // namespace teejet::client
