#pragma once

// valve-decode's second input: the teejet/can/frame channel of an MCAP recording
// (teejet-record, with teejet-gateway --record-frames), printed line for line as the same frames
// read from candump -L.

#include <cstdint>
#include <ostream>
#include <span>
#include <string>
#include <string_view>

#include "teejet/mcap/reader.hpp"

namespace teejet::valve_decode {

// What std::getline reads first from an MCAP file: its 8-byte magic \x89MCAP0\r\n ends with the
// newline. Detecting by the first line lets a pipe (valve-decode <(...)) be read once, front to
// back, whatever it turns out to hold.
inline constexpr std::string_view kMcapFirstLine{"\x89MCAP0\r", 7};

// Prints one line per message of every channel whose schema is teejet::BusFrame, in file order;
// other channels are skipped. Says on `err` ("valve-decode: <path>: ...") what was wrong with the
// file. Returns false for a file that could not be decoded: damaged (the reader's reason; nothing
// is printed), or without a frame channel. A file that ends early (a recorder that was killed)
// is decoded up to there with a warning, and returns true.
bool decode_mcap(mcap::Source& file, const std::string& path, std::ostream& out, std::ostream& err);
bool decode_mcap(std::span<const std::uint8_t> file, const std::string& path, std::ostream& out,
                 std::ostream& err);

}  // namespace teejet::valve_decode
