#pragma once

// Chunk compression as MCAP names it: "" (none), "zstd" (a Zstandard frame), "lz4" (an LZ4
// frame). The libraries are Debian's libzstd and liblz4.

#include <span>
#include <string>

#include "teejet/core/result.hpp"
#include "teejet/mcap/records.hpp"

namespace teejet::mcap {

Result<Bytes> compress(const std::string& compression, std::span<const std::uint8_t> data);

// Refuses an unknown compression, damaged data and a result of any size but `uncompressed_size`.
Result<Bytes> decompress(const std::string& compression, std::span<const std::uint8_t> data,
                         std::uint64_t uncompressed_size);

}  // namespace teejet::mcap
