#pragma once

// The JSON every client prints the same way: a valve's row with its telemetry, a command status,
// and field values as the codec names them, as valvectl --json writes them and teejet-web serves
// them. Pure functions of the data, so the tests pin the format.

#include <nlohmann/json.hpp>
#include <optional>
#include <vector>

#include "teejet/client/valve_table.hpp"
#include "teejet/codec/codec.hpp"
#include "teejet/valve.h"

namespace teejet::client {

// {"serial":"TJV000001","address":216,"online":true,"boot_mode":false,"position":45.0,
//  "temperature_c":25,"volts":12.0,"errors":["high_voltage"],"gateway":"...","location":"",
//  "telemetry":{"position":{"degrees":45.0},"current":{"amps":0.35,...},...}}; missing values
// are null, "telemetry" holds the latest message of every subject the valve has sent.
nlohmann::json to_json(const ValveRow& row);
nlohmann::json to_json(const std::vector<ValveRow>& rows);

// {"order":1,"location":"left-master","role":"master","serial":"TJV000101","state":"ok",
//  "gateway":"...","closed_deg":0.0,"opened_deg":360.0}: a place of a gateway's layout; state
// "unknown" once its gateway vanished; missing values are null.
nlohmann::json to_json(const LocationRow& place);

// {"event":"status","serial":"TJV000002","command_id":17,"origin":"...","kind":"target_degrees",
//  "state":"accepted","reason":"","stamp_ns":...}
nlohmann::json status_json(const CommandStatus& status);
// {"event":"layout_change","location":"section-03","gateway":"...","kind":"assign",
//  "state":"applied","serial":"TJV000007","reason":"","change_id":4,"origin":"..."}; "serial"
// is where the place stands after the change (null: empty).
nlohmann::json status_json(const LayoutChangeStatus& status);

// An ISO 11783-5 NAME: {"name":"0x2008800000000000","identity_number":0,...} with every field
// of isobus::name_fields() by its name.
nlohmann::json name_json(std::uint64_t name);
// A gateway's address claim: {"state":"claimed","address":"0xD5","name":{...},"holder":null or
// {...},"violations":0,"claims_in_valve_range":0,"neighbours":[{"address":"0x26",
// "name":{...},"last_seen_ns":...}, ...]}.
nlohmann::json claim_json(const GatewaySummary& gateway);

// A message's fields by the codec's names, {"volts":12.1}; {} for a message without fields.
nlohmann::json fields_json(const codec::FromValveMessage& message);

// A field value as JSON, and what JSON gives for one (a number, a word, true or false); nullopt
// for arrays, objects and null, which no field takes.
nlohmann::json to_json(const codec::FieldValue& value);
std::optional<codec::FieldValue> field_value_of(const nlohmann::json& value);

}  // namespace teejet::client
