#pragma once
// Layout constants of the LAS 1.0-1.4 (R15) file format shared by the reader and the writer.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "csgtile/geo/las.h"

namespace csgtile::geo::detail {

// Public header block (§2.2 of the 1.4 R15 specification): byte offsets.
inline constexpr std::size_t kLasSignature = 0;
inline constexpr std::size_t kLasFileSourceId = 4;
inline constexpr std::size_t kLasGlobalEncoding = 6;
inline constexpr std::size_t kLasGuid = 8;
inline constexpr std::size_t kLasVersionMajor = 24;
inline constexpr std::size_t kLasVersionMinor = 25;
inline constexpr std::size_t kLasSystemIdentifier = 26;
inline constexpr std::size_t kLasGeneratingSoftware = 58;
inline constexpr std::size_t kLasCreationDay = 90;
inline constexpr std::size_t kLasCreationYear = 92;
inline constexpr std::size_t kLasHeaderSize = 94;
inline constexpr std::size_t kLasOffsetToPoints = 96;
inline constexpr std::size_t kLasVlrCount = 100;
inline constexpr std::size_t kLasPointFormat = 104;
inline constexpr std::size_t kLasRecordLength = 105;
inline constexpr std::size_t kLasLegacyCount = 107;
inline constexpr std::size_t kLasLegacyByReturn = 111;
inline constexpr std::size_t kLasScale = 131;
inline constexpr std::size_t kLasOffset = 155;
inline constexpr std::size_t kLasBounds = 179;         // max x, min x, max y, min y, max z, min z
inline constexpr std::size_t kLasWaveformStart = 227;  // 1.3
inline constexpr std::size_t kLasEvlrOffset = 235;     // 1.4
inline constexpr std::size_t kLasEvlrCount = 243;
inline constexpr std::size_t kLasPointCount = 247;
inline constexpr std::size_t kLasByReturn = 255;

inline constexpr std::size_t kLasHeaderSize12 = 227;  // 1.0, 1.1, 1.2
inline constexpr std::size_t kLasHeaderSize13 = 235;
inline constexpr std::size_t kLasHeaderSize14 = 375;
inline constexpr std::size_t kLasVlrHeaderSize = 54;
inline constexpr std::size_t kLasEvlrHeaderSize = 60;
inline constexpr std::size_t kLasExtraDescriptorSize = 192;
inline constexpr std::size_t kLasWavePacketSize = 29;

/// Header size a version defines.
inline constexpr std::size_t las_header_size(int minor) {
  return minor <= 2 ? kLasHeaderSize12 : minor == 3 ? kLasHeaderSize13 : kLasHeaderSize14;
}

/// The first LAS minor version that defines point format `format`.
inline constexpr int las_first_version_of_format(int format) {
  if (format <= 1) return 0;
  if (format <= 3) return 2;
  if (format <= 5) return 3;
  return 4;
}

inline constexpr bool las_format_has_gps(int f) { return f == 1 || f >= 3; }
inline constexpr bool las_format_has_rgb(int f) {
  return f == 2 || f == 3 || f == 5 || f == 7 || f == 8 || f == 10;
}
inline constexpr bool las_format_has_nir(int f) { return f == 8 || f == 10; }
inline constexpr bool las_format_has_waves(int f) { return f == 4 || f == 5 || f == 9 || f == 10; }

/// Extra Bytes descriptor data types (R15 table 24): element type of 1-30, 0 for Raw.
/// Returns false for reserved types (> 30).
bool las_extra_type(std::uint8_t data_type, ExtraType& type, int& elements);
/// The data type number of (type, elements), the inverse of las_extra_type.
std::uint8_t las_extra_data_type(ExtraType type, int elements);

/// Text of a fixed-size, NUL-padded character field.
std::string las_fixed_string(const std::uint8_t* p, std::size_t size);

}  // namespace csgtile::geo::detail
