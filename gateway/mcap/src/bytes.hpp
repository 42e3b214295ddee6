#pragma once

// Little-endian building and reading of MCAP record fields. The reader never reads past its
// span: every take reports whether the bytes were there, and a short field is a malformed file,
// never a crash.

#include <cstdint>
#include <cstring>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "teejet/mcap/records.hpp"

namespace teejet::mcap {

class ByteBuilder {
 public:
  explicit ByteBuilder(Bytes& out) : out_(out) {}

  void u8(std::uint8_t value) { out_.push_back(value); }
  void u16(std::uint16_t value) { little_endian(value, 2); }
  void u32(std::uint32_t value) { little_endian(value, 4); }
  void u64(std::uint64_t value) { little_endian(value, 8); }
  void raw(std::span<const std::uint8_t> bytes) {
    out_.insert(out_.end(), bytes.begin(), bytes.end());
  }
  void string(std::string_view text) {
    u32(static_cast<std::uint32_t>(text.size()));
    out_.insert(out_.end(), text.begin(), text.end());
  }
  void bytes32(std::span<const std::uint8_t> bytes) {
    u32(static_cast<std::uint32_t>(bytes.size()));
    raw(bytes);
  }
  void string_map(const std::map<std::string, std::string>& map);
  void u16_u64_map(const std::map<std::uint16_t, std::uint64_t>& map);

  // Starts a record: opcode and a length placeholder; end_record() fills the length in.
  std::size_t begin_record(Opcode opcode);
  void end_record(std::size_t started);

  std::size_t size() const { return out_.size(); }

 private:
  void little_endian(std::uint64_t value, int count) {
    for (int i = 0; i < count; ++i) out_.push_back(static_cast<std::uint8_t>(value >> (8 * i)));
  }
  Bytes& out_;
};

class ByteReader {
 public:
  explicit ByteReader(std::span<const std::uint8_t> bytes) : bytes_(bytes) {}

  std::optional<std::uint8_t> u8() { return fixed<std::uint8_t>(1); }
  std::optional<std::uint16_t> u16() { return fixed<std::uint16_t>(2); }
  std::optional<std::uint32_t> u32() { return fixed<std::uint32_t>(4); }
  std::optional<std::uint64_t> u64() { return fixed<std::uint64_t>(8); }
  std::optional<std::span<const std::uint8_t>> take(std::uint64_t count) {
    if (count > remaining()) return std::nullopt;
    auto part = bytes_.subspan(at_, static_cast<std::size_t>(count));
    at_ += static_cast<std::size_t>(count);
    return part;
  }
  std::optional<std::string> string() {
    const auto size = u32();
    if (!size) return std::nullopt;
    const auto text = take(*size);
    if (!text) return std::nullopt;
    return std::string(text->begin(), text->end());
  }
  std::optional<Bytes> bytes32() {
    const auto size = u32();
    if (!size) return std::nullopt;
    const auto part = take(*size);
    if (!part) return std::nullopt;
    return Bytes(part->begin(), part->end());
  }
  std::optional<std::map<std::string, std::string>> string_map();
  std::optional<std::map<std::uint16_t, std::uint64_t>> u16_u64_map();

  std::size_t position() const { return at_; }
  std::size_t remaining() const { return bytes_.size() - at_; }

 private:
  template <class Value>
  std::optional<Value> fixed(int count) {
    if (remaining() < static_cast<std::size_t>(count)) return std::nullopt;
    std::uint64_t value = 0;
    for (int i = 0; i < count; ++i)
      value |= std::uint64_t{bytes_[at_ + static_cast<std::size_t>(i)]} << (8 * i);
    at_ += static_cast<std::size_t>(count);
    return static_cast<Value>(value);
  }
  std::span<const std::uint8_t> bytes_;
  std::size_t at_ = 0;
};

// CRC-32 (ISO-HDLC, zlib's crc32), continuing from `crc` (0 to start).
std::uint32_t crc32(std::span<const std::uint8_t> bytes, std::uint32_t crc = 0);

}  // namespace teejet::mcap
