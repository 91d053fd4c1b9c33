#pragma once
// The entropy decoder of LASzip-compressed point data: a 32-bit range (arithmetic) decoder
// with adaptive bit and symbol models, and the integer decoder built on it (a corrector
// against a prediction, coded as its bit length k and then its bits). Written from the LAZ
// specification and the published description of the coder (A. Said, "Introduction to
// Arithmetic Coding — Theory and Practice", HP Labs HPL-2004-76); the constants are the
// format's. Private to geo.
//
// Bytes come from a ByteStream: a span in memory, optionally refilled from a ByteSource for
// the one un-chunked compressor. Reading past the end yields zeros and counts the overrun, so
// a hostile stream cannot read outside its chunk; the chunk decoder turns an overrun into an
// error naming the chunk.

#include <cstdint>
#include <span>
#include <vector>

#include "csgtile/kernel/result.h"

namespace csgtile::geo {
class ByteSource;
namespace detail {
using ByteSource = geo::ByteSource;
}  // namespace detail
}  // namespace csgtile::geo

namespace csgtile::geo::detail::laz {

inline constexpr std::uint32_t kMinLength = 0x01000000u;  // renormalise below this
inline constexpr std::uint32_t kMaxLength = 0xFFFFFFFFu;
inline constexpr std::uint32_t kBitLengthShift = 13;
inline constexpr std::uint32_t kBitMaxCount = 1u << kBitLengthShift;
inline constexpr std::uint32_t kSymbolLengthShift = 15;
inline constexpr std::uint32_t kSymbolMaxCount = 1u << kSymbolLengthShift;

/// Bytes for a decoder: a window that is refilled from a ByteSource when one is attached.
/// Movable, not copyable (it may own the bytes it points into).
class ByteStream {
 public:
  ByteStream() = default;
  ByteStream(ByteStream&&) = default;
  ByteStream& operator=(ByteStream&&) = default;
  ByteStream(const ByteStream&) = delete;
  ByteStream& operator=(const ByteStream&) = delete;
  /// Memory that outlives the stream.
  explicit ByteStream(std::span<const std::uint8_t> bytes)
      : next_(bytes.data()), end_(bytes.data() + bytes.size()) {}
  /// Reads [offset, offset + length) of `source` in blocks of `block` bytes.
  ByteStream(ByteSource& source, std::uint64_t offset, std::uint64_t length,
             std::size_t block = 1 << 20);

  std::uint8_t get() {
    if (next_ != end_) [[likely]]
      return *next_++;
    return refill();
  }
  /// Copies n bytes (zeros past the end, counted as overrun).
  void get(std::uint8_t* out, std::size_t n);
  std::uint32_t get_u32() {
    std::uint8_t b[4];
    get(b, 4);
    return std::uint32_t{b[0]} | std::uint32_t{b[1]} << 8 | std::uint32_t{b[2]} << 16 |
           std::uint32_t{b[3]} << 24;
  }
  /// A sub-stream of the next n bytes; this stream skips them. Over memory it points into the
  /// same bytes; over a ByteSource it owns a copy (later refills replace this window). Bytes
  /// it claims past the end count as this stream's overrun.
  ByteStream take(std::size_t n);
  /// Bytes read past the end (each returned as 0).
  std::uint64_t overrun() const { return overrun_; }
  /// An I/O error met while refilling (the stream then reads as past its end).
  const kernel::Status& io_status() const { return io_; }

 private:
  std::uint8_t refill();

  const std::uint8_t* next_ = nullptr;
  const std::uint8_t* end_ = nullptr;
  ByteSource* source_ = nullptr;
  std::uint64_t source_next_ = 0, source_end_ = 0;
  std::vector<std::uint8_t> buffer_;  // the current window, or a sub-stream's own bytes
  std::size_t block_ = 0;
  std::uint64_t overrun_ = 0;
  kernel::Status io_;
};

/// Adaptive model of one binary decision.
struct BitModel {
  std::uint32_t update_cycle = 4, until_update = 4;
  std::uint32_t bit_0_prob = 1u << (kBitLengthShift - 1), bit_0_count = 1, bit_count = 2;
  void update();
};

/// Adaptive model of a symbol alphabet 0..n-1, with a look-up table for n > 16.
class SymbolModel {
 public:
  explicit SymbolModel(std::uint32_t symbols);
  void update();

  std::uint32_t symbols = 0, last_symbol = 0;
  std::uint32_t table_size = 0, table_shift = 0;
  std::uint32_t total_count = 0, update_cycle = 0, until_update = 0;
  std::vector<std::uint32_t> distribution, symbol_count, table;
};

/// The range decoder.
class ArithmeticDecoder {
 public:
  ArithmeticDecoder() = default;
  /// Starts on `in`: when `read_start` the first four bytes seed the value (every stream but
  /// an empty layer does so).
  explicit ArithmeticDecoder(ByteStream* in, bool read_start = true) { start(in, read_start); }
  void start(ByteStream* in, bool read_start = true);

