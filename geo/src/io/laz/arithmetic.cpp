#include "io/laz/arithmetic.h"

#include <algorithm>
#include <cassert>
#include <cstring>

#include "io/byte_source.h"

namespace csgtile::geo::detail::laz {

ByteStream::ByteStream(ByteSource& source, std::uint64_t offset, std::uint64_t length,
                       std::size_t block)
    : source_(&source), source_next_(offset), source_end_(offset + length), block_(block) {}

std::uint8_t ByteStream::refill() {
  if (source_ != nullptr && source_next_ < source_end_ && io_.ok()) {
    const std::size_t n =
        static_cast<std::size_t>(std::min<std::uint64_t>(block_, source_end_ - source_next_));
    buffer_.resize(n);
    if (auto st = source_->read_at(source_next_, buffer_); !st.ok()) {
      io_ = st;
    } else {
      source_next_ += n;
      next_ = buffer_.data();
      end_ = next_ + n;
      return *next_++;
    }
  }
  ++overrun_;
  return 0;
}

void ByteStream::get(std::uint8_t* out, std::size_t n) {
  while (n > 0) {
    if (next_ == end_) {
      *out++ = refill();
      --n;
      continue;
    }
    const std::size_t k = std::min<std::size_t>(n, static_cast<std::size_t>(end_ - next_));
    std::memcpy(out, next_, k);
    next_ += k;
    out += k;
    n -= k;
  }
}

ByteStream ByteStream::take(std::size_t n) {
  std::size_t left = static_cast<std::size_t>(end_ - next_);  // bytes this stream still has
  if (source_ != nullptr) left += static_cast<std::size_t>(source_end_ - source_next_);
  const std::size_t k = std::min(n, left);
  overrun_ += n - k;         // a layer that claims more bytes than the chunk holds
  if (source_ == nullptr) {  // memory outlives the stream: point into it
    ByteStream sub(std::span<const std::uint8_t>(next_, k));
    next_ += k;
    return sub;
  }
  // Over a ByteSource the window is refilled under a sub-stream: it gets its own copy.
  ByteStream sub;
  sub.buffer_.resize(k);
  get(sub.buffer_.data(), k);
  sub.next_ = sub.buffer_.data();
  sub.end_ = sub.next_ + k;
  return sub;
}

void BitModel::update() {
  if ((bit_count += update_cycle) > kBitMaxCount) {
    bit_count = (bit_count + 1) >> 1;
    bit_0_count = (bit_0_count + 1) >> 1;
    if (bit_0_count == bit_count) ++bit_count;
  }
  const std::uint32_t scale = 0x80000000u / bit_count;
  bit_0_prob = (bit_0_count * scale) >> (31 - kBitLengthShift);
  update_cycle = (5 * update_cycle) >> 2;
  if (update_cycle > 64) update_cycle = 64;
  until_update = update_cycle;
}

SymbolModel::SymbolModel(std::uint32_t n) : symbols(n), last_symbol(n - 1) {
  assert(n >= 1 && "a symbol model has at least one symbol");
  if (n > 16) {
    // A bucket per symbol (LASzip uses one per four): the decoded symbol is the same (the
    // table only brackets the search), and the search rarely needs a bisection step.
    std::uint32_t table_bits = 3;
    while (n > (1u << table_bits) && table_bits < 12) ++table_bits;
    table_size = 1u << table_bits;
    table_shift = kSymbolLengthShift - table_bits;
    table.assign(table_size + 2, 0);
  }
  distribution.assign(n, 0);
  symbol_count.assign(n, 1);
  update_cycle = n;
  update();
  update_cycle = (n + 6) >> 1;
  until_update = update_cycle;
}

void SymbolModel::update() {
  if ((total_count += update_cycle) > kSymbolMaxCount) {
    total_count = 0;
    for (std::uint32_t i = 0; i < symbols; ++i) {
      total_count += (symbol_count[i] = (symbol_count[i] + 1) >> 1);
    }
  }
  // Not zero: every one of the model's symbols (at least one, see the constructor) counts at
  // least 1, also after the halving.
  const std::uint32_t scale = 0x80000000u / total_count;  // NOLINT(clang-analyzer-core.DivideZero)
  std::uint32_t sum = 0;
  if (table.empty()) {
    for (std::uint32_t k = 0; k < symbols; ++k) {
      distribution[k] = (scale * sum) >> (31 - kSymbolLengthShift);
      sum += symbol_count[k];
    }
  } else {
    std::uint32_t s = 0;
    for (std::uint32_t k = 0; k < symbols; ++k) {
      distribution[k] = (scale * sum) >> (31 - kSymbolLengthShift);
      sum += symbol_count[k];
      const std::uint32_t w = distribution[k] >> table_shift;
      while (s < w) table[++s] = k - 1;
    }
    table[0] = 0;
    while (s <= table_size) table[++s] = symbols - 1;
  }
  update_cycle = (5 * update_cycle) >> 2;
  const std::uint32_t max_cycle = (symbols + 6) << 3;
  if (update_cycle > max_cycle) update_cycle = max_cycle;
  until_update = update_cycle;
}

void ArithmeticDecoder::start(ByteStream* in, bool read_start) {
  in_ = in;
  length_ = kMaxLength;
  value_ = 0;
  if (read_start) {
    for (int i = 0; i < 4; ++i) value_ = (value_ << 8) | in_->get();
  }
}

IntegerDecoder::IntegerDecoder(std::uint32_t bits, std::uint32_t contexts, std::uint32_t bits_high,
                               std::uint32_t range)
    : bits_high_(bits_high) {
  if (range != 0) {
    corr_range_ = range;
    for (std::uint32_t r = range; r != 0; r >>= 1) ++corr_bits_;
    if (corr_range_ == (1u << (corr_bits_ - 1))) --corr_bits_;
    corr_min_ = -static_cast<std::int32_t>(corr_range_ / 2);
  } else if (bits > 0 && bits < 32) {
    corr_bits_ = bits;
    corr_range_ = 1u << bits;
    corr_min_ = -static_cast<std::int32_t>(corr_range_ / 2);
  } else {
    corr_bits_ = 32;
    corr_range_ = 0;
    corr_min_ = INT32_MIN;
  }
  k_models_.reserve(contexts);
  for (std::uint32_t i = 0; i < contexts; ++i) k_models_.emplace_back(corr_bits_ + 1);
  corrector_models_.reserve(corr_bits_);
  for (std::uint32_t i = 1; i <= corr_bits_; ++i) {
    corrector_models_.emplace_back(i <= bits_high_ ? 1u << i : 1u << bits_high_);
  }
}

std::int32_t IntegerDecoder::corrector(ArithmeticDecoder& dec, SymbolModel& bits_model) {
  k_ = dec.decode_symbol(bits_model);
  if (k_ == 0) return static_cast<std::int32_t>(dec.decode_bit(corrector0_));
  if (k_ >= 32) return corr_min_;
  std::int64_t c;
  if (k_ <= bits_high_) {
    c = dec.decode_symbol(corrector_models_[k_ - 1]);
  } else {
    const std::uint32_t low_bits = k_ - bits_high_;
    const std::int64_t high = dec.decode_symbol(corrector_models_[k_ - 1]);
    c = (high << low_bits) | dec.read_bits(low_bits);
  }
  // [0, 2^(k-1)) maps to [-(2^k - 1), -2^(k-1)], [2^(k-1), 2^k) to [2^(k-1) + 1, 2^k].
  if (c >= (std::int64_t{1} << (k_ - 1))) {
    c += 1;
  } else {
    c -= (std::int64_t{1} << k_) - 1;
  }
  return static_cast<std::int32_t>(c);
}

std::int32_t IntegerDecoder::decode(ArithmeticDecoder& dec, std::int32_t prediction,
                                    std::uint32_t context) {
  const std::int32_t c = corrector(dec, k_models_[context]);
  // Wrap into [0, range) in unsigned arithmetic (the format relies on two's complement).
  std::uint32_t real = static_cast<std::uint32_t>(prediction) + static_cast<std::uint32_t>(c);
  if (corr_range_ != 0) {
    if (static_cast<std::int32_t>(real) < 0) {
      real += corr_range_;
    } else if (real >= corr_range_) {
      real -= corr_range_;
    }
  }
  return static_cast<std::int32_t>(real);
}

}  // namespace csgtile::geo::detail::laz
