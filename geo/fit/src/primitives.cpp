// From detected surfaces to scene primitives. Boxes come from planes: a seed plane whose
// points fill their bounding rectangle, the nearest parallel plane facing it across the box
// (or, when none is seen, the points of orthogonal planes along its rectangle), so that a beam
// scanned on two or three sides is one box. Curved surfaces are bounded by their inliers.
// Every primitive is built as a kernel solid and checked before it is kept.

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numbers>
#include <set>
#include <tuple>

#include "csgtile/kernel/check.h"
#include "csgtile/kernel/mass_properties.h"
#include "disjoint_sets.h"
#include "fit_internal.h"
#include "plane2d.h"
#include "primitive_builder.h"
#include "synth/ray_internal.h"

namespace csgtile::fit {

namespace detail {

namespace {

// Share of voxels of size `cell` the points occupy, against the area of the primitive's
// surface: an estimate of how much of the primitive the scan saw.
double coverage_of(std::span<const Vec3> points, const std::vector<std::uint32_t>& members,
                   double cell, double area) {
  if (!(area > 0.0) || members.empty()) return 0.0;
  std::set<std::tuple<long long, long long, long long>> voxels;
  for (auto i : members) {
    voxels.emplace(detail::cell_index(points[i].x(), cell), detail::cell_index(points[i].y(), cell),
                   detail::cell_index(points[i].z(), cell));
  }
  return std::min(1.0, static_cast<double>(voxels.size()) * cell * cell / area);
}

}  // namespace

// A rotation with columns x, y, x × y, made exactly orthonormal.
Eigen::Matrix3d frame(const Vec3& x, const Vec3& y) {
  const Vec3 ex = x.normalized();
  const Vec3 ey = (y - y.dot(ex) * ex).normalized();
  Eigen::Matrix3d r;
  r.col(0) = ex;
  r.col(1) = ey;
  r.col(2) = ex.cross(ey);
  return r;
}

std::optional<Location> placement(const Eigen::Matrix3d& rotation, const Vec3& origin) {
  kernel::Matrix34 q;
  q.leftCols<3>() = rotation;
  q.col(3) = origin;
  auto loc = Location::from_matrix(q);
  if (!loc.ok()) return std::nullopt;
  return loc.value();
}

std::optional<PrimitiveSpec> box_spec(const Eigen::Matrix3d& rotation, const Vec3& corner,
                                      const Vec3& size) {
  auto loc = placement(rotation, corner);
  if (!loc) return std::nullopt;
  PrimitiveSpec spec;
  spec.type = PrimitiveType::Box;
  spec.size = size;
  spec.placement = *loc;
  return spec;
}

double box_area(const Vec3& size) {
  return 2.0 * (size.x() * size.y() + size.y() * size.z() + size.x() * size.z());
}

void Builder::emit(PrimitiveSpec spec, const std::vector<std::uint32_t>& members, double area,
                   const std::string& what, bool carried) {
  auto solid = kernel::build_primitive(spec, o_.linear_tolerance);
  if (!solid.ok()) {
    out_.rejected.push_back({what, std::string("kernel: ") + solid.error().message,
                             static_cast<long long>(members.size())});
    return;
  }
  const auto report = kernel::check_shape(solid.value());
  if (!report.valid()) {
    out_.rejected.push_back({what, std::string("invalid solid: ") + report.issues.front().message,
                             static_cast<long long>(members.size())});
    return;
  }
  const double coverage = coverage_of(points_, members, cell_, area);
  // A carried primitive's support is the one it stands under.
  if (std::string why = detail::unsupported(spec, kernel::bounding_box(solid.value()),
                                            carried ? 1.0 : coverage, region_box_, cell_, o_);
      !why.empty()) {
    out_.rejected.push_back({what, std::move(why), static_cast<long long>(members.size())});
    return;
  }
  if (!carried) {
    if (std::string why = detail::flat_strips(spec, points_, members, region_sigma(), cell_);
        !why.empty()) {
      out_.rejected.push_back({what, std::move(why), static_cast<long long>(members.size())});
      return;
    }
  }
  if (!carried && o_.footprint == nullptr &&
      (spec.type == PrimitiveType::Box || spec.type == PrimitiveType::Extrusion)) {
    // A solid's inside is never seen: a surface's worth of points (min_points) measured deep
    // inside it (beyond the noise margin from every side) are another object's, and the solid
    // claims space the scan saw through (a block over the bays of a frame). A building in its
    // footprint stands on it whatever it holds.
    const double deep = std::max(4.0 * ransac_.epsilon, 0.5 * cell_);
    const long long inside = points_deep_inside(spec, deep, members);
    if (inside >= std::max<long long>(ransac_.min_points, 3)) {
      out_.rejected.push_back(
          {what,
           std::to_string(inside) + " points (its own: " + std::to_string(members.size()) +
               ") lie deep inside it (more than " + std::to_string(deep) + " from its boundary)",
           static_cast<long long>(members.size())});
      return;
    }
  }
  geo::ScenePrimitive p;
  p.spec = std::move(spec);
  p.id = "r" + std::to_string(region_) + "-" + std::to_string(out_.primitives.size());
  geo::FitQuality q;
  q.inliers = static_cast<long long>(members.size());
  // The RMS distance of its points to its solid (the model), on a mesh finer than the fit's
  // tolerance, and the share within 2σ of it; when that cannot be measured, to the surfaces
  // their RANSAC shapes found.
  const double chordal = std::clamp(0.25 * ransac_.epsilon, 0.001, 0.05);
  const double sigma = region_sigma();
  double within = 0.0;
  if (const auto fit = detail::boundary_fit(solid.value(), points_, members, chordal, 2 * sigma)) {
    q.rms = fit->rms;
    within = fit->share_near;
  } else {
    double sum = 0.0;
    std::size_t counted = 0, near = 0;
    for (auto i : members) {
      const int s = shapes_.assignment[i];
      if (s < 0) continue;
      const double d =
          surface_distance(shapes_.shapes[static_cast<std::size_t>(s)].surface, points_[i]);
      sum += d * d;
      ++counted;
      if (std::abs(d) <= 2 * sigma) ++near;
    }
    q.rms = counted > 0 ? std::sqrt(sum / static_cast<double>(counted)) : 0.0;
    within = counted > 0 ? static_cast<double>(near) / static_cast<double>(counted) : 0.0;
  }
  if (sigma > 0.0) {
    q.sigma = sigma;
    q.within_2sigma = within;
  }
  q.coverage = coverage;
  p.quality = q;
  ++out_.per_type[static_cast<std::size_t>(p.spec.type)];
  out_.assigned_points += q.inliers;
  for (auto i : members) used_[i] = 1;
  out_.primitives.push_back(std::move(p));
  emitted_members_.push_back(members);
}

long long Builder::points_deep_inside(const PrimitiveSpec& spec, double deep,
                                      const std::vector<std::uint32_t>& own) const {
  std::vector<std::uint32_t> sorted_copy;
  const std::vector<std::uint32_t>* sorted = &own;
  if (!std::is_sorted(own.begin(), own.end())) {
    sorted_copy = own;
    std::sort(sorted_copy.begin(), sorted_copy.end());
    sorted = &sorted_copy;
  }
  const auto prepared = geo::detail::prepare_primitive(spec);
  const kernel::BoundingBox& box = prepared.world_bounds;
  const std::array<Vec3, 6> steps{Vec3(deep, 0, 0),  Vec3(-deep, 0, 0), Vec3(0, deep, 0),
                                  Vec3(0, -deep, 0), Vec3(0, 0, deep),  Vec3(0, 0, -deep)};
  long long count = 0;
  for (std::uint32_t i = 0; i < points_.size(); ++i) {
    const Vec3& q = points_[i];
    if (!q.allFinite() || q.x() < box.min.x() + deep || q.x() > box.max.x() - deep ||
        q.y() < box.min.y() + deep || q.y() > box.max.y() - deep || q.z() < box.min.z() + deep ||
        q.z() > box.max.z() - deep || !geo::detail::primitive_contains(prepared, q)) {
      continue;
    }
    bool deep_inside = true;
    for (const Vec3& step : steps) {
      if (!geo::detail::primitive_contains(prepared, q + step)) {
        deep_inside = false;
        break;
      }
    }
    if (!deep_inside) continue;
    // Its own points count when the RANSAC found them on a curved surface: a column inside a
    // block is no part of it.
    const int shape = i < shapes_.assignment.size() ? shapes_.assignment[i] : -1;
    const bool curved =
        shape >= 0 &&
        shapes_.shapes[static_cast<std::size_t>(shape)].surface.type != ShapeType::Plane;
    count += curved || !std::binary_search(sorted->begin(), sorted->end(), i) ? 1 : 0;
  }
  return count;
}

void Builder::curved(int index) {
  const DetectedShape& shape = shapes_.shapes[static_cast<std::size_t>(index)];
  const Surface& s = shape.surface;
  const std::string what = std::string(shape_type_name(s.type)) + " " + std::to_string(index);
  std::vector<std::uint32_t> members;
  for (auto i : shape.inliers) {
    if (!used_[i]) members.push_back(i);
  }
  if (static_cast<long long>(members.size()) < ransac_.min_points) {
    out_.rejected.push_back(
        {what, "inside an earlier primitive", static_cast<long long>(members.size())});
    return;
  }
  PrimitiveSpec spec;
  Vec3 e1, e2;
  detail::orthonormal_basis(s.axis, e1, e2);
  const Eigen::Matrix3d rot = frame(e1, e2);  // local z along the axis
  double t0 = INFINITY, t1 = -INFINITY;
  for (auto i : members) {
    const double t = (points_[i] - s.point).dot(s.axis);
    t0 = std::min(t0, t);
    t1 = std::max(t1, t);
  }
  if (s.type == ShapeType::Cylinder || s.type == ShapeType::Cone || s.type == ShapeType::Torus) {
    // Share of 10° sectors around the axis holding inliers.
    std::array<bool, 36> sector{};
    for (auto i : members) {
      const Vec3 d = points_[i] - s.point;
      const double phi = std::atan2(d.dot(e2), d.dot(e1));
      const auto k = static_cast<std::size_t>(
          std::clamp((phi + std::numbers::pi) / (2.0 * std::numbers::pi) * 36.0, 0.0, 35.0));
      sector[k] = true;
    }
    const double span = 10.0 * static_cast<double>(std::count(sector.begin(), sector.end(), true));
    if (span < o_.min_angular_span_deg) {
      out_.rejected.push_back(
          {what,
           "inliers span " + std::to_string(static_cast<int>(span)) + " degrees around the axis",
           static_cast<long long>(members.size())});
      return;
    }
    if (s.type != ShapeType::Torus && t1 - t0 < 2.0 * cell_) {
      out_.rejected.push_back({what, "shorter than two connectivity cells along the axis",
                               static_cast<long long>(members.size())});
      return;
    }
  }
  double area = 0.0;
  switch (s.type) {
    case ShapeType::Plane:
      return;
    case ShapeType::Cylinder: {
      spec.type = PrimitiveType::Cylinder;
      spec.radius = s.radius;
      spec.height = t1 - t0;
      auto loc = placement(rot, s.point + t0 * s.axis);
      if (!loc) return;
      spec.placement = *loc;
      area = 2.0 * std::numbers::pi * s.radius * spec.height;
      break;
    }
    case ShapeType::Cone: {
      // Radii where the inliers start and end along the axis, measured from the apex.
      t0 = std::max(t0, 0.0);
      spec.type = PrimitiveType::Cone;
      spec.radius = t0 * std::tan(s.angle);
      spec.radius2 = t1 * std::tan(s.angle);
      spec.height = t1 - t0;
      auto loc = placement(rot, s.point + t0 * s.axis);
      if (!loc) return;
      spec.placement = *loc;
      area = std::numbers::pi * (spec.radius + spec.radius2) * spec.height / std::cos(s.angle);
      break;
    }
    case ShapeType::Sphere: {
      spec.type = PrimitiveType::Sphere;
      spec.radius = s.radius;
      auto loc = placement(Eigen::Matrix3d::Identity(), s.point);
      if (!loc) return;
      spec.placement = *loc;
      area = 4.0 * std::numbers::pi * s.radius * s.radius;
      break;
    }
    case ShapeType::Torus: {
      spec.type = PrimitiveType::Torus;
      spec.radius = s.radius;
      spec.radius2 = s.radius2;
      auto loc = placement(rot, s.point);
      if (!loc) return;
      spec.placement = *loc;
      area = 4.0 * std::numbers::pi * std::numbers::pi * s.radius * s.radius2;
      break;
    }
  }
  if (spec.type == PrimitiveType::Cylinder || spec.type == PrimitiveType::Cone) {
    // One piece per axis: a round tower split by the RANSAC into cones (one inverted) keeps
    // the earlier, larger one.
    const std::string other = coaxial_overlap(spec);
    if (!other.empty()) {
      out_.rejected.push_back(
          {what, "overlaps the coaxial " + other, static_cast<long long>(members.size())});
      return;
    }
  }
  emit(std::move(spec), members, area, what);
}

// The id of a kept cylinder or cone on the same axis as `spec` (directions within the angle
// tolerance, axes within half the larger radius, or 2 ε, of each other) whose extent along
// the axis overlaps it; empty when none.
std::string Builder::coaxial_overlap(const PrimitiveSpec& spec) const {
  const Vec3 b = spec.placement.rotation().col(2).normalized();
  const Vec3 pb = spec.placement.translation();
  const double rb = std::max(spec.radius, spec.type == PrimitiveType::Cone ? spec.radius2 : 0.0);
  for (const auto& p : out_.primitives) {
    const PrimitiveSpec& q = p.spec;
    if (q.type != PrimitiveType::Cylinder && q.type != PrimitiveType::Cone) continue;
    const Vec3 a = q.placement.rotation().col(2).normalized();
    if (std::abs(a.dot(b)) < cos_tol_) continue;
    const Vec3 pa = q.placement.translation();
    const double ra = std::max(q.radius, q.type == PrimitiveType::Cone ? q.radius2 : 0.0);
    const double reach = std::max(0.5 * std::max(ra, rb), 2.0 * ransac_.epsilon);
    const Vec3 qb = pb + spec.height * b;
    auto off_axis = [&](const Vec3& x) {
      const Vec3 d = x - pa;
      return (d - d.dot(a) * a).norm();
    };
    if (off_axis(pb) > reach || off_axis(qb) > reach) continue;
    const double t0 = (pb - pa).dot(a), t1 = (qb - pa).dot(a);
    if (std::min(std::max(t0, t1), q.height) > std::max(std::min(t0, t1), 0.0)) return p.id;
  }
  return {};
}

// A proposal of several shapes (extrusion, revolution) kept when its solid is valid; its
// shapes then make nothing of their own. True when kept.
bool Builder::take(const detail::Proposal& proposal) {
  const std::size_t before = out_.primitives.size();
  emit(proposal.spec, proposal.members, proposal.area, proposal.what, proposal.carried);
  if (out_.primitives.size() == before) return false;
  for (int s : proposal.shapes) absorbed_[static_cast<std::size_t>(s)] = 1;
  // Its house's number until name_houses names the region's houses.
  if (proposal.house >= 0) out_.primitives.back().house = std::to_string(proposal.house);
  return true;
}

void Builder::name_houses() {
  auto& prims = out_.primitives;
  // take() left each partition part's house as its number; renumbered in the order of their
  // first primitive.
  std::map<int, int> number;
  std::vector<int> house(prims.size(), -1);
  for (std::size_t k = 0; k < prims.size(); ++k) {
    if (prims[k].house.empty()) continue;
    house[k] =
        number.emplace(std::stoi(prims[k].house), static_cast<int>(number.size())).first->second;
    prims[k].house.clear();
  }
  if (number.size() < 2) return;
  // A primitive of no house (a block of leftover points, a dome, a roof part) goes with the
  // houses whose primitives' boxes (in x, y) overlap its own by a tenth of its box or more —
  // those houses become one, so that no two buildings overlap — else with the house it
  // overlaps most, else the nearest.
  std::vector<kernel::BoundingBox> box(prims.size());
  for (std::size_t k = 0; k < prims.size(); ++k) {
    box[k] = geo::detail::prepare_primitive(prims[k].spec).world_bounds;
  }
  DisjointSets sets(number.size());
  auto root = [&sets](int x) { return static_cast<int>(sets.root(static_cast<std::size_t>(x))); };
  const std::vector<int> own = house;
  for (std::size_t k = 0; k < prims.size(); ++k) {
    if (own[k] >= 0 || box[k].empty()) continue;
    const double area =
        std::max((box[k].max.x() - box[k].min.x()) * (box[k].max.y() - box[k].min.y()), 1e-12);
    std::map<int, double> overlap;  // house -> overlap of its primitives' boxes with box[k]
    double nearest = INFINITY;
    int near = -1;
    for (std::size_t m = 0; m < prims.size(); ++m) {
      if (own[m] < 0 || box[m].empty()) continue;
      const double dx =
          std::min(box[k].max.x(), box[m].max.x()) - std::max(box[k].min.x(), box[m].min.x());
      const double dy =
          std::min(box[k].max.y(), box[m].max.y()) - std::max(box[k].min.y(), box[m].min.y());
      if (dx > 0.0 && dy > 0.0) {
        overlap[own[m]] += dx * dy;
      } else if (const double gap = std::hypot(std::min(dx, 0.0), std::min(dy, 0.0));
                 gap < nearest) {
        nearest = gap;
        near = own[m];
      }
    }
    int chosen = -1;
    double most = 0.0;
    for (const auto& [h, a] : overlap) {
      if (a > most) {
        most = a;
        chosen = h;
      }
    }
    for (const auto& [h, a] : overlap) {
      if (h != chosen && a >= 0.1 * area) {
        sets.join(static_cast<std::size_t>(h), static_cast<std::size_t>(chosen));
      }
    }
    house[k] = chosen >= 0 ? chosen : near;
  }
  // The houses left after the joins, numbered again in the order of their first primitive.
  std::map<int, int> renumber;
  for (std::size_t k = 0; k < prims.size(); ++k) {
    if (house[k] < 0) continue;
    house[k] = renumber.emplace(root(house[k]), static_cast<int>(renumber.size())).first->second;
  }
  if (renumber.size() < 2) return;
  for (std::size_t k = 0; k < prims.size(); ++k) {
    if (house[k] >= 0) {
      prims[k].house = "r" + std::to_string(region_) + "-h" + std::to_string(house[k]);
    }
  }
}

double Builder::region_sigma() {
  if (!sigma_) {
    // The RANSAC's own estimate when it derived its epsilon, else the same estimate (the 5 %
    // quantile of the neighbourhoods' RMS distance to their plane) over the region's points:
    // from the RANSAC's neighbour sample when it held them all, else measured here.
    double sigma = shapes_.noise;
    if (!(sigma > 0.0) && shapes_.plane_noise) {
      sigma = *shapes_.plane_noise;
    } else if (!(sigma > 0.0)) {
      std::vector<std::uint32_t> all(points_.size());
      for (std::size_t i = 0; i < all.size(); ++i) all[i] = static_cast<std::uint32_t>(i);
      sigma = detail::estimate_noise(points_, all, 0.05);
    }
    sigma_ = std::isfinite(sigma) && sigma > 0.0 ? sigma : 0.0;
  }
  return *sigma_;
}

FittedPrimitives Builder::run() {
  absorbed_.assign(shapes_.shapes.size(), 0);
  const detail::ProposalInput in = proposal_input();
  if (o_.footprint != nullptr && !o_.footprint->empty()) {
    // A building in its footprint: a dome on it, else its roof partition, else the
    // footprint's block; nothing else (one building per footprint, standing exactly on it).
    if (domed_footprint(in)) return std::move(out_);
    bool any = false;
    for (const auto& p : detail::propose_roof_partition(in, out_.rejected)) any = take(p) || any;
    if (!any) {
      for (const auto& p : detail::propose_footprint_block(in, out_.rejected)) take(p);
    }
    return std::move(out_);
  }
  if (o_.extrusions) {
    // Domes first: their points are no roof planes'. A drum only under its kept dome.
    bool dome_kept = false;
    for (const auto& p : detail::propose_domes(in, out_.rejected)) {
      if (!p.carried) {
        dome_kept = take(p);
      } else if (dome_kept) {
        take(p);
      }
    }
  }
  if (o_.revolutions) {
    for (const auto& p : detail::propose_revolutions(in, out_.rejected)) take(p);
  }
  if (o_.extrusions && o_.roof_partition) {
    const auto parts = detail::propose_roof_partition(in, out_.rejected);
    for (const auto& p : parts) take(p);
    if (!parts.empty()) {
      // Shapes most of whose points the parts took make nothing of their own.
      for (std::size_t s = 0; s < shapes_.shapes.size(); ++s) {
        const auto& inl = shapes_.shapes[s].inliers;
        std::size_t taken = 0;
        for (auto i : inl) taken += used_[i] ? 1 : 0;
        if (2 * taken >= inl.size()) absorbed_[s] = 1;
      }
    }
  }
  if (o_.extrusions) {
    // One at a time: each kept extrusion takes its walls, the next is sought among the rest.
    for (int k = 0; k < 8; ++k) {
      const auto p = detail::propose_extrusion(in, out_.rejected);
      if (!p || !take(*p)) break;
    }
    for (int k = 0; k < 8; ++k) {
      const auto p = detail::propose_roof_extrusion(in, out_.rejected);
      if (!p || !take(*p)) break;
    }
    for (const auto& p : detail::propose_pitched_roofs(in, out_.rejected)) take(p);
    for (const auto& p : detail::propose_roof_parts(in, out_.rejected)) take(p);
  }
  if (o_.boxes) boxes();
  for (std::size_t s = 0; s < shapes_.shapes.size(); ++s) {
    const ShapeType type = shapes_.shapes[s].surface.type;
    if (absorbed_[s]) continue;
    if (type == ShapeType::Plane) {
      if (!o_.boxes) {
        out_.rejected.push_back({"plane " + std::to_string(s), "planes alone are not primitives",
                                 static_cast<long long>(shapes_.shapes[s].inliers.size())});
      }
      continue;
    }
    curved(static_cast<int>(s));
  }
  if (o_.boxes) {
    one_face_members();
    join_members();
  }
  if (o_.extrusions) blocks();
  name_houses();
  return std::move(out_);
}

// The region's points no kept primitive explains (inside one, or up to half a metre above
// it) become LoD1.2 blocks (blocks.cpp).
void Builder::blocks() {
  std::vector<geo::detail::PreparedPrimitive> kept;
  for (const auto& p : out_.primitives) kept.push_back(geo::detail::prepare_primitive(p.spec));
  const double above = std::max(0.5, 3.0 * ransac_.epsilon);
  auto explained = [&](const Vec3& q) {
    for (const auto& p : kept) {
      const kernel::BoundingBox& b = p.world_bounds;
      if (q.x() < b.min.x() || q.x() > b.max.x() || q.y() < b.min.y() || q.y() > b.max.y() ||
          q.z() < b.min.z() || q.z() > b.max.z() + above) {
        continue;
      }
      if (geo::detail::primitive_contains(p, q) ||
          geo::detail::primitive_contains(p, q - Vec3(0.0, 0.0, above))) {
        return true;
      }
    }
    return false;
  };
  for (const auto& p : detail::propose_blocks(proposal_input(), explained, out_.rejected)) {
    take(p);
  }
}

}  // namespace detail

FittedPrimitives primitives_from_shapes(std::span<const kernel::Vec3> points,
                                        std::span<const kernel::Vec3> normals,
                                        const RansacResult& shapes, const PrimitiveOptions& options,
                                        const RansacOptions& ransac, int region) {
  if (shapes.assignment.size() != points.size() ||
      (!normals.empty() && normals.size() != points.size())) {
    FittedPrimitives none;
    none.rejected.push_back({"region " + std::to_string(region),
                             "shapes or normals do not match the points (" +
                                 std::to_string(shapes.assignment.size()) + " assignments, " +
                                 std::to_string(normals.size()) + " normals, " +
                                 std::to_string(points.size()) + " points)",
                             static_cast<long long>(points.size())});
    return none;
  }
  detail::Builder builder(points, normals, shapes, options, ransac, region);
  return builder.run();
}

}  // namespace csgtile::fit