  // The hot paths work on local copies of the interval and the model's arrays: stores to the
  // model's counts would otherwise force the compiler to reload them after every write.
  std::uint32_t decode_bit(BitModel& m) {
    std::uint32_t value = value_, length = length_;
    const std::uint32_t x = m.bit_0_prob * (length >> kBitLengthShift);
    const std::uint32_t bit = value >= x;
    if (bit == 0) {
      length = x;
      ++m.bit_0_count;
    } else {
      value -= x;
      length -= x;
    }
    if (length < kMinLength) renormalise(value, length);
    value_ = value;
    length_ = length;
    if (--m.until_update == 0) m.update();
    return bit;
  }

  std::uint32_t decode_symbol(SymbolModel& m) {
    std::uint32_t value = value_, length = length_;
    const std::uint32_t* const dist = m.distribution.data();
    std::uint32_t sym, x, y = length;
    if (!m.table.empty()) {
      const std::uint32_t* const table = m.table.data();
      length >>= kSymbolLengthShift;
      const std::uint32_t dv = value / length;
      std::uint32_t t = dv >> m.table_shift;
      if (t > m.table_size) t = m.table_size;  // only a corrupt stream gets here
      sym = table[t];
      std::uint32_t n = table[t + 1] + 1;
      while (n > sym + 1) {  // bisection within the table's bracket
        const std::uint32_t k = (sym + n) >> 1;
        if (dist[k] > dv) {
          n = k;
        } else {
          sym = k;
        }
      }
      x = dist[sym] * length;
      if (sym != m.last_symbol) y = dist[sym + 1] * length;
    } else {
      x = sym = 0;
      length >>= kSymbolLengthShift;
      std::uint32_t n = m.symbols;
      std::uint32_t k = n >> 1;
      do {
        const std::uint32_t z = length * dist[k];
        if (z > value) {
          n = k;
          y = z;
        } else {
          sym = k;
          x = z;
        }
      } while ((k = (sym + n) >> 1) != sym);
    }
    value -= x;
    length = y - x;
    if (length < kMinLength) renormalise(value, length);
    value_ = value;
    length_ = length;
    ++m.symbol_count[sym];
    if (--m.until_update == 0) m.update();
    return sym;
  }

  /// `bits` (1-32) raw bits.
  std::uint32_t read_bits(std::uint32_t bits) {
    if (bits > 19) {
      const std::uint32_t low = read_short();
      return (read_bits(bits - 16) << 16) | low;
    }
    std::uint32_t value = value_, length = length_ >> bits;
    const std::uint32_t sym = value / length;
    value -= length * sym;
    if (length < kMinLength) renormalise(value, length);
    value_ = value;
    length_ = length;
    return sym & ((1u << bits) - 1);  // a hostile stream can exceed the range; keep it in
  }
  std::uint32_t read_short() {
    std::uint32_t value = value_, length = length_ >> 16;
    const std::uint32_t sym = value / length;
    value -= length * sym;
    if (length < kMinLength) renormalise(value, length);
    value_ = value;
    length_ = length;
    return sym & 0xFFFFu;
  }
  std::uint32_t read_int() {
    const std::uint32_t low = read_short();
    return (read_short() << 16) | low;
  }
  std::uint64_t read_int64() {
    const std::uint64_t low = read_int();
    return (std::uint64_t{read_int()} << 32) | low;
  }

 private:
  void renormalise(std::uint32_t& value, std::uint32_t& length) {
    do {
      value = (value << 8) | in_->get();
    } while ((length <<= 8) < kMinLength);
  }

  ByteStream* in_ = nullptr;
  std::uint32_t value_ = 0, length_ = kMaxLength;
};

/// Integer decoder: value = prediction + corrector, wrapped into the value's bit range.
class IntegerDecoder {
 public:
  explicit IntegerDecoder(std::uint32_t bits = 16, std::uint32_t contexts = 1,
                          std::uint32_t bits_high = 8, std::uint32_t range = 0);
  std::int32_t decode(ArithmeticDecoder& dec, std::int32_t prediction, std::uint32_t context = 0);
  /// Bit length class of the last corrector.
  std::uint32_t k() const { return k_; }

 private:
  std::int32_t corrector(ArithmeticDecoder& dec, SymbolModel& bits_model);

  std::uint32_t bits_high_;
  std::uint32_t corr_bits_ = 0, corr_range_ = 0;
  std::int32_t corr_min_ = 0;
  std::uint32_t k_ = 0;
  std::vector<SymbolModel> k_models_;          // one per context
  BitModel corrector0_;                        // k == 0
  std::vector<SymbolModel> corrector_models_;  // k = 1 .. corr_bits
};

}  // namespace csgtile::geo::detail::laz
