#pragma once
// The GDAL module: the one room of csgtile that links GDAL (gdal_reader.cpp, built as
// libcsgtile_gdal.so). GDAL and the hundred libraries it brings (GEOS, Poppler, HDF5, ...)
// cost about 75 ms of symbol binding at every process start, so the binary does not link
// them: footprints.cpp loads the module on the first footprint read, and a process that
// reads no footprints never loads GDAL.
//
// The module and the binary are built from the same sources and flags; the entry point passes
// csgtile's own types by reference, and the ABI number below, compiled into both, must agree
// (change it when those types change shape). Loading: csgtile/kernel/module.h.

#include "csgtile/geo/footprints.h"

namespace csgtile::geo {

inline constexpr int kGdalModuleAbi = 1;

/// The module's file name (kernel::load_module says where it is looked for).
inline constexpr const char* kGdalModuleFile = "libcsgtile_gdal.so";

}  // namespace csgtile::geo

extern "C" {
/// read_footprints, done with GDAL: the result in `out`; nothing is thrown.
using CsgtileGdalReadFootprints = void(const csgtile::geo::FootprintSource& source,
                                       const csgtile::geo::FootprintQuery& query,
                                       csgtile::kernel::Result<csgtile::geo::FootprintSet>& out);
}
