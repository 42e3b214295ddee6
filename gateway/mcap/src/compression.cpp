#include "compression.hpp"

#include <lz4frame.h>
#include <zstd.h>

#include <memory>

namespace teejet::mcap {
namespace {

// Level 3 is zstd's default: ~6x on our samples at a fraction of a core for a full bus.
constexpr int kZstdLevel = 3;
// A reader allocates what a chunk claims to hold before decompressing it: a damaged size field
// must not ask for gigabytes (the fuzz target mcap_read found 4 GB). Writers chunk at about
// 1 MiB (ours, and the mcap libraries' defaults); 256 MiB leaves room for any sane writer.
constexpr std::uint64_t kLargestChunk = std::uint64_t{256} << 20;

Error damaged(const std::string& compression, const std::string& why) {
  return Error{ErrorCode::kInvalidValue, compression + " chunk data is damaged: " + why};
}

}  // namespace

Result<Bytes> compress(const std::string& compression, std::span<const std::uint8_t> data) {
  if (compression.empty()) return Bytes(data.begin(), data.end());
  if (compression == "zstd") {
    Bytes out(ZSTD_compressBound(data.size()));
    const std::size_t size =
        ZSTD_compress(out.data(), out.size(), data.data(), data.size(), kZstdLevel);
    if (ZSTD_isError(size)) return damaged(compression, ZSTD_getErrorName(size));
    out.resize(size);
    return out;
  }
  if (compression == "lz4") {
    Bytes out(LZ4F_compressFrameBound(data.size(), nullptr));
    const std::size_t size =
        LZ4F_compressFrame(out.data(), out.size(), data.data(), data.size(), nullptr);
    if (LZ4F_isError(size)) return damaged(compression, LZ4F_getErrorName(size));
    out.resize(size);
    return out;
  }
  return Error{ErrorCode::kInvalidValue,
               "unknown compression '" + compression + "' (known: zstd, lz4, none)"};
}

Result<Bytes> decompress(const std::string& compression, std::span<const std::uint8_t> data,
                         std::uint64_t uncompressed_size) {
  if (compression.empty()) {
    if (data.size() != uncompressed_size) {
      return damaged("uncompressed", "size " + std::to_string(data.size()) + " instead of " +
                                         std::to_string(uncompressed_size));
    }
    return Bytes(data.begin(), data.end());
  }
  if (compression != "zstd" && compression != "lz4") {
    return Error{ErrorCode::kInvalidValue, "unknown chunk compression '" + compression + "'"};
  }
  if (uncompressed_size > kLargestChunk) {
    return damaged(compression, "claims " + std::to_string(uncompressed_size) +
                                    " bytes uncompressed, more than the 256 MiB a chunk may hold");
  }
  if (compression == "zstd") {
    // A frame that states its size must state the chunk's, before anything is allocated.
    const unsigned long long stated = ZSTD_getFrameContentSize(data.data(), data.size());
    if (stated == ZSTD_CONTENTSIZE_ERROR) return damaged(compression, "not a zstd frame");
    if (stated != ZSTD_CONTENTSIZE_UNKNOWN && stated != uncompressed_size) {
      return damaged(compression, "the frame holds " + std::to_string(stated) +
                                      " bytes, the chunk says " +
                                      std::to_string(uncompressed_size));
    }
  }
  Bytes out(static_cast<std::size_t>(uncompressed_size));
  if (compression == "zstd") {
    const std::size_t size = ZSTD_decompress(out.data(), out.size(), data.data(), data.size());
    if (ZSTD_isError(size)) return damaged(compression, ZSTD_getErrorName(size));
    if (size != out.size()) return damaged(compression, "shorter than its uncompressed size");
    return out;
  }
  LZ4F_dctx* raw = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&raw, LZ4F_VERSION))) {
    return damaged(compression, "no decompression context");
  }
  const std::unique_ptr<LZ4F_dctx, decltype(&LZ4F_freeDecompressionContext)> context(
      raw, &LZ4F_freeDecompressionContext);
  std::size_t written = 0, read = 0;
  for (;;) {
    std::size_t out_size = out.size() - written;
    std::size_t in_size = data.size() - read;
    const std::size_t hint = LZ4F_decompress(context.get(), out.data() + written, &out_size,
                                             data.data() + read, &in_size, nullptr);
    if (LZ4F_isError(hint)) return damaged(compression, LZ4F_getErrorName(hint));
    written += out_size;
    read += in_size;
    if (hint == 0) break;  // the frame is complete
    if (in_size == 0 && out_size == 0) return damaged(compression, "the frame ends early");
  }
  if (written != out.size()) return damaged(compression, "shorter than its uncompressed size");
  return out;
}

}  // namespace teejet::mcap
