// valve-decode's whole input path: text in, one JSON object per line out, as
// tools/valve-decode/main.cpp does it (split at '\n', a trailing '\r' dropped, blank lines
// skipped; frame_json::decode_log_line), checked against the parser and the codec.
//
// Input: any bytes, read as the tool reads a file.
//
// Properties: every output line is one JSON object that nlohmann::json parses strictly, without
// a newline inside; it is either {"error","line"} with a non-empty reason, or {"t","iface","dir",
// "addr","msg","fields"} in that order with "t" the logged time, "addr" a valve address 216..247,
// "dir" a direction and "fields" an object. Valid UTF-8 lines are echoed verbatim in errors.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "fuzz_input.hpp"
#include "teejet/candump/log_line.hpp"
#include "teejet/codec/codec.hpp"
#include "teejet/frame_json/frame_json.hpp"

namespace {

using namespace teejet;
using Json = nlohmann::ordered_json;

// nlohmann's strict dump refuses exactly the invalid UTF-8 that valve-decode replaces.
bool valid_utf8(std::string_view text) {
  try {
    (void)Json(std::string(text)).dump();
    return true;
  } catch (const Json::type_error&) {
    return false;
  }
}

void check_line(std::string_view line) {
  const std::string out = frame_json::decode_log_line(line);
  // The oracle: what the line is, from the parser and the codec directly.
  const auto record = candump::parse_log_line(line);
  std::optional<codec::DecodedFrame> decoded;
  if (record) {
    if (auto frame = codec::decode(record->frame)) decoded = std::move(*frame);
  }
  const bool decoded_ok = decoded.has_value();
  const codec::Route route = decoded_ok ? decoded->route : codec::Route{};

  FUZZ_CHECK(out.find('\n') == std::string::npos, out);
  const auto json = Json::parse(out, nullptr, /*allow_exceptions=*/false);
  FUZZ_CHECK(!json.is_discarded(), "not JSON: " + out);
  FUZZ_CHECK(json.is_object(), out);
  if (!decoded_ok) {
    FUZZ_CHECK(json.size() == 2 && json.contains("error") && json.contains("line"), out);
    FUZZ_CHECK(json["error"].is_string() && !json["error"].get<std::string>().empty(), out);
    // Only invalid UTF-8 is replaced (U+FFFD); anything else comes back byte for byte.
    if (valid_utf8(line)) FUZZ_CHECK(json["line"].get<std::string>() == line, out);
    return;
  }
  std::string keys;
  for (const auto& item : json.items()) keys += item.key() + ",";
  FUZZ_CHECK(keys == "t,iface,dir,addr,msg,fields,", out);
  FUZZ_CHECK(json["t"].is_number(), out);
  // "t" is the logged time digit for digit, leading zeros of the seconds dropped.
  const auto t_text = out.substr(5, out.find(',') - 5);
  FUZZ_CHECK(t_text == frame_json::timestamp_json_number(record->seconds, record->microseconds),
             out);
  FUZZ_CHECK(json["iface"].is_string(), out);
  FUZZ_CHECK(json["dir"] == codec::to_string(route.flow), out);
  FUZZ_CHECK(json["addr"].is_number_unsigned() && json["addr"] == route.valve_address, out);
  FUZZ_CHECK(json["addr"] >= 216 && json["addr"] <= 247, out);
  FUZZ_CHECK(json["msg"].is_string() && !json["msg"].get<std::string>().empty(), out);
  FUZZ_CHECK(json["fields"].is_object(), out);
  for (const auto& field : json["fields"].items()) {
    FUZZ_CHECK(!field.value().is_null(), out);  // a NaN or infinity would print as null
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fuzz::Input input(data, size);
  std::string_view text = input.rest();
  while (!text.empty()) {
    const auto end = text.find('\n');
    std::string_view line = text.substr(0, end);
    text.remove_prefix(end == std::string_view::npos ? text.size() : end + 1);
    if (line.ends_with('\r')) line.remove_suffix(1);
    if (frame_json::is_blank_line(line)) continue;
    check_line(line);
  }
  return 0;
}
