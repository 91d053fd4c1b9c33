// Items of the point-wise compressors: version 1 (LASzip 1.x) and version 2 of POINT10,
// GPSTIME11, RGB12 and BYTE, and WAVEPACKET13 version 1. All items of a point share one
// arithmetic stream, decoded in item order.

#include <algorithm>
#include <array>
#include <cstring>
#include <vector>

#include "io/endian.h"
#include "io/laz/items.h"
#include "io/laz/tables.h"

namespace csgtile::geo::detail::laz {

namespace {

using detail::load_le;
using detail::store_le;

std::uint8_t fold8(std::int32_t v) { return static_cast<std::uint8_t>(v); }
std::int32_t clamp8(std::int32_t v) { return v < 0 ? 0 : v > 255 ? 255 : v; }
std::int32_t times(std::int32_t a, std::int32_t b) {  // the format's 32-bit product
  return static_cast<std::int32_t>(static_cast<std::uint32_t>(a) * static_cast<std::uint32_t>(b));
}

// ---------------------------------------------------------------- POINT10 (20 bytes)

class Point10V1 final : public PointwiseItemDecoder {
 public:
  void first(const std::uint8_t* raw) override { std::memcpy(last_, raw, 20); }

  void next(ArithmeticDecoder& dec, std::uint8_t* out) override {
    const std::int32_t median_x = median3(last_x_);
    const std::int32_t median_y = median3(last_y_);
    const std::int32_t dx = dx_.decode(dec, median_x);
    store_le<std::int32_t>(last_, wrap_add(load_le<std::int32_t>(last_), dx));
    std::uint32_t k = dx_.k();
    const std::int32_t dy = dy_.decode(dec, median_y, k < 19 ? k : 19);
    store_le<std::int32_t>(last_ + 4, wrap_add(load_le<std::int32_t>(last_ + 4), dy));
    k = (k + dy_.k()) / 2;
    store_le<std::int32_t>(last_ + 8,
                           z_.decode(dec, load_le<std::int32_t>(last_ + 8), k < 19 ? k : 19));
    const std::uint32_t changed = dec.decode_symbol(changed_);
    if (changed != 0) {
      if (changed & 32) {
        store_le<std::uint16_t>(last_ + 12, static_cast<std::uint16_t>(intensity_.decode(
                                                dec, load_le<std::uint16_t>(last_ + 12))));
      }
      if (changed & 16)
        last_[14] = static_cast<std::uint8_t>(dec.decode_symbol(lazy_model<256>(bits_[last_[14]])));
      if (changed & 8)
        last_[15] =
            static_cast<std::uint8_t>(dec.decode_symbol(lazy_model<256>(class_[last_[15]])));
      if (changed & 4)
        last_[16] = static_cast<std::uint8_t>(scan_angle_.decode(dec, last_[16], k < 3));
      if (changed & 2)
        last_[17] = static_cast<std::uint8_t>(dec.decode_symbol(lazy_model<256>(user_[last_[17]])));
      if (changed & 1) {
        store_le<std::uint16_t>(last_ + 18, static_cast<std::uint16_t>(source_.decode(
                                                dec, load_le<std::uint16_t>(last_ + 18))));
      }
    }
    last_x_[at_] = dx;
    last_y_[at_] = dy;
    at_ = at_ == 2 ? 0 : at_ + 1;
    std::memcpy(out, last_, 20);
  }

 private:
  static std::int32_t median3(const std::array<std::int32_t, 3>& v) {
    if (v[0] < v[1]) {
      if (v[1] < v[2]) return v[1];
      if (v[0] < v[2]) return v[2];
      return v[0];
    }
    if (v[0] < v[2]) return v[0];
    if (v[1] < v[2]) return v[2];
    return v[1];
  }

  std::uint8_t last_[20]{};
  std::array<std::int32_t, 3> last_x_{}, last_y_{};
  int at_ = 0;
  IntegerDecoder dx_{32}, dy_{32, 20}, z_{32, 20}, intensity_{16}, scan_angle_{8, 2}, source_{16};
  SymbolModel changed_{64};
  std::array<std::unique_ptr<SymbolModel>, 256> bits_, class_, user_;
};

class Point10V2 final : public PointwiseItemDecoder {
 public:
  void first(const std::uint8_t* raw) override {
    std::memcpy(last_, raw, 20);
    last_[12] = last_[13] = 0;  // the format starts the intensity prediction at zero
  }

