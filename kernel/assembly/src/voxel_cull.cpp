// OpenVDB overlap culling (see csgtile/assembly/voxel_cull.h): each solid tessellated here, its
// shell voxelised by the OpenVDB module (vdb_module.h), loaded when the first shells are built
// (or ahead of them, load_culling_in_background).

#include "csgtile/assembly/voxel_cull.h"

#include <tbb/parallel_for.h>

#include <array>
#include <cmath>
#include <cstdint>

#include "csgtile/kernel/bounding_box.h"
#include "csgtile/kernel/mass_properties.h"
#include "csgtile/kernel/module.h"
#include "csgtile/kernel/tessellation.h"
#include "vdb_module.h"

namespace csgtile::assembly {

namespace {

// The module takes the mesh's vertices, its triangles and the regions' boxes as the arrays of
// doubles and indices they are stored as.
static_assert(sizeof(kernel::Vec3) == 3 * sizeof(double));
static_assert(sizeof(std::array<std::uint32_t, 3>) == 3 * sizeof(std::uint32_t));
static_assert(sizeof(kernel::BoundingBox) == 6 * sizeof(double));

// The module's entry points, or why there are none.
struct VdbModule {
  CsgtileVdbShellBuild* build = nullptr;
  CsgtileVdbShellsMeet* meet = nullptr;
  CsgtileVdbShellVoxels* voxels = nullptr;
  CsgtileVdbShellFree* free = nullptr;
  std::string error;
};

const VdbModule& vdb_module() {
  static const VdbModule module = [] {
    VdbModule m;
    const kernel::Module& loaded = kernel::load_module(kVdbModuleFile, kVdbModuleAbi);
    m.build = kernel::module_function<CsgtileVdbShellBuild>(loaded, "csgtile_vdb_shell_build");
    m.meet = kernel::module_function<CsgtileVdbShellsMeet>(loaded, "csgtile_vdb_shells_meet");
    m.voxels = kernel::module_function<CsgtileVdbShellVoxels>(loaded, "csgtile_vdb_shell_voxels");
    m.free = kernel::module_function<CsgtileVdbShellFree>(loaded, "csgtile_vdb_shell_free");
    if (!loaded.error.empty()) {
      m.error = loaded.error;
    } else if (!m.build || !m.meet || !m.voxels || !m.free) {
      m.error = "the module " + loaded.path + " lacks its entry points";
    }
    return m;
  }();
  return module;
}

// A shell made by the module, freed by it.
struct Shell {
  void* tree = nullptr;
  Shell() = default;
  Shell(const Shell&) = delete;
  Shell& operator=(const Shell&) = delete;
  ~Shell() {
    if (tree != nullptr) vdb_module().free(tree);
  }
};

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
  std::vector<kernel::BoundingBox> boxes;     // exact boxes, enlarged by the tolerance
  std::vector<std::unique_ptr<Shell>> masks;  // null: not voxelised
  std::vector<char> whole;                    // could not be voxelised: may meet anything
  std::string unavailable;                    // why the module could not be used
};

std::jthread load_culling_in_background() {
  return kernel::load_module_in_background(kVdbModuleFile, kVdbModuleAbi);
}

VoxelCuller::VoxelCuller(double voxel_size, double tolerance) : impl_(std::make_unique<Impl>()) {
  impl_->voxel = voxel_size > 0 && std::isfinite(voxel_size) ? voxel_size : 0.5;
  impl_->tolerance = tolerance;
  impl_->chordal = impl_->voxel / 4;
  // Half a voxel diagonal (a contact point to its voxel's centre) + the mesh's distance from
  // the exact surface + the contact tolerance + 1% of a voxel for rounding.
  impl_->margin =
      std::sqrt(3.0) / 2 * impl_->voxel + impl_->chordal + tolerance + 0.01 * impl_->voxel;
}

VoxelCuller::~VoxelCuller() = default;
VoxelCuller::VoxelCuller(VoxelCuller&&) noexcept = default;
VoxelCuller& VoxelCuller::operator=(VoxelCuller&&) noexcept = default;

void VoxelCuller::build(const std::vector<kernel::Shape>& shapes,
                        const std::vector<std::pair<int, int>>& pairs,
                        const std::vector<kernel::BoundingBox>* boxes) {
  Impl& d = *impl_;
  const std::size_t n = shapes.size();
  d.masks.clear();
  d.masks.resize(n);
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
  const VdbModule& vdb = vdb_module();
  if (!vdb.error.empty()) {
    // Without the module nothing is voxelised: every shape may meet anything (the exact
    // tests decide); the assembly reports why (unavailable()).
    d.unavailable = vdb.error;
    for (std::size_t i = 0; i < n; ++i) d.whole[i] = regions[i].empty() ? 0 : 1;
    return;
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
    // Voxels of the shell inside the regions, triangle by triangle (the module): every voxel
    // centre in the triangle's box (grown by the margin) clipped to a region, kept when within
    // the margin of the triangle. The mesh and the regions are handed over as they are stored.
    const double* vertices = mesh->vertices.front().data();
    const std::uint32_t* triangles = mesh->triangles.front().data();
    const double* boxes_flat = regions[i].front().min.data();
    auto shell = std::make_unique<Shell>();
    shell->tree = vdb.build(vertices, mesh->vertices.size(), triangles, mesh->triangles.size(),
                            boxes_flat, regions[i].size(), d.voxel, d.margin);
    if (shell->tree == nullptr) {
      d.whole[i] = 1;
      return;
    }
    d.masks[i] = std::move(shell);
  });
}

bool VoxelCuller::may_meet(std::size_t i, std::size_t j) const {
  const Impl& d = *impl_;
  if (i >= d.masks.size() || j >= d.masks.size()) return true;
  if (d.whole[i] || d.whole[j]) return true;
  if (!d.boxes[i].intersects(d.boxes[j])) return false;
  // Nested solids: their boundaries need not come near each other.
  if (contains(d.boxes[i], d.boxes[j]) || contains(d.boxes[j], d.boxes[i])) return true;
  if (!d.masks[i] || !d.masks[j]) return true;  // not voxelised: nothing is known
  return vdb_module().meet(d.masks[i]->tree, d.masks[j]->tree) != 0;
}

long long VoxelCuller::active_voxels(std::size_t i) const {
  const Impl& d = *impl_;
  if (i >= d.masks.size() || !d.masks[i]) return 0;
  return vdb_module().voxels(d.masks[i]->tree);
}

double VoxelCuller::margin() const { return impl_->margin; }

const std::string& VoxelCuller::unavailable() const { return impl_->unavailable; }

std::size_t VoxelCuller::unvoxelised() const {
  std::size_t n = 0;
  for (char w : impl_->whole) n += w ? 1 : 0;
  return n;
}

}  // namespace csgtile::assembly
