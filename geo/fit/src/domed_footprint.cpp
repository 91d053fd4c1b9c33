// Buildings in their footprint that carry a dome: the dome over the whole footprint on the
// footprint's prism, or over part of it on the roof partition of the rest (issue #18: "domes,
// towers ... use the paper's curved primitives").

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>

#include "csgtile/kernel/check.h"
#include "fit_internal.h"
#include "plane2d.h"
#include "primitive_builder.h"

namespace csgtile::fit::detail {

namespace {

// Points around a dome's base circle, between the roof and the base, that make its drum's
// wall seen.
constexpr long long kMinDrumWall = 5;

// How far a dome's rim keeps from walls, or sinks into roofs of several heights: a centimetre
// (ten tolerances where the tolerance is coarser).
double contact_step(const PrimitiveOptions& o) { return std::max(0.01, 10.0 * o.linear_tolerance); }

// The height of the roof the parts (extrusions clipped by their roof planes, placed upright)
// give at `xy`: the highest over the parts whose outline holds it; nullopt where none does.
std::optional<double> roof_top_at(const std::vector<Proposal>& parts, const Vec2& xy) {
  std::optional<double> top;
  for (const Proposal& p : parts) {
    const kernel::PrimitiveSpec& s = p.spec;
    if (s.type != PrimitiveType::Extrusion) continue;
    if ((s.placement.rotation() * Vec3::UnitZ() - Vec3::UnitZ()).norm() > 1e-9) continue;
    const Vec3 local = s.placement.inverse().apply_point(Vec3(xy.x(), xy.y(), 0.0));
    if (!inside_polygon(Vec2(local.x(), local.y()), s.profile, s.holes)) continue;
    double z = s.height;
    for (const Eigen::Vector4d& c : s.clips) {
      if (c.z() > 1e-9) z = std::min(z, (c.w() - c.x() * local.x() - c.y() * local.y()) / c.z());
    }
    const double world = s.placement.apply_point(Vec3(local.x(), local.y(), z)).z();
    top = top ? std::max(*top, world) : world;
  }
  return top;
}

}  // namespace

bool Builder::domed_footprint(const ProposalInput& in) {
  std::vector<Rejection> reasons;
  const auto domes = propose_domes(in, reasons);
  if (domes.empty() || domes.front().carried) {
    out_.rejected.insert(out_.rejected.end(), reasons.begin(), reasons.end());
    return false;
  }
  const Proposal& dome = domes.front();
  const Vec3 c = dome.spec.placement.apply_point(Vec3::Zero());
  const Vec2 axis(c.x(), c.y());
  double inside = INFINITY;  // the axis's distance to the footprint's boundary
  bool holds = false;
  for (const geo::FootprintPolygon& fp : *o_.footprint) {
    holds = holds || inside_polygon(axis, fp.outer, fp.holes);
    inside = std::min(inside, boundary_distance(axis, fp.outer, fp.holes));
  }
  if (!holds) {
    out_.rejected.push_back({dome.what, "no domed building: its axis lies outside its footprint",
                             static_cast<long long>(dome.members.size())});
    return false;
  }
  // The points the dome and its drum (the wall the prism stands for) explain.
  std::vector<char> explained(points_.size(), 0);
  for (std::size_t k = 0; k < domes.size() && (k == 0 || domes[k].carried); ++k) {
    for (auto i : domes[k].members) explained[i] = 1;
  }
  long long rest = 0;
  for (std::uint32_t i = 0; i < points_.size(); ++i) rest += !used_[i] && !explained[i] ? 1 : 0;
  const long long allowed =
      std::max<long long>(ransac_.min_points, static_cast<long long>(0.05 * points_.size()));
  if (rest > allowed) return domed_roof(in, dome, explained);
  // The dome stands on the footprint's prism: its cut is a disc a centimetre within the
  // footprint (raised where the footprint is narrower than the dome's base: a round footprint
  // digitised as a polygon is no circle), the prism's top that disc's plane. The dome's rim
  // then lies in the prism's top, clear of its walls (no wall meets the sphere nearly tangent).
  const double step = contact_step(o_);
  Proposal on = dome;
  const double radius = on.spec.radius;
  auto [base, disc] = cap_base(on);
  if (disc > inside - step) {
    disc = std::max(inside - step, 0.0);
    base = c.z() + std::sqrt(std::max(radius * radius - disc * disc, 0.0));
    cut_dome(on, base);
  }
  if (!(disc > step)) return false;
  auto prisms = propose_footprint_block(in, out_.rejected, base);
  if (prisms.empty() || !take(on)) return false;
  for (auto& p : prisms) {
    std::erase_if(p.members, [&](std::uint32_t i) { return used_[i] != 0; });
    take(p);
  }
  return true;
}

bool Builder::domed_roof(const ProposalInput& in, const Proposal& dome,
                         const std::vector<char>& explained) {
  auto refuse = [&](const std::string& why) {
    out_.rejected.push_back(
        {dome.what, "no dome on the roof: " + why, static_cast<long long>(dome.members.size())});
    return false;
  };
  // The roof partition of the rest of the footprint: the dome's points (and its drum's) take
  // no part in it; the cells under the dome take their neighbours' roofs.
  std::vector<char> rest_used(used_.size());
  for (std::size_t i = 0; i < used_.size(); ++i) rest_used[i] = used_[i] || explained[i];
  ProposalInput rest = in;
  rest.used = &rest_used;
  std::vector<Rejection> reasons;
  std::vector<Proposal> parts = propose_roof_partition(rest, reasons);
  if (parts.empty()) return refuse("the rest of its footprint has no roof partition");
  // The roof under the dome's base circle (and its axis), from the parts.
  const Vec3 c = dome.spec.placement.apply_point(Vec3::Zero());
  const double radius = dome.spec.radius;
  const auto [base, rim] = cap_base(dome);
  double lo = INFINITY, hi = -INFINITY;
  for (int k = -1; k < 64; ++k) {
    const double a = 2.0 * std::numbers::pi * k / 64.0;
    const Vec2 q =
        k < 0 ? Vec2(c.x(), c.y()) : Vec2(c.x() + rim * std::cos(a), c.y() + rim * std::sin(a));
    const auto z = roof_top_at(parts, q);
    if (!z) return refuse("its base reaches past the roof of its footprint");
    lo = std::min(lo, *z);
    hi = std::max(hi, *z);
  }
  if (hi >= c.z() + radius) return refuse("the roof under it stands above its top");
  // Where it stands: on a flat roof, on the roof's plane; on roofs of several heights or
  // slopes, a step below the lowest (the disc buried in the roof, no contact at one point).
  const double step = contact_step(o_);
  const double level = hi - lo <= o_.linear_tolerance ? lo : lo - step;
  // A drum between the roof and the dome's base where the roof lies below the sphere's
  // equator, or where its wall is seen (points around the base circle, between the roof and
  // the base). Otherwise the cap reaches down to the roof: seen from the air, a cap's lowest
  // points lie well above its true base (the sphere is steep there), so a gap between them
  // and the roof is no evidence of a wall.
  const double eps = ransac_.epsilon;
  long long wall = 0;
  for (std::uint32_t i = 0; i < points_.size(); ++i) {
    const Vec3& p = points_[i];
    if (used_[i] || !explained[i] || p.z() <= level + 3.0 * eps || p.z() >= base - 3.0 * eps)
      continue;
    wall += std::abs(std::hypot(p.x() - c.x(), p.y() - c.y()) - rim) <= 3.0 * eps ? 1 : 0;
  }
  const bool drummed = base - level > step && (level < c.z() - step || wall >= kMinDrumWall);
  Proposal on = dome;
  std::optional<Proposal> drum;
  if (drummed) {
    auto spec = drum_spec(Vec2(c.x(), c.y()), rim, level, base - level);
    if (!spec) return refuse("no drum can be placed under it");
    drum.emplace();
    drum->spec = std::move(*spec);
    drum->carried = true;
    drum->what = dome.what + " drum";
    drum->area = 2.0 * std::numbers::pi * rim * (base - level);
    for (std::uint32_t i = 0; i < points_.size(); ++i) {
      const Vec3& p = points_[i];
      if (used_[i] || !explained[i] || p.z() > base + 3.0 * eps) continue;
      if (std::hypot(p.x() - c.x(), p.y() - c.y()) <= rim + 3.0 * eps) drum->members.push_back(i);
    }
    if (auto solid = kernel::build_primitive(drum->spec, o_.linear_tolerance);
        !solid.ok() || !kernel::check_shape(solid.value()).valid()) {
      return refuse("its drum is no valid solid");
    }
  } else if (level < c.z() + radius - step) {
    cut_dome(on, level);  // the cap's rim on the roof (or buried in it)
  } else {
    return refuse("too flat a cap above its roof");
  }
  if (!take(on)) return false;
  if (drum) {
    std::erase_if(drum->members, [&](std::uint32_t i) { return used_[i] != 0; });
    take(*drum);
  }
  out_.rejected.insert(out_.rejected.end(), reasons.begin(), reasons.end());
  for (auto& p : parts) {
    std::erase_if(p.members, [&](std::uint32_t i) { return used_[i] != 0; });
    take(p);
  }
  return true;
}

}  // namespace csgtile::fit::detail
