#include "io/laz/tables.h"

#include <cstring>

#include "io/endian.h"

namespace csgtile::geo::detail::laz {

namespace {
constexpr std::int32_t kMulti = 500;
constexpr std::int32_t kMultiMinus = -10;

std::int32_t times(std::int32_t a, std::int32_t b) {  // the format's 32-bit product
  return static_cast<std::int32_t>(static_cast<std::uint32_t>(a) * static_cast<std::uint32_t>(b));
}
}  // namespace

GpsTimeState::GpsTimeState(Coding coding)
    : coding_(coding),
      multi_(coding == Coding::V2 ? 516 : 515),
      zero_diff_(coding == Coding::V2 ? 6 : 5) {}

void GpsTimeState::reset(std::uint64_t first_bits) {
  last_ = next_ = 0;
  time_ = {first_bits, 0, 0, 0};
  diff_ = {};
  extreme_ = {};
}

void GpsTimeState::start_sequence(ArithmeticDecoder& dec) {
  // A full time: its high half predicted from the current sequence's, its low half raw.
  next_ = (next_ + 1) & 3;
  const auto high = static_cast<std::uint32_t>(
      gps_.decode(dec, static_cast<std::int32_t>(time_[last_] >> 32), 8));
  time_[next_] = (std::uint64_t{high} << 32) | dec.read_int();
  last_ = next_;
  diff_[last_] = 0;
  extreme_[last_] = 0;
}

std::uint64_t GpsTimeState::decode(ArithmeticDecoder& dec) {
  // Codes of the non-zero-difference alphabet: v2 has an "unchanged" code before the full one.
  const std::int32_t code_full = coding_ == Coding::V2 ? 512 : 511;
  const std::int32_t code_unchanged = coding_ == Coding::V2 ? 511 : -1;
  // A valid stream switches sequence at most once per point; a corrupt one could do it forever.
  for (int round = 0; round < 4; ++round) {
    if (diff_[last_] == 0) {
      const auto multi = static_cast<std::int32_t>(dec.decode_symbol(zero_diff_));
      const std::int32_t small = coding_ == Coding::V2 ? 1 : 0;      // a 32-bit difference
      const std::int32_t full = small + 1;                           // a full new time
      if (coding_ == Coding::V2 && multi == 0) return time_[last_];  // unchanged
      if (multi == small) {
        diff_[last_] = gps_.decode(dec, 0, 0);
        time_[last_] += static_cast<std::uint64_t>(static_cast<std::int64_t>(diff_[last_]));
        extreme_[last_] = 0;
      } else if (multi == full) {
        start_sequence(dec);
      } else {
        last_ = (last_ + static_cast<std::uint32_t>(multi - full)) & 3;
        continue;
      }
      return time_[last_];
    }
    const auto multi = static_cast<std::int32_t>(dec.decode_symbol(multi_));
    if (multi == 1) {
      time_[last_] +=
          static_cast<std::uint64_t>(static_cast<std::int64_t>(gps_.decode(dec, diff_[last_], 1)));
      extreme_[last_] = 0;
    } else if (multi == code_unchanged) {
      // unchanged
    } else if (multi < code_full) {
      std::int32_t diff;
      if (multi == 0) {
        diff = gps_.decode(dec, 0, 7);
        if (++extreme_[last_] > 3) {
          diff_[last_] = diff;
          extreme_[last_] = 0;
        }
      } else if (multi < kMulti) {
        diff = gps_.decode(dec, times(multi, diff_[last_]), multi < 10 ? 2 : 3);
      } else if (multi == kMulti) {
        diff = gps_.decode(dec, times(kMulti, diff_[last_]), 4);
        if (++extreme_[last_] > 3) {
          diff_[last_] = diff;
          extreme_[last_] = 0;
        }
      } else {
        const std::int32_t m = kMulti - multi;
        if (m > kMultiMinus) {
          diff = gps_.decode(dec, times(m, diff_[last_]), 5);
        } else {
          diff = gps_.decode(dec, times(kMultiMinus, diff_[last_]), 6);
          if (++extreme_[last_] > 3) {
            diff_[last_] = diff;
            extreme_[last_] = 0;
          }
        }
      }
      time_[last_] += static_cast<std::uint64_t>(static_cast<std::int64_t>(diff));
    } else if (multi == code_full) {
      start_sequence(dec);
    } else {
      last_ = (last_ + static_cast<std::uint32_t>(multi - code_full)) & 3;
      continue;
    }
    return time_[last_];
  }
  return time_[last_];
}

void WavePacketCoder::decode(ArithmeticDecoder& dec, const std::uint8_t* last_packet,
                             std::uint8_t* out) {
  using detail::load_le;
  using detail::store_le;
  out[0] = static_cast<std::uint8_t>(dec.decode_symbol(packet_index_));
  const std::uint8_t* last = last_packet + 1;
  const auto last_offset = load_le<std::uint64_t>(last);
  const auto last_size = load_le<std::uint32_t>(last + 8);
  sym_last_offset_diff_ = dec.decode_symbol(offset_diff_[sym_last_offset_diff_]);
  std::uint64_t offset;
  if (sym_last_offset_diff_ == 0) {
    offset = last_offset;
  } else if (sym_last_offset_diff_ == 1) {
    offset = last_offset + last_size;
  } else if (sym_last_offset_diff_ == 2) {
    last_diff_32_ = offset_.decode(dec, last_diff_32_);
    offset = last_offset + static_cast<std::uint64_t>(static_cast<std::int64_t>(last_diff_32_));
  } else {
    offset = dec.read_int64();
  }
  std::uint8_t* p = out + 1;
  store_le<std::uint64_t>(p, offset);
  store_le<std::int32_t>(p + 8, packet_size_.decode(dec, static_cast<std::int32_t>(last_size)));
  store_le<std::int32_t>(p + 12, return_point_.decode(dec, load_le<std::int32_t>(last + 12)));
  for (int i = 0; i < 3; ++i) {
    store_le<std::int32_t>(
        p + 16 + 4 * i,
        xyz_.decode(dec, load_le<std::int32_t>(last + 16 + 4 * i), static_cast<std::uint32_t>(i)));
  }
}

}  // namespace csgtile::geo::detail::laz