  void next(ArithmeticDecoder& dec, std::uint8_t* out) override {
    const std::uint32_t changed = dec.decode_symbol(changed_);
    std::uint32_t r, n, m, l;
    if (changed != 0) {
      if (changed & 32)
        last_[14] = static_cast<std::uint8_t>(dec.decode_symbol(lazy_model<256>(bits_[last_[14]])));
      r = last_[14] & 7;
      n = (last_[14] >> 3) & 7;
      m = kNumberReturnMap[n][r];
      l = kNumberReturnLevel[n][r];
      if (changed & 16) {
        const auto v =
            static_cast<std::uint16_t>(intensity_.decode(dec, last_intensity_[m], m < 3 ? m : 3));
        store_le<std::uint16_t>(last_ + 12, v);
        last_intensity_[m] = v;
      } else {
        store_le<std::uint16_t>(last_ + 12, last_intensity_[m]);
      }
      if (changed & 8)
        last_[15] =
            static_cast<std::uint8_t>(dec.decode_symbol(lazy_model<256>(class_[last_[15]])));
      if (changed & 4) {
        const std::uint32_t v = dec.decode_symbol(scan_angle_[(last_[14] >> 6) & 1]);
        last_[16] = fold8(static_cast<std::int32_t>(v + last_[16]));
      }
      if (changed & 2)
        last_[17] = static_cast<std::uint8_t>(dec.decode_symbol(lazy_model<256>(user_[last_[17]])));
      if (changed & 1) {
        store_le<std::uint16_t>(last_ + 18, static_cast<std::uint16_t>(source_.decode(
                                                dec, load_le<std::uint16_t>(last_ + 18))));
      }
    } else {
      r = last_[14] & 7;
      n = (last_[14] >> 3) & 7;
      m = kNumberReturnMap[n][r];
      l = kNumberReturnLevel[n][r];
    }
    const std::uint32_t single = n == 1;
    std::int32_t diff = dx_.decode(dec, median_x_[m].get(), single);
    store_le<std::int32_t>(last_, wrap_add(load_le<std::int32_t>(last_), diff));
    median_x_[m].add(diff);
    std::uint32_t k = dx_.k();
    diff = dy_.decode(dec, median_y_[m].get(), single + (k < 20 ? (k & ~1u) : 20));
    store_le<std::int32_t>(last_ + 4, wrap_add(load_le<std::int32_t>(last_ + 4), diff));
    median_y_[m].add(diff);
    k = (dx_.k() + dy_.k()) / 2;
    const std::int32_t z = z_.decode(dec, last_height_[l], single + (k < 18 ? (k & ~1u) : 18));
    store_le<std::int32_t>(last_ + 8, z);
    last_height_[l] = z;
    std::memcpy(out, last_, 20);
  }

 private:
  std::uint8_t last_[20]{};
  std::array<std::uint16_t, 16> last_intensity_{};
  std::array<StreamingMedian5, 16> median_x_{}, median_y_{};
  std::array<std::int32_t, 8> last_height_{};
  IntegerDecoder intensity_{16, 4}, source_{16}, dx_{32, 2}, dy_{32, 22}, z_{32, 20};
  SymbolModel changed_{64};
  std::array<SymbolModel, 2> scan_angle_{SymbolModel(256), SymbolModel(256)};
  std::array<std::unique_ptr<SymbolModel>, 256> bits_, class_, user_;
};

// ---------------------------------------------------------------- GPSTIME11 (8 bytes)

class GpsTime11V1 final : public PointwiseItemDecoder {
 public:
  void first(const std::uint8_t* raw) override { last_ = load_le<std::uint64_t>(raw); }

  void next(ArithmeticDecoder& dec, std::uint8_t* out) override {
    constexpr std::int32_t kMultiMax = 512;
    if (last_diff_ == 0) {
      const std::uint32_t multi = dec.decode_symbol(zero_diff_);
      if (multi == 1) {
        last_diff_ = gps_.decode(dec, 0, 0);
        last_ += static_cast<std::uint64_t>(static_cast<std::int64_t>(last_diff_));
      } else if (multi == 2) {
        last_ = dec.read_int64();
      }
    } else {
      const auto multi = static_cast<std::int32_t>(dec.decode_symbol(multi_));
      if (multi < kMultiMax - 2) {
        std::int32_t diff;
        if (multi == 1) {
          diff = gps_.decode(dec, last_diff_, 1);
          last_diff_ = diff;
          extreme_ = 0;
        } else if (multi == 0) {
          diff = gps_.decode(dec, last_diff_ / 4, 2);
          if (++extreme_ > 3) {
            last_diff_ = diff;
            extreme_ = 0;
          }
        } else if (multi < 10) {
          diff = gps_.decode(dec, times(multi, last_diff_), 3);
        } else if (multi < 50) {
          diff = gps_.decode(dec, times(multi, last_diff_), 4);
        } else {
          diff = gps_.decode(dec, times(multi, last_diff_), 5);
          if (multi == kMultiMax - 3 && ++extreme_ > 3) {
            last_diff_ = diff;
            extreme_ = 0;
          }
        }
        last_ += static_cast<std::uint64_t>(static_cast<std::int64_t>(diff));
      } else if (multi < kMultiMax - 1) {
        last_ = dec.read_int64();
      }
    }
    store_le<std::uint64_t>(out, last_);
  }

