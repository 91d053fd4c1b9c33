// Hash of an integer grid cell (x, y, z) for the Booleans' vertex and point grids.
//
// The arithmetic is unsigned: cells of georeferenced coordinates (RD New, UTM) at a
// tolerance of 1e-7 m have indices near 1e12, whose products overflow a signed type.
#pragma once

#include <cstdint>

namespace csgtile::kernel::detail {

inline long long cell_hash(long long x, long long y, long long z) {
  const auto ux = static_cast<std::uint64_t>(x);
  const auto uy = static_cast<std::uint64_t>(y);
  const auto uz = static_cast<std::uint64_t>(z);
  const std::uint64_t h = (ux * 73856093ULL) ^ (uy * 19349663ULL) ^ (uz * 83492791ULL);
  return static_cast<long long>(h);
}

}  // namespace csgtile::kernel::detail
