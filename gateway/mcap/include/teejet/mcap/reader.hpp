#pragma once

// Reads MCAP files: front to back (every message in file order, as a replay needs it), and the
// summary at the end (what --info shows, without reading the messages). Works on the bytes of a
// whole file; never reads outside them. A damaged file (wrong magic, a CRC that does not match,
// a record that does not parse, a message before its channel) is an Error naming the byte offset;
// a file that merely ends early (a recorder that was killed) reads up to its last complete
// record and says so.

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <span>
#include <string>

#include "teejet/core/result.hpp"
#include "teejet/mcap/records.hpp"

namespace teejet::mcap {

struct Contents {
  Header header;
  std::map<std::uint16_t, Schema> schemas;
  std::map<std::uint16_t, Channel> channels;
  std::uint64_t messages = 0;
  std::uint64_t chunks = 0;
  // Empty when the file is complete (Data End, summary, footer, magic); otherwise why it is not,
  // e.g. "the file ends inside a Chunk record at byte 81234 (not closed: the recorder stopped
  // early?)". Everything before that point was read.
  std::string incomplete;
};

using MessageVisitor = std::function<void(const Channel&, const Message&)>;

// Reads every message in file order; `visit` may be empty (a check of the whole file).
Result<Contents> read_messages(std::span<const std::uint8_t> file, const MessageVisitor& visit);

struct Summary {
  Statistics statistics;
  std::map<std::uint16_t, Schema> schemas;
  std::map<std::uint16_t, Channel> channels;
  std::vector<ChunkIndex> chunk_indexes;
};

// The summary section through the footer. nullopt when the file has no summary (it was not
// closed, or its writer wrote none): read_messages() still reads such a file.
Result<std::optional<Summary>> read_summary(std::span<const std::uint8_t> file);

// The whole file in memory; errors name the path.
Result<Bytes> load_file(const std::string& path);

}  // namespace teejet::mcap