 private:
  std::uint64_t last_ = 0;
  std::int32_t last_diff_ = 0;
  std::int32_t extreme_ = 0;
  SymbolModel multi_{512}, zero_diff_{3};
  IntegerDecoder gps_{32, 6};
};

class GpsTime11V2 final : public PointwiseItemDecoder {
 public:
  void first(const std::uint8_t* raw) override { state_.reset(load_le<std::uint64_t>(raw)); }
  void next(ArithmeticDecoder& dec, std::uint8_t* out) override {
    store_le<std::uint64_t>(out, state_.decode(dec));
  }

 private:
  GpsTimeState state_{GpsTimeState::Coding::V2};
};

// ---------------------------------------------------------------- RGB12 (6 bytes)

class Rgb12V1 final : public PointwiseItemDecoder {
 public:
  void first(const std::uint8_t* raw) override { read3(raw, last_); }

  void next(ArithmeticDecoder& dec, std::uint8_t* out) override {
    const std::uint32_t sym = dec.decode_symbol(used_);
    std::array<std::uint16_t, 3> c{};
    for (std::uint32_t i = 0; i < 3; ++i) {
      c[i] = (sym & (1u << (2 * i))) != 0
                 ? static_cast<std::uint16_t>(rgb_.decode(dec, last_[i] & 0xFF, 2 * i))
                 : static_cast<std::uint16_t>(last_[i] & 0xFF);
      if ((sym & (1u << (2 * i + 1))) != 0) {
        c[i] |= static_cast<std::uint16_t>(rgb_.decode(dec, last_[i] >> 8, 2 * i + 1) << 8);
      } else {
        c[i] |= last_[i] & 0xFF00;
      }
    }
    last_ = c;
    write3(out, c);
  }

 private:
  static void read3(const std::uint8_t* p, std::array<std::uint16_t, 3>& v) {
    for (int i = 0; i < 3; ++i) v[i] = load_le<std::uint16_t>(p + 2 * i);
  }
  static void write3(std::uint8_t* p, const std::array<std::uint16_t, 3>& v) {
    for (int i = 0; i < 3; ++i) store_le<std::uint16_t>(p + 2 * i, v[i]);
  }
  std::array<std::uint16_t, 3> last_{};
  SymbolModel used_{64};
  IntegerDecoder rgb_{8, 6};
};

class Rgb12V2 final : public PointwiseItemDecoder {
 public:
  void first(const std::uint8_t* raw) override {
    for (int i = 0; i < 3; ++i) last_[i] = load_le<std::uint16_t>(raw + 2 * i);
  }
  void next(ArithmeticDecoder& dec, std::uint8_t* out) override {
    last_ = decode_rgb(dec, models_, last_);
    for (int i = 0; i < 3; ++i) store_le<std::uint16_t>(out + 2 * i, last_[i]);
  }

 private:
  std::array<std::uint16_t, 3> last_{};
  RgbModels models_;
};

// ---------------------------------------------------------------- WAVEPACKET13 (29 bytes)

class WavePacket13V1 final : public PointwiseItemDecoder {
 public:
  void first(const std::uint8_t* raw) override { std::memcpy(last_.data(), raw, 29); }
  void next(ArithmeticDecoder& dec, std::uint8_t* out) override {
    coder_.decode(dec, last_.data(), out);
    std::memcpy(last_.data(), out, 29);
  }

 private:
  std::array<std::uint8_t, 29> last_{};
  WavePacketCoder coder_;
};

// ---------------------------------------------------------------- BYTE (n bytes)

class ByteV1 final : public PointwiseItemDecoder {
 public:
  explicit ByteV1(std::size_t n) : last_(n), bytes_(8, static_cast<std::uint32_t>(n)) {}
  void first(const std::uint8_t* raw) override { std::copy_n(raw, last_.size(), last_.begin()); }
  void next(ArithmeticDecoder& dec, std::uint8_t* out) override {
    for (std::size_t i = 0; i < last_.size(); ++i) {
      last_[i] = out[i] =
          static_cast<std::uint8_t>(bytes_.decode(dec, last_[i], static_cast<std::uint32_t>(i)));
    }
  }

