#pragma once
/// \file
/// OpenVDB overlap culling. Two solids are in contact only if their boundaries meet or one
/// lies inside the other — and then its bounding box lies inside the other's. So each solid
/// is voxelised as a shell: the voxels whose centres lie within a margin of its boundary
/// (of its tessellation, by exact point–triangle distances), kept in a sparse OpenVDB mask
/// and only where candidate partners' boxes are; the margin covers half a voxel diagonal, the
/// tessellation error and the contact tolerance. A pair may meet when the shells share a voxel or
/// one box holds the other. Culling is conservative by construction: a point common to both
/// boundaries lies in a voxel whose centre is within half a diagonal of both, so both shells hold
/// it. The shells are OpenVDB masks made by csgtile's OpenVDB module (libcsgtile_vdb.so),
/// loaded when the first shells are built.

#include <cstddef>
#include <memory>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "csgtile/kernel/bounding_box.h"
#include "csgtile/kernel/shape.h"

namespace csgtile::assembly {

/// Loads the OpenVDB module on a thread of its own, so that a process about to assemble (a city
/// run, a worker) has it by its first assembly without waiting for it (binding its symbols in a
/// process of csgtile's libraries takes about 0.1 s). Keep the thread until the scope ends: it
/// joins then. An empty thread when none can be started (the first shells load it then).
std::jthread load_culling_in_background();

class VoxelCuller {
 public:
  /// voxel_size: edge of a voxel (world units), > 0; tolerance: the contact tolerance.
  VoxelCuller(double voxel_size, double tolerance);
  ~VoxelCuller();
  VoxelCuller(VoxelCuller&&) noexcept;
  VoxelCuller& operator=(VoxelCuller&&) noexcept;

  /// Voxelises, in parallel, each shape that takes part in a candidate pair (indices into
  /// `shapes`), where its partners' boxes are. A shape that cannot be tessellated is kept
  /// whole (it may meet anything). `boxes`, when given, are the shapes' bounding boxes
  /// (kernel::bounding_box, one per shape) the caller already has; otherwise they are computed.
  void build(const std::vector<kernel::Shape>& shapes,
             const std::vector<std::pair<int, int>>& pairs,
             const std::vector<kernel::BoundingBox>* boxes = nullptr);

  /// False only when shapes i and j cannot be in contact (see the file comment).
  bool may_meet(std::size_t i, std::size_t j) const;

  /// Active voxels of shape i's shell (0 when not voxelised).
  long long active_voxels(std::size_t i) const;
  /// The margin of the shells (world units).
  double margin() const;
  /// Shapes kept whole because they could not be voxelised.
  std::size_t unvoxelised() const;
  /// Why nothing was voxelised (the OpenVDB module could not be loaded: every pair may then
  /// meet); empty when the culling ran.
  const std::string& unavailable() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace csgtile::assembly
