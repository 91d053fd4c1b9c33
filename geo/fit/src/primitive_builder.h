// The primitive builder (internal): from one region's detected surfaces to scene primitives.
// primitives.cpp holds the builder's run, curved primitives and the checks every primitive
// passes; box_primitives.cpp builds boxes from planes.
#pragma once

#include <array>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "fit_internal.h"

namespace csgtile::fit::detail {

using kernel::Location;
using kernel::PrimitiveSpec;
using kernel::PrimitiveType;
using kernel::Vec2;
using kernel::Vec3;

// A plane's points in its own frame: n its normal, (u, v) the sides of the smallest
// rectangle around its points.
struct PlanePatch {
  int shape = -1;
  std::vector<std::uint32_t> members;  // a connected piece of the shape's inliers
  Vec3 origin, n, u, v;
  double umin = 0, umax = 0, vmin = 0, vmax = 0;
  double coverage = 0.0;
  double sagitta = 0.0;  // how far its points bow out of the plane across its width
  bool used = false;
};

// The patch of `members` (a connected piece of plane `shape`, number `index`): its frame (u
// along the longer side of the smallest rectangle around them), extent, coverage of `cell`
// cells and how far it bows across (box_primitives.cpp).
PlanePatch make_patch(std::span<const Vec3> points, const DetectedShape& shape, int index,
                      std::vector<std::uint32_t> members, double cell);

// A rotation with columns x, y, x × y, made exactly orthonormal.
Eigen::Matrix3d frame(const Vec3& x, const Vec3& y);

// The location with this rotation and origin, or nullopt when it is no rigid motion.
std::optional<Location> placement(const Eigen::Matrix3d& rotation, const Vec3& origin);

// A box of `size` along the rotation's columns from `corner`, or nullopt as placement.
std::optional<PrimitiveSpec> box_spec(const Eigen::Matrix3d& rotation, const Vec3& corner,
                                      const Vec3& size);

// A box's surface area.
double box_area(const Vec3& size);

// A box in a seed plane's frame: [u0, u1] along u, [v0, v1] along v, [c0, c1] along n.
struct SeedBox {
  double u0 = 0, u1 = 0, v0 = 0, v1 = 0, c0 = 0, c1 = 0;
};

// The box `box` in the seed's frame (corner at (u0, v0, c0)), or nullopt as placement.
std::optional<PrimitiveSpec> seed_box_spec(const PlanePatch& seed, const SeedBox& box);

// The connectivity cell of a region's primitives: the RANSAC's cluster epsilon, else three
// times its epsilon.
inline double connectivity_cell(double cluster_epsilon, double epsilon) {
  return cluster_epsilon > 0.0 ? cluster_epsilon : 3.0 * epsilon;
}

class Builder {
 public:
  Builder(std::span<const Vec3> points, std::span<const Vec3> normals, const RansacResult& shapes,
          const PrimitiveOptions& o, const RansacOptions& ransac, int region)
      : points_(points),
        normals_(normals),
        shapes_(shapes),
        o_(o),
        ransac_(ransac),
        region_(region),
        used_(points.size(), 0) {
    cos_tol_ = std::cos(o.angle_tolerance_deg * std::numbers::pi / 180.0);
    cell_ = connectivity_cell(shapes.cluster_epsilon, ransac.epsilon);
    for (const Vec3& p : points) {
      if (p.allFinite()) region_box_.add(p);
    }
    // A footprint is evidence too: a building reaches over all of it, points or not.
    if (o.footprint != nullptr && !region_box_.empty()) {
      for (const auto& polygon : *o.footprint) {
        for (const kernel::Vec2& q : polygon.outer) {
          region_box_.add(Vec3(q.x(), q.y(), region_box_.min.z()));
        }
      }
    }
  }

  FittedPrimitives run();

