#pragma once
// The OpenVDB module (libcsgtile_vdb.so, built from vdb_shells.cpp, the one file that sees
// OpenVDB): the voxel shells of the assembly's culling (voxel_cull.h) as sparse OpenVDB masks,
// loaded by voxel_cull.cpp (why, and how: csgtile/kernel/module.h). Plain arrays cross the
// boundary; the ABI text hashes this header (kernel/assembly/CMakeLists.txt).

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
