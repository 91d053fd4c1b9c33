// OpenVDB overlap culling (see csgtile/assembly/voxel_cull.h). The shells are sparse
// OpenVDB masks filled by our own exact point–triangle distances (double precision: no
// float rounding of city coordinates), which for small solids is about 100 times faster
// than OpenVDB's mesh-to-volume and its fixed set-up. The only translation unit that
// includes OpenVDB: its headers are heavy.

#include "csgtile/assembly/voxel_cull.h"

#include <openvdb/openvdb.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <mutex>

#include "csgtile/kernel/bounding_box.h"
#include "csgtile/kernel/mass_properties.h"
#include "csgtile/kernel/tessellation.h"

namespace csgtile::assembly {

namespace {

// Shells are small and many (one per solid in a candidate pair): a shallow tree (root →
// 4³ internal → 8³ leaves holding only their active masks) instead of OpenVDB's default
// 5-4-3 layout, whose two internal levels cost about 0.6 MB per grid however few voxels it
// holds (3 000 shells took 2.6 GB that way).
using ShellTree = openvdb::tree::Tree3<openvdb::ValueMask, 2, 3>::Type;
using ShellGrid = openvdb::Grid<ShellTree>;

void initialise_openvdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

// The point of triangle (a, b, c) closest to p (by the Voronoi regions of its vertices,
// edges and face).
kernel::Vec3 closest_on_triangle(const kernel::Vec3& p, const kernel::Vec3& a,
                                 const kernel::Vec3& b, const kernel::Vec3& c) {
  const kernel::Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const kernel::Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  const kernel::Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

bool contains(const kernel::BoundingBox& outer, const kernel::BoundingBox& inner) {
  return !outer.empty() && !inner.empty() && (outer.min.array() <= inner.min.array()).all() &&
         (inner.max.array() <= outer.max.array()).all();
}

}  // namespace

struct VoxelCuller::Impl {
  double voxel = 0.5;
  double tolerance = 1e-7;
  double chordal = 0.1;
  double margin = 0.0;
  openvdb::math::Transform::Ptr transform;
  std::vector<kernel::BoundingBox> boxes;  // exact boxes, enlarged by the tolerance
  std::vector<ShellGrid::Ptr> masks;       // null: not voxelised
  std::vector<char> whole;                 // could not be voxelised: may meet anything
};

VoxelCuller::VoxelCuller(double voxel_size, double tolerance) : impl_(std::make_unique<Impl>()) {
  initialise_openvdb();
  impl_->voxel = voxel_size > 0 && std::isfinite(voxel_size) ? voxel_size : 0.5;
  impl_->tolerance = tolerance;
  impl_->chordal = impl_->voxel / 4;
  // Half a voxel diagonal (a contact point to its voxel's centre) + the mesh's distance from
  // the exact surface + the contact tolerance + 1% of a voxel for rounding.
  impl_->margin =
      std::sqrt(3.0) / 2 * impl_->voxel + impl_->chordal + tolerance + 0.01 * impl_->voxel;
  impl_->transform = openvdb::math::Transform::createLinearTransform(impl_->voxel);
}

VoxelCuller::~VoxelCuller() = default;
VoxelCuller::VoxelCuller(VoxelCuller&&) noexcept = default;
VoxelCuller& VoxelCuller::operator=(VoxelCuller&&) noexcept = default;

void VoxelCuller::build(const std::vector<kernel::Shape>& shapes,
                        const std::vector<std::pair<int, int>>& pairs,
                        const std::vector<kernel::BoundingBox>* boxes) {
  Impl& d = *impl_;
  const std::size_t n = shapes.size();
  d.masks.assign(n, nullptr);
  d.whole.assign(n, 0);
  d.boxes.assign(n, kernel::BoundingBox{});
  std::vector<char> used(n, 0);
  for (const auto& [a, b] : pairs)
    used[static_cast<std::size_t>(a)] = used[static_cast<std::size_t>(b)] = 1;
  tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) {
    if (!used[i] || shapes[i].is_null()) return;
    d.boxes[i] = boxes && i < boxes->size() ? (*boxes)[i] : kernel::bounding_box(shapes[i]);
    d.boxes[i].enlarge(d.tolerance);
  });
  // Where each shell matters: the overlaps of its box with its partners' boxes, grown by
  // the margin and a voxel diagonal (a contact point's voxel centre lies that close).
  std::vector<std::vector<kernel::BoundingBox>> regions(n);
  const double grow = d.margin + std::sqrt(3.0) * d.voxel;
  for (const auto& [a, b] : pairs) {
    const kernel::BoundingBox& ba = d.boxes[static_cast<std::size_t>(a)];
    const kernel::BoundingBox& bb = d.boxes[static_cast<std::size_t>(b)];
    if (!ba.intersects(bb)) continue;  // apart: the shells cannot meet, nor the boxes nest
    kernel::BoundingBox common;
    common.min = ba.min.cwiseMax(bb.min);
    common.max = ba.max.cwiseMin(bb.max);
    common.enlarge(grow);
    regions[static_cast<std::size_t>(a)].push_back(common);
    regions[static_cast<std::size_t>(b)].push_back(common);
  }
  tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) {
    if (regions[i].empty()) return;
    kernel::TessellationOptions options;
    options.chordal_tolerance = d.chordal;
    auto mesh = kernel::tessellate(shapes[i], options);
    if (!mesh.ok() || mesh->triangles.empty()) {
      d.whole[i] = 1;
      return;
    }
    // Voxels of the shell inside the regions, triangle by triangle: every voxel centre in
    // the triangle's box (grown by the margin) clipped to a region, kept when within the
    // margin of the triangle. Index coordinates are world / voxel (OpenVDB's linear
    // transform: voxel centres at integer coordinates).
    auto mask = ShellGrid::create();
    mask->setTransform(d.transform);
    auto access = mask->getAccessor();
    const double h = d.voxel, m2 = d.margin * d.margin;
    for (const auto& t : mesh->triangles) {
      const kernel::Vec3 &p0 = mesh->vertices[t[0]], &p1 = mesh->vertices[t[1]],
                         &p2 = mesh->vertices[t[2]];
      kernel::BoundingBox tb;
      tb.add(p0);
      tb.add(p1);
      tb.add(p2);
      tb.enlarge(d.margin);
      // Voxel centres farther than the margin from the triangle's plane are farther from the
      // triangle: skipped before the closest-point test (most of a sloped triangle's box).
      kernel::Vec3 normal = (p1 - p0).cross(p2 - p0);
      const double length = normal.norm();
      const bool flat = length > 0.0 && std::isfinite(length);
      if (flat) normal /= length;
      for (const kernel::BoundingBox& r : regions[i]) {
        if (!r.intersects(tb)) continue;
        const kernel::Vec3 lo = tb.min.cwiseMax(r.min), hi = tb.max.cwiseMin(r.max);
        const openvdb::Coord c0(static_cast<int>(std::ceil(lo.x() / h)),
                                static_cast<int>(std::ceil(lo.y() / h)),
                                static_cast<int>(std::ceil(lo.z() / h)));
        const openvdb::Coord c1(static_cast<int>(std::floor(hi.x() / h)),
                                static_cast<int>(std::floor(hi.y() / h)),
                                static_cast<int>(std::floor(hi.z() / h)));
        for (int x = c0.x(); x <= c1.x(); ++x) {
          for (int y = c0.y(); y <= c1.y(); ++y) {
            for (int z = c0.z(); z <= c1.z(); ++z) {
              const openvdb::Coord c(x, y, z);
              if (access.isValueOn(c)) continue;
              const kernel::Vec3 q(x * h, y * h, z * h);
              if (flat && std::abs(normal.dot(q - p0)) > d.margin) continue;
              if ((closest_on_triangle(q, p0, p1, p2) - q).squaredNorm() <= m2)
                access.setValueOn(c);
            }
          }
        }
      }
    }
    d.masks[i] = mask;
  });
}

bool VoxelCuller::may_meet(std::size_t i, std::size_t j) const {
  const Impl& d = *impl_;
  if (i >= d.masks.size() || j >= d.masks.size()) return true;
  if (d.whole[i] || d.whole[j]) return true;
  if (!d.boxes[i].intersects(d.boxes[j])) return false;
  // Nested solids: their boundaries need not come near each other.
  if (contains(d.boxes[i], d.boxes[j]) || contains(d.boxes[j], d.boxes[i])) return true;
  const ShellGrid* a = d.masks[i].get();
  const ShellGrid* b = d.masks[j].get();
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
  for (char w : impl_->whole) n += w ? 1 : 0;
  return n;
}

}  // namespace csgtile::assembly
