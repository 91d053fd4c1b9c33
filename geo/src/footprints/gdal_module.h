#pragma once
// The GDAL module (libcsgtile_gdal.so, built from gdal_reader.cpp, the one file that sees GDAL),
// which footprints.cpp loads on the first footprint read (why, and how: csgtile/kernel/module.h).
// Its entry point passes csgtile's own types by reference; the ABI text hashes their headers
// (geo/CMakeLists.txt).

#include "csgtile/geo/footprints.h"

namespace csgtile::geo {

inline constexpr const char* kGdalModuleAbi = CSGTILE_GDAL_MODULE_ABI;

/// The module's file name (kernel::load_module says where it is looked for).
inline constexpr const char* kGdalModuleFile = "libcsgtile_gdal.so";

}  // namespace csgtile::geo

extern "C" {
/// read_footprints, done with GDAL: the result in `out`; nothing is thrown (noexcept).
using CsgtileGdalReadFootprints = void(const csgtile::geo::FootprintSource& source,
                                       const csgtile::geo::FootprintQuery& query,
                                       csgtile::kernel::Result<csgtile::geo::FootprintSet>& out);
}