 private:
  std::vector<std::uint8_t> last_;
  IntegerDecoder bytes_;
};

class ByteV2 final : public PointwiseItemDecoder {
 public:
  explicit ByteV2(std::size_t n) : last_(n), models_(n, SymbolModel(256)) {}
  void first(const std::uint8_t* raw) override { std::copy_n(raw, last_.size(), last_.begin()); }
  void next(ArithmeticDecoder& dec, std::uint8_t* out) override {
    for (std::size_t i = 0; i < last_.size(); ++i) {
      last_[i] = out[i] =
          fold8(static_cast<std::int32_t>(last_[i] + dec.decode_symbol(models_[i])));
    }
  }

 private:
  std::vector<std::uint8_t> last_;
  std::vector<SymbolModel> models_;
};

}  // namespace

std::array<std::uint16_t, 3> decode_rgb(ArithmeticDecoder& dec, RgbModels& m,
                                        const std::array<std::uint16_t, 3>& last) {
  const std::uint32_t sym = dec.decode_symbol(m.used);
  std::array<std::uint16_t, 3> c{};
  auto corr = [&](int i) { return static_cast<std::int32_t>(dec.decode_symbol(m.diff[i])); };
  c[0] = (sym & 1) ? fold8(corr(0) + (last[0] & 0xFF)) : (last[0] & 0xFF);
  c[0] |= (sym & 2) ? static_cast<std::uint16_t>(fold8(corr(1) + (last[0] >> 8)) << 8)
                    : (last[0] & 0xFF00);
  if (sym & 64) {
    std::int32_t diff = (c[0] & 0xFF) - (last[0] & 0xFF);
    c[1] = (sym & 4) ? fold8(corr(2) + clamp8(diff + (last[1] & 0xFF))) : (last[1] & 0xFF);
    if (sym & 16) {
      const std::int32_t d = (diff + ((c[1] & 0xFF) - (last[1] & 0xFF))) / 2;
      c[2] = fold8(corr(4) + clamp8(d + (last[2] & 0xFF)));
    } else {
      c[2] = last[2] & 0xFF;
    }
    diff = (c[0] >> 8) - (last[0] >> 8);
    c[1] |= (sym & 8)
                ? static_cast<std::uint16_t>(fold8(corr(3) + clamp8(diff + (last[1] >> 8))) << 8)
                : (last[1] & 0xFF00);
    if (sym & 32) {
      const std::int32_t d = (diff + ((c[1] >> 8) - (last[1] >> 8))) / 2;
      c[2] |= static_cast<std::uint16_t>(fold8(corr(5) + clamp8(d + (last[2] >> 8))) << 8);
    } else {
      c[2] |= last[2] & 0xFF00;
    }
  } else {
    c[1] = c[0];
    c[2] = c[0];
  }
  return c;
}

std::unique_ptr<PointwiseItemDecoder> make_pointwise_decoder(const Item& item) {
  switch (item.type) {
    case ItemType::Point10:
      if (item.size != 20) return nullptr;
      if (item.version == 1) return std::make_unique<Point10V1>();
      if (item.version == 2) return std::make_unique<Point10V2>();
      return nullptr;
    case ItemType::GpsTime11:
      if (item.size != 8) return nullptr;
      if (item.version == 1) return std::make_unique<GpsTime11V1>();
      if (item.version == 2) return std::make_unique<GpsTime11V2>();
      return nullptr;
    case ItemType::Rgb12:
      if (item.size != 6) return nullptr;
      if (item.version == 1) return std::make_unique<Rgb12V1>();
      if (item.version == 2) return std::make_unique<Rgb12V2>();
      return nullptr;
    case ItemType::WavePacket13:
      if (item.size != 29 || item.version != 1) return nullptr;
      return std::make_unique<WavePacket13V1>();
    case ItemType::Byte:
      if (item.size == 0) return nullptr;
      if (item.version == 1) return std::make_unique<ByteV1>(item.size);
      if (item.version == 2) return std::make_unique<ByteV2>(item.size);
      return nullptr;
    default:
      return nullptr;
  }
}

}  // namespace csgtile::geo::detail::laz
