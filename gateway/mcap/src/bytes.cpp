#include "bytes.hpp"

#include <zlib.h>

namespace teejet::mcap {

void ByteBuilder::string_map(const std::map<std::string, std::string>& map) {
  Bytes entries;
  ByteBuilder builder(entries);
  for (const auto& [key, value] : map) {
    builder.string(key);
    builder.string(value);
  }
  bytes32(entries);
}

void ByteBuilder::u16_u64_map(const std::map<std::uint16_t, std::uint64_t>& map) {
  u32(static_cast<std::uint32_t>(map.size() * 10));
  for (const auto& [key, value] : map) {
    u16(key);
    u64(value);
  }
}

std::size_t ByteBuilder::begin_record(Opcode opcode) {
  u8(static_cast<std::uint8_t>(opcode));
  const std::size_t started = out_.size();
  u64(0);
  return started;
}

void ByteBuilder::end_record(std::size_t started) {
  const std::uint64_t length = out_.size() - started - 8;
  for (int i = 0; i < 8; ++i)
    out_[started + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(length >> (8 * i));
}

std::optional<std::map<std::string, std::string>> ByteReader::string_map() {
  const auto size = u32();
  if (!size) return std::nullopt;
  const auto entries = take(*size);
  if (!entries) return std::nullopt;
  ByteReader reader(*entries);
  std::map<std::string, std::string> map;
  while (reader.remaining() > 0) {
    auto key = reader.string();
    auto value = reader.string();
    if (!key || !value) return std::nullopt;
    map.emplace(std::move(*key), std::move(*value));
  }
  return map;
}

std::optional<std::map<std::uint16_t, std::uint64_t>> ByteReader::u16_u64_map() {
  const auto size = u32();
  if (!size) return std::nullopt;
  const auto entries = take(*size);
  if (!entries || entries->size() % 10 != 0) return std::nullopt;
  ByteReader reader(*entries);
  std::map<std::uint16_t, std::uint64_t> map;
  while (reader.remaining() > 0) {
    const auto key = reader.u16();
    const auto value = reader.u64();
    map.emplace(*key, *value);
  }
  return map;
}

std::uint32_t crc32(std::span<const std::uint8_t> bytes, std::uint32_t crc) {
  // zlib takes uInt lengths: feed very large spans in parts.
  uLong value = crc;
  while (!bytes.empty()) {
    const std::size_t part = std::min<std::size_t>(bytes.size(), 1u << 30);
    value = ::crc32(value, bytes.data(), static_cast<uInt>(part));
    bytes = bytes.subspan(part);
  }
  return static_cast<std::uint32_t>(value);
}

}  // namespace teejet::mcap
