#pragma once
// Factories of the non-LAS readers over a byte source, and small parsing helpers shared by
// the text formats. Private to geo.

#include <charconv>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "csgtile/geo/point_reader.h"
#include "io/byte_source.h"

namespace csgtile::geo::detail {

kernel::Result<std::unique_ptr<PointReader>> open_ply(std::unique_ptr<ByteSource> source,
                                                      const PointReadOptions& options);
kernel::Result<std::unique_ptr<PointReader>> open_pcd(std::unique_ptr<ByteSource> source,
                                                      const PointReadOptions& options);
kernel::Result<std::unique_ptr<PointReader>> open_xyz(std::unique_ptr<ByteSource> source,
                                                      const PointReadOptions& options);

/// Splits `text` at runs of spaces and tabs (and commas when `commas`); no empty tokens.
std::vector<std::string_view> split_fields(std::string_view text, bool commas = false);
/// `text` without leading and trailing blanks.
std::string_view trim(std::string_view text);

/// Parses a whole token as a number (from_chars: no locale, no leading '+' except as handled).
template <class T>
std::optional<T> parse_number(std::string_view token) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  T value{};
  const auto* end = token.data() + token.size();
  const auto [ptr, ec] = std::from_chars(token.data(), end, value);
  if (ec != std::errc() || ptr != end) return std::nullopt;
  return value;
}

/// Tracks the largest coordinate magnitude of float32 sources and, at the end, warns when
/// float32 cannot resolve it to a centimetre (e.g. UTM northings: 0.5 m steps).
class Float32PrecisionCheck {
 public:
  void add(double magnitude) {
    if (magnitude > largest_) largest_ = magnitude;
  }
  /// The warning, or nothing when the coordinates are small enough.
  std::optional<std::string> warning(const std::string& file) const;

 private:
  double largest_ = 0;
};

/// Which Point field an input column or property feeds.
enum class PointTarget {
  None,
  X,
  Y,
  Z,
  NormalX,
  NormalY,
  NormalZ,
  Red,
  Green,
  Blue,
  Rgb,
  Intensity,
  Classification,
  GpsTime,
  ReturnNumber,
  NumberOfReturns,
  PointSourceId,
  UserData,
  ScanAngle,
  Nir
};
/// The field named `name` (PLY / PCD / XYZ conventions, case-insensitive), or None.
PointTarget point_target(std::string_view name);
/// Stores `value` in the field (clamping and rounding into integer fields; colours given by
/// 8-bit sources are scaled ×257 when `eight_bit_color`).
void assign_target(Point& point, PointTarget target, double value, bool eight_bit_color);
/// Marks `target` in `fields`.
void mark_field(PointFields& fields, PointTarget target);

}  // namespace csgtile::geo::detail