 private:
  // How far a box reaches behind (c0 < 0) or before (c1 > 0) its seed plane, and the extent
  // across (v) of the opposite face when one was seen.
  struct Depth {
    double c0 = 0.0, c1 = 0.0;
    double v0 = INFINITY, v1 = -INFINITY;
  };
  // Which axis of the seed's frame a point's normal follows.
  enum class Facing : std::uint8_t { Normal, Across, Along, Other };
  struct Framed {
    double a = 0.0, b = 0.0, c = 0.0;  // along u, v, n of the seed
    Facing facing = Facing::Other;
  };
  std::vector<Framed> framed_near(const PlanePatch& seed, double across, double cos_normal) const;
  Depth box_depth(const PlanePatch& seed, double margin, double cos_normal) const;
  std::pair<double, double> box_length(const PlanePatch& seed, double c0, double c1, double v0,
                                       double v1, double tight, double cos_normal) const;
  bool round_section(const std::vector<std::uint32_t>& members, const PlanePatch& seed,
                     const std::array<double, 4>& section) const;
  void boxes();
  // The unused finite points within `box` grown by `grow` on every side, in index order.
  std::vector<std::uint32_t> unused_in(const PlanePatch& seed, const SeedBox& box,
                                       double grow) const;
  // Boxes seen in pieces joined into one member, members' ends into what they run into
  // (members.cpp).
  void join_members();
  // Elongated planes left without a box given the section of their parallel siblings, on the
  // side of the face whose centre line runs through a column's axis (members.cpp).
  void one_face_members();
  void curved(int index);
  void blocks();
  // What the proposal steps see of the region (points, shapes, what is used or absorbed).
  detail::ProposalInput proposal_input() const {
    detail::ProposalInput in;
    in.points = points_;
    in.normals = normals_;
    in.shapes = &shapes_;
    in.used = &used_;
    in.absorbed = &absorbed_;
    in.options = &o_;
    in.ransac = &ransac_;
    in.cell = cell_;
    return in;
  }
  std::string coaxial_overlap(const PrimitiveSpec& spec) const;
  // σ of the region's scan (estimate_noise where it is flattest), found once; 0 when the
  // region has too few points to tell.
  double region_sigma();
  bool take(const detail::Proposal& proposal);
  // When the roof partition split the region into houses (Proposal::house, which take()
  // leaves in ScenePrimitive::house as its number): every primitive's house named, those of
  // no house given the houses their boxes overlap (joined into one when several), else the
  // nearest; no house at all when one is left.
  void name_houses();
  // A building in its footprint carrying a dome: when the dome takes (nearly) all its points,
  // the dome on the footprint's prism up to the dome's base, else domed_roof. False, changing
  // nothing but the rejections, otherwise.
  bool domed_footprint(const detail::ProposalInput& in);
  // A dome over part of its footprint (`explained`: the points it and its drum take): the
  // roof partition of the rest, the dome (on a drum when its base stands above the roof)
  // standing on that roof. False, changing nothing but the rejections, otherwise.
  bool domed_roof(const detail::ProposalInput& in, const detail::Proposal& dome,
                  const std::vector<char>& explained);
  // The region's points, other than `own` (sorted), inside the primitive by more than `deep`
  // along each axis direction.
  long long points_deep_inside(const PrimitiveSpec& spec, double deep,
                               const std::vector<std::uint32_t>& own) const;
  void emit(PrimitiveSpec spec, const std::vector<std::uint32_t>& members, double area,
            const std::string& what, bool carried = false);

  std::span<const Vec3> points_;
  std::span<const Vec3> normals_;
  const RansacResult& shapes_;
  PrimitiveOptions o_;
  RansacOptions ransac_;
  int region_;
  double cos_tol_ = 1.0;
  double cell_ = 0.1;
  std::vector<char> used_;
  std::vector<char> absorbed_;  // per shape: part of a kept extrusion or revolution
  std::vector<PlanePatch> patches_;
  kernel::BoundingBox region_box_;  // of the region's finite points
  FittedPrimitives out_;
  std::optional<double> sigma_;  // region_sigma()
  // The points of each primitive in out_.primitives (what emit was given), in its order.
  std::vector<std::vector<std::uint32_t>> emitted_members_;
};

}  // namespace csgtile::fit::detail
