#pragma once
/// \file
/// Little-endian bytes, LEB128 varints and IEEE doubles for the native format: an appending
/// writer and a bounds-checked reader for untrusted input. Not API.

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <utility>

namespace csgtile::kernel::detail {

inline std::uint64_t double_bits(double v) {
  std::uint64_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  return bits;
}

inline double bits_double(std::uint64_t bits) {
  double v;
  std::memcpy(&v, &bits, sizeof v);
  return v;
}

/// Appends to a string.
class ByteWriter {
 public:
  void byte(std::uint8_t v) { out_.push_back(static_cast<char>(v)); }
  void varint(std::uint64_t v) {
    while (v >= 0x80) {
      byte(static_cast<std::uint8_t>(v | 0x80));
      v >>= 7;
    }
    byte(static_cast<std::uint8_t>(v));
  }
  void u32le(std::uint32_t v) {
    for (int i = 0; i < 4; ++i) byte(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  void f64le(double v) {
    const std::uint64_t bits = double_bits(v);
    for (int i = 0; i < 8; ++i) byte(static_cast<std::uint8_t>(bits >> (8 * i)));
  }
  void bytes(std::string_view v) { out_.append(v); }

  const std::string& str() const { return out_; }
  std::string take() { return std::move(out_); }

 private:
  std::string out_;
};

/// Reads untrusted bytes. The first failure is sticky: afterwards every read returns 0 and
/// remaining() is 0, so loops driven by counts end at once; callers check failed() before
/// using a value as a subscript. `base` is the offset of the view in the file (messages).
class ByteReader {
 public:
  ByteReader(std::string_view bytes, std::size_t base) : bytes_(bytes), base_(base) {}

  bool failed() const { return failed_; }
  const std::string& error() const { return error_; }
  std::size_t remaining() const { return failed_ ? 0 : bytes_.size() - pos_; }
  bool at_end() const { return !failed_ && pos_ == bytes_.size(); }
  std::size_t offset() const { return base_ + pos_; }

  /// Records the first failure with the file offset where it was found.
  void fail(const std::string& message) {
    if (failed_) return;
    failed_ = true;
    error_ = message + " (at byte " + std::to_string(offset()) + ")";
  }

  std::uint8_t byte() {
    if (remaining() < 1) {
      fail("truncated");
      return 0;
    }
    return static_cast<std::uint8_t>(bytes_[pos_++]);
  }

  /// LEB128, at most 10 bytes; values above 2^64 − 1 are refused.
  std::uint64_t varint() {
    std::uint64_t v = 0;
    for (unsigned shift = 0; shift < 64; shift += 7) {
      const std::uint8_t b = byte();
      if (failed_) return 0;
      const std::uint64_t low = b & 0x7F;
      if (shift == 63 && low > 1) break;
      v |= low << shift;
      if ((b & 0x80) == 0) return v;
    }
    fail("varint too long");
    return 0;
  }

  std::uint32_t u32le() {
    std::uint32_t v = 0;
    for (int i = 0; i < 4; ++i) v |= static_cast<std::uint32_t>(byte()) << (8 * i);
    return failed_ ? 0 : v;
  }

  double f64le() {
    if (remaining() < 8) {
      fail("truncated");
      return 0.0;
    }
    std::uint64_t bits = 0;
    for (int i = 0; i < 8; ++i) {
      bits |= static_cast<std::uint64_t>(static_cast<std::uint8_t>(bytes_[pos_ + i])) << (8 * i);
    }
    pos_ += 8;
    return bits_double(bits);
  }

  /// A count of items that take at least `min_bytes_each` (≥ 1) bytes each: refused when
  /// the remaining bytes cannot hold them, so no allocation is ever larger than the input.
  std::size_t count(std::size_t min_bytes_each, const char* what) {
    const std::uint64_t n = varint();
    if (failed_) return 0;
    if (n > remaining() / min_bytes_each) {
      fail(std::string(what) + " count " + std::to_string(n) + " exceeds the remaining " +
           std::to_string(remaining()) + " bytes");
      return 0;
    }
    return static_cast<std::size_t>(n);
  }

  /// An index below `size`; on failure 0 (check failed() before subscripting).
  std::size_t index(std::size_t size, const char* what) {
    const std::uint64_t i = varint();
    if (failed_) return 0;
    if (i >= size) {
      fail(std::string(what) + " index " + std::to_string(i) + " out of range (" +
           std::to_string(size) + " entries)");
      return 0;
    }
    return static_cast<std::size_t>(i);
  }

  /// The next n bytes (n ≤ remaining(), else a failure and an empty view).
  std::string_view take(std::size_t n) {
    if (n > remaining()) {
      fail("truncated");
      return {};
    }
    const std::string_view v = bytes_.substr(pos_, n);
    pos_ += n;
    return v;
  }

 private:
  std::string_view bytes_;
  std::size_t base_;
  std::size_t pos_ = 0;
  bool failed_ = false;
  std::string error_;
};

}  // namespace csgtile::kernel::detail
