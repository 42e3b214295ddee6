#pragma once

// Shared by the fuzz targets: reading typed values off the front of libFuzzer's input, and
// stopping with a message when a property does not hold.

#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <iterator>
#include <limits>
#include <string>
#include <string_view>
#include <type_traits>

namespace teejet::fuzz {

// A property failed: print why and abort, which libFuzzer records as a crash with its input.
[[noreturn]] inline void fail(const char* file, int line, const std::string& what) {
  std::fprintf(stderr, "%s:%d: property violated: %s\n", file, line, what.c_str());
  std::fflush(stderr);
  std::abort();
}

// NDEBUG does not switch it off: the fuzz build is RelWithDebInfo.
#define FUZZ_CHECK(condition, what)                                                      \
  do {                                                                                   \
    if (!(condition))                                                                    \
      ::teejet::fuzz::fail(__FILE__, __LINE__, "(" #condition ") " + std::string(what)); \
  } while (false)

// Values are taken from the front, little-endian, so that a seed file can be written by hand
// (tests/fuzz/README.md). Once the input is used up every value reads as zero: each input is a
// complete test case, however short.
class Input {
  template <class T>
  struct IntegerOf : std::type_identity<T> {};
  template <class T>
  requires std::is_enum_v<T>
  struct IntegerOf<T> : std::underlying_type<T> {
  };
  template <class T>
  using Integer = typename IntegerOf<T>::type;

 public:
  Input(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}

  template <class T>
  T take() {
    static_assert(std::is_integral_v<T> || std::is_enum_v<T>);
    if constexpr (std::is_same_v<T, bool>) {
      return (byte() & 1) != 0;
    } else {
      std::make_unsigned_t<Integer<T>> value = 0;
      for (std::size_t i = 0; i < sizeof(T); ++i) {
        value =
            static_cast<decltype(value)>(value | static_cast<decltype(value)>(byte()) << (8 * i));
      }
      return static_cast<T>(value);
    }
  }

  // A mode byte first, so that the fuzzer reaches the interesting doubles without guessing bit
  // patterns: 0 raw bits (NaN, infinities, huge), 1 tenths, 2 hundredths, 3 a whole signed number,
  // else the special values.
  double take_double() {
    switch (byte() % 5) {
      case 0:
        return std::bit_cast<double>(take<std::uint64_t>());
      case 1:
        return take<std::uint16_t>() / 10.0;
      case 2:
        return take<std::uint16_t>() / 100.0;
      case 3:
        return static_cast<double>(take<std::int32_t>());
      default:
        break;
    }
    constexpr double kSpecial[] = {std::numeric_limits<double>::quiet_NaN(),
                                   std::numeric_limits<double>::infinity(),
                                   -std::numeric_limits<double>::infinity(),
                                   std::numeric_limits<double>::max(),
                                   std::numeric_limits<double>::lowest(),
                                   std::numeric_limits<double>::denorm_min(),
                                   -0.0,
                                   -0.05,
                                   359.95,
                                   359.94999999999999,
                                   655.355,
                                   16.55,
                                   4294967296.0};
    return kSpecial[byte() % std::size(kSpecial)];
  }

  float take_float() {
    if (byte() % 2 == 0) return std::bit_cast<float>(take<std::uint32_t>());
    return static_cast<float>(take_double());
  }

  // A length byte, then that many bytes (fewer when the input ends).
  std::string take_string() {
    const std::size_t length = byte();
    std::string text;
    while (text.size() < length && !empty()) text += static_cast<char>(byte());
    return text;
  }

  std::string_view rest() {
    const std::string_view text(reinterpret_cast<const char*>(data_), size_);
    size_ = 0;
    return text;
  }

  bool empty() const { return size_ == 0; }

 private:
  std::uint8_t byte() {
    if (size_ == 0) return 0;
    --size_;
    return *data_++;
  }

  const std::uint8_t* data_;
  std::size_t size_;
};

}  // namespace teejet::fuzz
