#pragma once
// The OpenVDB module (libcsgtile_vdb.so, built from vdb_shells.cpp): the voxel shells of the
// assembly's culling (voxel_cull.h) as sparse OpenVDB masks. OpenVDB and the libraries it
// brings cost about 60 ms of symbol binding at every process start, so the binary does not
// link them: voxel_cull.cpp loads the module (csgtile/kernel/module.h) when it first builds
// shells, or on a thread of its own when a city run starts (load_culling_in_background), and a
// process that assembles nothing never loads OpenVDB.
//
// Plain arrays cross the boundary; the ABI text, a hash of this header computed when CMake
// configures (kernel/assembly/CMakeLists.txt), is compiled into both sides and must agree.

#include <cstddef>
#include <cstdint>

namespace csgtile::assembly {

inline constexpr const char* kVdbModuleAbi = CSGTILE_VDB_MODULE_ABI;
inline constexpr const char* kVdbModuleFile = "libcsgtile_vdb.so";

}  // namespace csgtile::assembly

extern "C" {
/// A shell: the voxels (edge `voxel`; voxel (i, j, k) centred at voxel·(i, j, k)) whose centres
/// lie within `margin` of one of the triangles (`vertices`: x, y, z each; `triangles`: three
/// vertex indices each), kept only inside the regions (`regions`: min x, y, z, max x, y, z
/// each). Null when it cannot be made (memory).
using CsgtileVdbShellBuild = void*(const double* vertices, std::size_t vertex_count,
                                   const std::uint32_t* triangles, std::size_t triangle_count,
                                   const double* regions, std::size_t region_count, double voxel,
                                   double margin);
/// 1 when two shells share a voxel, else 0.
using CsgtileVdbShellsMeet = int(const void* a, const void* b);
/// The voxels of a shell.
using CsgtileVdbShellVoxels = long long(const void* shell);
/// Frees a shell.
using CsgtileVdbShellFree = void(void* shell);
}
