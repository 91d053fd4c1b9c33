#pragma once
// Pieces the LASzip item decoders share: the return-number context tables, the running
// median of five, the GPS-time predictor (versions 2 and 3 differ only in their code
// numbering), the colour decoder of RGB12 v2 / RGB14 and the wave-packet decoder. Private.

#include <array>
#include <cstdint>
#include <memory>

#include "io/laz/arithmetic.h"

namespace csgtile::geo::detail::laz {

// Context of a point by (number of returns, return number), point formats 0-5. Files that
// number returns from 0 or swap the two fields get contexts of their own.
inline constexpr std::uint8_t kNumberReturnMap[8][8] = {
    {15, 14, 13, 12, 11, 10, 9, 8},  {14, 0, 1, 3, 6, 10, 10, 9},
    {13, 1, 2, 4, 7, 11, 11, 10},    {12, 3, 4, 5, 8, 12, 12, 11},
    {11, 6, 7, 8, 9, 13, 13, 12},    {10, 10, 11, 12, 13, 14, 14, 13},
    {9, 10, 11, 12, 13, 14, 15, 14}, {8, 9, 10, 11, 12, 13, 14, 15}};
// |number of returns - return number| capped at 7, point formats 0-5.
inline constexpr std::uint8_t kNumberReturnLevel[8][8] = {
    {0, 1, 2, 3, 4, 5, 6, 7}, {1, 0, 1, 2, 3, 4, 5, 6}, {2, 1, 0, 1, 2, 3, 4, 5},
    {3, 2, 1, 0, 1, 2, 3, 4}, {4, 3, 2, 1, 0, 1, 2, 3}, {5, 4, 3, 2, 1, 0, 1, 2},
    {6, 5, 4, 3, 2, 1, 0, 1}, {7, 6, 5, 4, 3, 2, 1, 0}};

// Point formats 6-10: six contexts by (number of returns, return number).
inline constexpr std::uint8_t kNumberReturnMap6[16][16] = {
    {0, 1, 2, 3, 4, 5, 3, 4, 4, 5, 5, 5, 5, 5, 5, 5},
    {1, 0, 1, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3},
    {2, 1, 2, 4, 4, 4, 4, 4, 4, 4, 4, 3, 3, 3, 3, 3},
    {3, 3, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4},
    {4, 3, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4},
    {5, 3, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4},
    {3, 3, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4, 4},
    {4, 3, 4, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4},
    {4, 3, 4, 4, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4},
    {5, 3, 4, 4, 4, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4},
    {5, 3, 4, 4, 4, 4, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4},
    {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5, 4, 4, 4},
    {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5, 5, 4, 4},
    {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5, 5, 4},
    {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5, 5},
    {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5}};
// Point formats 6-10: |number of returns - return number| capped at 7.
constexpr std::uint8_t number_return_level8(std::uint32_t n, std::uint32_t r) {
  const std::uint32_t d = n > r ? n - r : r - n;
  return static_cast<std::uint8_t>(d > 7 ? 7 : d);
}

/// A context model made on first use (LASzip makes these lazily; a fresh model is the same
/// whenever it is made).
template <std::uint32_t N>
SymbolModel& lazy_model(std::unique_ptr<SymbolModel>& slot) {
  if (!slot) slot = std::make_unique<SymbolModel>(N);
  return *slot;
}

/// a + b with the format's 32-bit wrap-around.
inline std::int32_t wrap_add(std::int32_t a, std::int32_t b) {
  return static_cast<std::int32_t>(static_cast<std::uint32_t>(a) + static_cast<std::uint32_t>(b));
}

/// Median of the last five values, kept sorted with a flag for the side to replace next.
struct StreamingMedian5 {
  std::array<std::int32_t, 5> v{};
  bool high = true;

  std::int32_t get() const { return v[2]; }
  void add(std::int32_t x) {
    if (high) {
      if (x < v[2]) {
        v[4] = v[3];
        v[3] = v[2];
        if (x < v[0]) {
          v[2] = v[1];
          v[1] = v[0];
          v[0] = x;
        } else if (x < v[1]) {
          v[2] = v[1];
          v[1] = x;
        } else {
          v[2] = x;
        }
      } else {
        if (x < v[3]) {
          v[4] = v[3];
          v[3] = x;
        } else {
          v[4] = x;
        }
        high = false;
      }
    } else {
      if (v[2] < x) {
        v[0] = v[1];
        v[1] = v[2];
        if (v[4] < x) {
          v[2] = v[3];
          v[3] = v[4];
          v[4] = x;
        } else if (v[3] < x) {
          v[2] = v[3];
          v[3] = x;
        } else {
          v[2] = x;
        }
      } else {
        if (v[1] < x) {
          v[0] = v[1];
          v[1] = x;
        } else {
          v[0] = x;
        }
        high = true;
      }
    }
  }
};

/// GPS-time predictor of GPSTIME11 v2 and POINT14 v3: four sequences of times, each with its
/// last integer difference; a code names a multiple of that difference, a full new time, or
/// a switch to another sequence. Times are kept as the double's bits.
class GpsTimeState {
 public:
  enum class Coding { V2, V3 };
  explicit GpsTimeState(Coding coding);
  void reset(std::uint64_t first_bits);
  /// Decodes the next time (v2: every point; v3: only points whose time changed).
  std::uint64_t decode(ArithmeticDecoder& dec);

 private:
  void start_sequence(ArithmeticDecoder& dec);

  Coding coding_;
  std::uint32_t last_ = 0, next_ = 0;
  std::array<std::uint64_t, 4> time_{};
  std::array<std::int32_t, 4> diff_{}, extreme_{};
  SymbolModel multi_, zero_diff_;
  IntegerDecoder gps_{32, 9};
};

/// Models of the RGB12 v2 / RGB14 colour decoder.
struct RgbModels {
  SymbolModel used{128};
  std::array<SymbolModel, 6> diff{SymbolModel(256), SymbolModel(256), SymbolModel(256),
                                  SymbolModel(256), SymbolModel(256), SymbolModel(256)};
};
/// The next colour from the last (bytes of each channel predicted from red's change).
std::array<std::uint16_t, 3> decode_rgb(ArithmeticDecoder& dec, RgbModels& m,
                                        const std::array<std::uint16_t, 3>& last);

/// The wave-packet decoder (descriptor index, offset, size, return point, x/y/z(t)): its
/// models and running state; the packet it predicts from is the caller's (29 bytes, the
/// descriptor index first).
class WavePacketCoder {
 public:
  void decode(ArithmeticDecoder& dec, const std::uint8_t* last, std::uint8_t* out);

 private:
  std::int32_t last_diff_32_ = 0;
  std::uint32_t sym_last_offset_diff_ = 0;
  SymbolModel packet_index_{256};
  std::array<SymbolModel, 4> offset_diff_{SymbolModel(4), SymbolModel(4), SymbolModel(4),
                                          SymbolModel(4)};
  IntegerDecoder offset_{32}, packet_size_{32}, return_point_{32}, xyz_{32, 3};
};

}  // namespace csgtile::geo::detail::laz
