#pragma once
/// \file
/// OpenVDB overlap culling: each solid's interior, dilated by a margin that covers the voxel
/// size, the tessellation error and the tolerance, as a sparse voxel mask on one grid shared
/// by all solids. Two solids whose masks share no voxel cannot meet: culling is conservative
/// by construction (a point common to both lies in a voxel whose centre is within half a
/// voxel diagonal of both solids, and both masks hold every voxel centre that close).

#include <cstddef>
#include <memory>
#include <vector>

#include "csgtile/kernel/shape.h"

namespace csgtile::assembly {

class VoxelCuller {
 public:
  /// voxel_size: edge of a voxel (world units), > 0; tolerance: the contact tolerance.
  VoxelCuller(double voxel_size, double tolerance);
  ~VoxelCuller();
  VoxelCuller(VoxelCuller&&) noexcept;
  VoxelCuller& operator=(VoxelCuller&&) noexcept;

  /// Voxelises shapes[i] wherever needed[i] (all when `needed` is empty), in parallel.
  /// A shape that cannot be tessellated is kept whole (it may meet anything its box meets).
  void build(const std::vector<kernel::Shape>& shapes, const std::vector<bool>& needed = {});

  /// False only when the dilated interiors of shapes i and j share no voxel.
  bool may_meet(std::size_t i, std::size_t j) const;

  /// Active voxels of shape i's mask (0 when not voxelised or kept whole).
  long long active_voxels(std::size_t i) const;
  /// The dilation margin every mask carries (world units).
  double margin() const;
  /// Shapes kept whole because they could not be voxelised.
  std::size_t unvoxelised() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace csgtile::assembly
