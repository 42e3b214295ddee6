// The MCAP reader (tools/mcap) on arbitrary bytes: what teejet-replay, valve-decode and
// teejet-record --info open, from disks that fill up, recorders that are killed and files
// people send each other.
//
// Input: the bytes of a file. Seeds: small recordings of our writer, one per compression, and
// one cut short.
//
// Properties: no crash, leak or sanitizer report whatever the bytes; an error always has a
// reason; every message handed out is on a channel the file defined, and the count the reader
// reports is the number it handed out; the summary reader likewise never crashes.

#include <cstddef>
#include <cstdint>
#include <span>

#include "fuzz_input.hpp"
#include "teejet/mcap/reader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace teejet::mcap;
  const std::span<const std::uint8_t> file(data, size);
  std::uint64_t visited = 0;
  auto contents = read_messages(file, [&](const Channel& channel, const Message& message) {
    FUZZ_CHECK(channel.id == message.channel_id, "a message handed out with another channel");
    ++visited;
  });
  if (contents) {
    FUZZ_CHECK(contents->messages == visited, "the count differs from the messages handed out");
    for (const auto& [id, channel] : contents->channels) {
      FUZZ_CHECK(channel.schema_id == 0 || contents->schemas.count(channel.schema_id),
                 "a channel whose schema was never defined");
    }
  } else {
    FUZZ_CHECK(!contents.error().reason.empty(), "an error without a reason");
  }
  auto summary = read_summary(file);
  if (!summary) FUZZ_CHECK(!summary.error().reason.empty(), "an error without a reason");
  return 0;
}
