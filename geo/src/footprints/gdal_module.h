#pragma once
// The GDAL module: the one room of csgtile that links GDAL (gdal_reader.cpp, built as
// libcsgtile_gdal.so). GDAL and the hundred libraries it brings (GEOS, Poppler, HDF5, ...)
// cost about 75 ms of symbol binding at every process start, so the binary does not link
// them: footprints.cpp loads the module on the first footprint read, and a process that
// reads no footprints never loads GDAL.
//
// The entry point passes csgtile's own types by reference: the module and the binary must be
// built from the same headers. The ABI text below, a hash of those headers computed when CMake
// configures (geo/CMakeLists.txt), is compiled into both, and the loader
// (csgtile/kernel/module.h) refuses a module whose text differs.

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
