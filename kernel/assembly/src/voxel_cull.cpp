// OpenVDB overlap culling (see csgtile/assembly/voxel_cull.h). The only translation unit
// that includes OpenVDB: its headers are heavy.

#include "csgtile/assembly/voxel_cull.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/LevelSetUtil.h>
#include <openvdb/tools/MeshToVolume.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <limits>
#include <mutex>

#include "csgtile/kernel/bounding_box.h"
#include "csgtile/kernel/tessellation.h"

namespace csgtile::assembly {

namespace {

void initialise_openvdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

}  // namespace

struct VoxelCuller::Impl {
  double voxel = 0.5;
  double tolerance = 1e-7;
  double chordal = 0.1;
  double margin = 0.0;
  openvdb::math::Transform::Ptr transform;
  std::vector<openvdb::BoolGrid::Ptr> masks;  // null: not voxelised
  std::vector<bool> whole;                    // could not be voxelised: may meet anything
};

VoxelCuller::VoxelCuller(double voxel_size, double tolerance) : impl_(std::make_unique<Impl>()) {
  initialise_openvdb();
  impl_->voxel = voxel_size > 0 && std::isfinite(voxel_size) ? voxel_size : 0.5;
  impl_->tolerance = tolerance;
  impl_->chordal = impl_->voxel / 4;
  // Half a voxel diagonal (a contact point to its voxel's centre) + the mesh's distance from
  // the exact surface + the contact tolerance; 1% of a voxel covers the float coordinates.
  impl_->margin = std::sqrt(3.0) / 2 * impl_->voxel + impl_->chordal + tolerance + 0.01 * impl_->voxel;
  impl_->transform = openvdb::math::Transform::createLinearTransform(impl_->voxel);
}

VoxelCuller::~VoxelCuller() = default;
VoxelCuller::VoxelCuller(VoxelCuller&&) noexcept = default;
VoxelCuller& VoxelCuller::operator=(VoxelCuller&&) noexcept = default;

void VoxelCuller::build(const std::vector<kernel::Shape>& shapes, const std::vector<bool>& needed) {
  Impl& d = *impl_;
  d.masks.assign(shapes.size(), nullptr);
  d.whole.assign(shapes.size(), false);
  const float band = static_cast<float>(std::ceil(d.margin / d.voxel) + 2);
  tbb::parallel_for(std::size_t{0}, shapes.size(), [&](std::size_t i) {
    if (!needed.empty() && !needed[i]) return;
    kernel::TessellationOptions options;
    options.chordal_tolerance = d.chordal;
    auto mesh = kernel::tessellate(shapes[i], options);
    if (!mesh.ok() || mesh->triangles.empty() || !kernel::mesh_is_closed(mesh.value())) {
      d.whole[i] = true;
      return;
    }
    std::vector<openvdb::Vec3s> points;
    points.reserve(mesh->vertices.size());
    for (const kernel::Vec3& p : mesh->vertices) {
      points.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
    }
    std::vector<openvdb::Vec3I> triangles;
    triangles.reserve(mesh->triangles.size());
    for (const auto& t : mesh->triangles) triangles.emplace_back(t[0], t[1], t[2]);
    const std::vector<openvdb::Vec4I> quads;
    // Interior filled (the band inside is unbounded), exterior band wider than the margin.
    auto sdf = openvdb::tools::meshToSignedDistanceField<openvdb::FloatGrid>(
        *d.transform, points, triangles, quads, band, std::numeric_limits<float>::max());
    auto mask = openvdb::tools::sdfInteriorMask(*sdf, static_cast<float>(d.margin));
    mask->tree().voxelizeActiveTiles();  // leaves only: pair tests compare leaf masks
    mask->setTransform(d.transform);
    d.masks[i] = mask;
  });
}

bool VoxelCuller::may_meet(std::size_t i, std::size_t j) const {
  const Impl& d = *impl_;
  if (i >= d.masks.size() || j >= d.masks.size()) return true;
  if (d.whole[i] || d.whole[j]) return true;
  const openvdb::BoolGrid* a = d.masks[i].get();
  const openvdb::BoolGrid* b = d.masks[j].get();
  if (!a || !b) return true;  // not voxelised: nothing is known
  if (a->tree().leafCount() > b->tree().leafCount()) std::swap(a, b);
  for (auto leaf = a->tree().cbeginLeaf(); leaf; ++leaf) {
    const auto* other = b->tree().probeConstLeaf(leaf->origin());
    if (other && !(leaf->getValueMask() & other->getValueMask()).isOff()) return true;
  }
  return false;
}

long long VoxelCuller::active_voxels(std::size_t i) const {
  const Impl& d = *impl_;
  if (i >= d.masks.size() || !d.masks[i]) return 0;
  return static_cast<long long>(d.masks[i]->activeVoxelCount());
}

double VoxelCuller::margin() const { return impl_->margin; }

std::size_t VoxelCuller::unvoxelised() const {
  std::size_t n = 0;
  for (bool w : impl_->whole) n += w ? 1 : 0;
  return n;
}

}  // namespace csgtile::assembly
