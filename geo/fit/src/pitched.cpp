// Buildings under pitched roofs seen from the air: the walls are barely scanned, the roof
// planes are. A tilted roof plane (a shed), or two of them sharing their horizontal direction
// and meeting at a ridge (a gable), become one extrusion along that direction whose section
// is the roof's profile over the terrain: a trapezoid under a shed, a pentagon under a gable.
// Before, such a plane became a slab a few centimetres thick floating at roof height (its
// noise band taken for the box's depth) or, worse, a thick tilted box whose "opposite face"
// was the far slope of the roof, reaching metres into the ground.
//
// A plane qualifies when it is tilted (between the angle tolerance and 75° from horizontal),
// its points cover most of its rectangle, and it is at least min_building_width wide both
// ways. The section is measured in the plane ⟂ the shared horizontal direction: x across, y
// up from the terrain (the lowest ground level around the footprint); each plane's trace is the
// least-squares line of its points there. A gable's top is the lower envelope of the two
// traces; it counts only when they rise to the ridge from either side and both planes' points
// end near it (within 1 m or two cells).

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "fit_internal.h"
#include "plane2d.h"

namespace csgtile::fit::detail {

namespace {

using kernel::PrimitiveType;
using kernel::Vec2;

// One tilted roof plane in the shared frame: its unused inliers and the line y = a + b·x of
// their heights across.
struct Slope {
  int shape = -1;
  std::vector<std::uint32_t> members;
  Vec3 h;  // horizontal direction in the plane (unit, canonical sign)
  double a = 0.0, b = 0.0;
  double x0 = 0.0, x1 = 0.0, t0 = 0.0, t1 = 0.0;
  double rms = 0.0;  // robust σ of the points about the plane
};

// The horizontal direction of a plane with normal n, with a sign fixed by its components.
Vec3 horizontal_of(const Vec3& n) {
  Vec3 h = n.cross(Vec3::UnitZ());
  h.z() = 0.0;
  h.normalize();
  if (h.x() < 0.0 || (h.x() == 0.0 && h.y() < 0.0)) h = -h;
  return h;
}

}  // namespace

double lowest_ground_under(const GroundGrid& ground, const std::vector<Vec2>& footprint) {
  if (ground.nx <= 0 || ground.ny <= 0 || !(ground.cell > 0.0) || footprint.empty()) return NAN;
  double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
  for (const auto& p : footprint) {
    if (!p.allFinite()) return NAN;
    x0 = std::min(x0, p.x());
    y0 = std::min(y0, p.y());
    x1 = std::max(x1, p.x());
    y1 = std::max(y1, p.y());
  }
  const double c = ground.cell;
  const std::vector<double>& level = ground.mean.size() == ground.z.size() ? ground.mean : ground.z;
  auto index = [&](double v, double origin, int n) {
    return static_cast<int>(
        std::clamp(std::floor((v - origin) / c), 0.0, static_cast<double>(n - 1)));
  };
  double best = NAN;
  for (int j = index(y0 - c, ground.y0, ground.ny); j <= index(y1 + c, ground.y0, ground.ny); ++j) {
    for (int i = index(x0 - c, ground.x0, ground.nx); i <= index(x1 + c, ground.x0, ground.nx);
         ++i) {
      const double h = level[static_cast<std::size_t>(j) * static_cast<std::size_t>(ground.nx) +
                             static_cast<std::size_t>(i)];
      if (!std::isfinite(h) || h >= best) continue;
      const Vec2 centre(ground.x0 + (i + 0.5) * c, ground.y0 + (j + 0.5) * c);
      bool near = footprint.size() >= 3 && inside_ring(centre, footprint);
      for (std::size_t k = 0; k < footprint.size() && !near; ++k) {
        near = segment_distance(centre, footprint[k], footprint[(k + 1) % footprint.size()]) <= c;
      }
      if (near) best = h;
    }
  }
  return best;
}

std::vector<Proposal> propose_pitched_roofs(const ProposalInput& in,
                                            std::vector<Rejection>& rejected) {
  std::vector<Proposal> out;
  const PrimitiveOptions& o = *in.options;
  const RansacOptions& r = *in.ransac;
  if (o.ground == nullptr || in.shapes == nullptr) return out;
  const auto& shapes = in.shapes->shapes;
  const double cos_tol = std::cos(o.angle_tolerance_deg * std::numbers::pi / 180.0);
  const double cos_steep = std::cos(75.0 * std::numbers::pi / 180.0);
  const double tight = 2.0 * r.epsilon;
  std::vector<char> taken(in.points.size(), 0);  // points of proposals made here
  std::vector<char> shape_taken(shapes.size(), 0);

  // Candidate planes, largest first (ties by index: deterministic).
  std::vector<int> order;
  for (std::size_t s = 0; s < shapes.size(); ++s) {
    const auto& sh = shapes[s];
    if ((*in.absorbed)[s] || sh.surface.type != ShapeType::Plane) continue;
    const double nz = std::abs(sh.surface.axis.normalized().z());
    if (nz >= cos_tol || nz <= cos_steep) continue;
    order.push_back(static_cast<int>(s));
  }
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return shapes[static_cast<std::size_t>(a)].inliers.size() >
           shapes[static_cast<std::size_t>(b)].inliers.size();
  });

  // A plane's slope in the frame (d across, e along, both horizontal), about `centre`.
  auto slope_of = [&](int s, const Vec3& d, const Vec3& e, const Vec3& centre) {
    Slope sl;
    sl.shape = s;
    sl.h = horizontal_of(shapes[static_cast<std::size_t>(s)].surface.axis.normalized());
    for (auto i : shapes[static_cast<std::size_t>(s)].inliers) {
      if (!(*in.used)[i] && !taken[i] && in.points[i].allFinite()) sl.members.push_back(i);
    }
    if (sl.members.size() < 8) return sl;
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    sl.x0 = sl.t0 = INFINITY;
    sl.x1 = sl.t1 = -INFINITY;
    for (auto i : sl.members) {
      const Vec3 p = in.points[i] - centre;
      const double x = p.dot(d), y = p.z(), t = p.dot(e);
      sx += x;
      sy += y;
      sxx += x * x;
      sxy += x * y;
      sl.x0 = std::min(sl.x0, x);
      sl.x1 = std::max(sl.x1, x);
      sl.t0 = std::min(sl.t0, t);
      sl.t1 = std::max(sl.t1, t);
    }
    const double n = static_cast<double>(sl.members.size());
    const double det = n * sxx - sx * sx;
    if (!(std::abs(det) > 1e-12)) {
      sl.members.clear();
      return sl;
    }
    sl.b = (n * sxy - sx * sy) / det;
    sl.a = (sy - sl.b * sx) / n;
    return sl;
  };
  // The noise about a slope's plane: 1.4826 × the median distance of the unused points over
  // its rectangle within 0.25 m of it (its inliers alone are cut off at epsilon).
  auto measure_noise = [&](Slope& sl, const Vec3& d, const Vec3& e, const Vec3& centre) {
    std::vector<double> offsets;
    const double scale = 1.0 / std::sqrt(1.0 + sl.b * sl.b);
    for (std::uint32_t i = 0; i < in.points.size(); ++i) {
      if ((*in.used)[i] || taken[i] || !in.points[i].allFinite()) continue;
      const Vec3 p = in.points[i] - centre;
      const double x = p.dot(d), t = p.dot(e);
      if (x < sl.x0 || x > sl.x1 || t < sl.t0 || t > sl.t1) continue;
      const double off = std::abs(p.z() - (sl.a + sl.b * x)) * scale;
      if (off <= 0.25) offsets.push_back(off);
    }
    if (!offsets.empty()) {
      const auto mid = offsets.begin() + static_cast<std::ptrdiff_t>(offsets.size() / 2);
      std::nth_element(offsets.begin(), mid, offsets.end());
      sl.rms = 1.4826 * *mid;
    }
  };
  // Share of cells (0.5 m, or the region's cell if larger) of the slope's rectangle holding
  // its points.
  auto coverage = [&](const Slope& sl, const Vec3& d, const Vec3& e, const Vec3& centre) {
    const double cell = std::max(0.5, in.cell);
    const auto nx = static_cast<long long>(std::ceil((sl.x1 - sl.x0) / cell));
    const auto nt = static_cast<long long>(std::ceil((sl.t1 - sl.t0) / cell));
    if (nx <= 0 || nt <= 0 || nx * nt > 4'000'000) return 0.0;
    std::vector<char> hit(static_cast<std::size_t>(nx * nt), 0);
    for (auto i : sl.members) {
      const Vec3 p = in.points[i] - centre;
      const auto ix = std::clamp(static_cast<long long>((p.dot(d) - sl.x0) / cell), 0LL, nx - 1);
      const auto it = std::clamp(static_cast<long long>((p.dot(e) - sl.t0) / cell), 0LL, nt - 1);
      hit[static_cast<std::size_t>(it * nx + ix)] = 1;
    }
    return static_cast<double>(std::count(hit.begin(), hit.end(), 1)) /
           static_cast<double>(nx * nt);
  };

  for (const int seed : order) {
    if (shape_taken[static_cast<std::size_t>(seed)]) continue;
    const auto& seed_shape = shapes[static_cast<std::size_t>(seed)];
    const std::string what = "pitched roof from plane " + std::to_string(seed);
    const Vec3 h = horizontal_of(seed_shape.surface.axis.normalized());
    const Vec3& e = h;
    const Vec3 d = Vec3::UnitZ().cross(e).normalized();  // across, horizontal
    Vec3 centre = Vec3::Zero();
    {
      std::size_t n = 0;
      for (auto i : seed_shape.inliers) {
        if (!in.points[i].allFinite()) continue;
        centre += in.points[i];
        ++n;
      }
      if (n == 0) continue;
      centre /= static_cast<double>(n);
      centre.z() = 0.0;
    }
    Slope first = slope_of(seed, d, e, centre);
    if (first.members.size() < static_cast<std::size_t>(std::max<long long>(8, r.min_points))) {
      continue;
    }
    if (first.x1 - first.x0 < o.min_building_width || first.t1 - first.t0 < o.min_building_width) {
      continue;
    }
    if (coverage(first, d, e, centre) < o.min_seed_coverage) {
      rejected.push_back({what, "its points cover too little of its rectangle",
                          static_cast<long long>(first.members.size())});
      continue;
    }
    // The partner across a ridge: parallel horizontal direction, opposite slope, overlapping
    // along e, meeting the seed near where both end across.
    measure_noise(first, d, e, centre);
    std::vector<Slope> group{first};
    for (const int other : order) {
      if (other == seed || shape_taken[static_cast<std::size_t>(other)]) continue;
      const Vec3 oh =
          horizontal_of(shapes[static_cast<std::size_t>(other)].surface.axis.normalized());
      if (std::abs(oh.dot(h)) < cos_tol) continue;
      Slope sl = slope_of(other, d, e, centre);
      if (sl.members.size() < static_cast<std::size_t>(std::max<long long>(8, r.min_points))) {
        continue;
      }
      if (sl.b * first.b >= 0.0) continue;
      const double overlap = std::min(sl.t1, first.t1) - std::max(sl.t0, first.t0);
      if (overlap < 0.5 * std::min(sl.t1 - sl.t0, first.t1 - first.t0)) continue;
      // Rising (b > 0) on the left of the ridge, falling on its right: ridge up.
      const Slope& rise = first.b > 0.0 ? first : sl;
      const Slope& fall = first.b > 0.0 ? sl : first;
      const double ridge = (fall.a - rise.a) / (rise.b - fall.b);
      const double reach = std::max(1.0, 2.0 * in.cell);
      if (std::abs(rise.x1 - ridge) > reach || std::abs(fall.x0 - ridge) > reach) continue;
      if (coverage(sl, d, e, centre) < o.min_seed_coverage) continue;
      measure_noise(sl, d, e, centre);
      group.push_back(std::move(sl));
      break;
    }
    // Section: x over the group's extent, the top the lower envelope of the traces.
    double x0 = INFINITY, x1 = -INFINITY, t0 = INFINITY, t1 = -INFINITY;
    for (const auto& sl : group) {
      x0 = std::min(x0, sl.x0);
      x1 = std::max(x1, sl.x1);
      t0 = std::min(t0, sl.t0);
      t1 = std::max(t1, sl.t1);
    }
    auto top = [&](double x) {
      double y = INFINITY;
      for (const auto& sl : group) y = std::min(y, sl.a + sl.b * x);
      return y;
    };
    // Distance from (x, y) to the roof, across the trace that is the roof there.
    auto roof_distance = [&](double x, double y) {
      double best = INFINITY, at = INFINITY;
      for (const auto& sl : group) {
        const double z = sl.a + sl.b * x;
        if (z < at) {
          at = z;
          best = std::abs(y - z) / std::sqrt(1.0 + sl.b * sl.b);
        }
      }
      return best;
    };
    // Bottom: the lowest terrain around the footprint (on sloping ground the walls reach
    // its foot rather than stopping at a mean level above it).
    std::vector<Vec2> footprint;
    for (const auto& [x, t] : {std::pair{x0, t0}, {x1, t0}, {x1, t1}, {x0, t1}}) {
      const Vec3 w = centre + x * d + t * e;
      footprint.emplace_back(w.x(), w.y());
    }
    double g = lowest_ground_under(*o.ground, footprint);
    if (!std::isfinite(g)) {  // no ground seen around it: the lowest farther off
      const Vec3 mid = centre + 0.5 * (x0 + x1) * d + 0.5 * (t0 + t1) * e;
      g = o.ground->lowest_near(mid.x(), mid.y(),
                                0.5 * std::hypot(x1 - x0, t1 - t0) + 2.0 * o.ground->cell);
    }
    if (!std::isfinite(g)) continue;
    std::vector<Vec2> profile{{x0, 0.0}, {x1, 0.0}, {x1, top(x1) - g}};
    if (group.size() == 2) {
      const Slope& rise = group[0].b > 0.0 ? group[0] : group[1];
      const Slope& fall = group[0].b > 0.0 ? group[1] : group[0];
      const double ridge = (fall.a - rise.a) / (rise.b - fall.b);
      if (ridge > x0 && ridge < x1) profile.emplace_back(ridge, top(ridge) - g);
    }
    profile.emplace_back(x0, top(x0) - g);
    double low = INFINITY, high = -INFINITY;
    for (std::size_t k = 2; k < profile.size(); ++k) {
      low = std::min(low, profile[k].y());
      high = std::max(high, profile[k].y());
    }
    if (!(low >= 0.5 * o.min_building_height) || high < o.min_building_height) {
      rejected.push_back({what, "its eaves are too close to the terrain for a building",
                          static_cast<long long>(first.members.size())});
      continue;
    }
    if (ring_area(profile) <= 0.0) continue;
    // Members: unused points within the noise of the solid's boundary (2 ε, or
    // 3 σ of the roof points about their planes when larger: airborne noise exceeds ε).
    double scatter = 0.0;
    for (const auto& sl : group) scatter = std::max(scatter, sl.rms);
    const double band = std::max(tight, 3.0 * scatter);
    // Points of another plane need to lie within 2 ε: a roof face of its own beside the
    // slopes (a steeper strip, a lower wing) is not the slopes' noise.
    std::vector<char> in_group(shapes.size(), 0);
    for (const auto& sl : group) in_group[static_cast<std::size_t>(sl.shape)] = 1;
    // ... unless it is a layer of a slope's noise: parallel to it, its points within the band
    // and spread over most of the slope (the RANSAC splits a roof whose noise exceeds ε into
    // parallel planes).
    for (std::size_t s = 0; s < shapes.size(); ++s) {
      if (in_group[s] || shapes[s].surface.type != ShapeType::Plane || shapes[s].inliers.empty()) {
        continue;
      }
      const Vec3 n = shapes[s].surface.axis.normalized();
      for (const auto& sl : group) {
        const Vec3 ns = (Vec3::UnitZ() - sl.b * d).normalized();
        if (std::abs(n.dot(ns)) < cos_tol) continue;
        double sum = 0.0, lx = INFINITY, hx = -INFINITY, lt = INFINITY, ht = -INFINITY;
        for (auto i : shapes[s].inliers) {
          const Vec3 q = in.points[i] - centre;
          const double x = q.dot(d), t = q.dot(e);
          sum += std::abs(q.z() - (sl.a + sl.b * x)) / std::sqrt(1.0 + sl.b * sl.b);
          lx = std::min(lx, x);
          hx = std::max(hx, x);
          lt = std::min(lt, t);
          ht = std::max(ht, t);
        }
        // Spread over most of the slope, as noise is; a face of its own is somewhere.
        const bool spread = std::min(hx, sl.x1) - std::max(lx, sl.x0) >= 0.5 * (sl.x1 - sl.x0) &&
                            std::min(ht, sl.t1) - std::max(lt, sl.t0) >= 0.5 * (sl.t1 - sl.t0);
        if (spread && sum <= band * static_cast<double>(shapes[s].inliers.size())) {
          in_group[s] = 1;
          break;
        }
      }
    }
    Proposal p;
    for (std::uint32_t i = 0; i < in.points.size(); ++i) {
      if ((*in.used)[i] || taken[i] || !in.points[i].allFinite()) continue;
      const int owner = i < in.shapes->assignment.size() ? in.shapes->assignment[i] : -1;
      const double near = owner >= 0 && !in_group[static_cast<std::size_t>(owner)] ? tight : band;
      const Vec3 q = in.points[i] - centre;
      const double x = q.dot(d), t = q.dot(e), y = in.points[i].z();
      if (x < x0 - band || x > x1 + band || t < t0 - band || t > t1 + band) continue;
      const double roof_z = top(std::clamp(x, x0, x1));
      if (y < g - band || y > roof_z + band) continue;
      // Near its roof or walls: points deep inside (a lower roof under the ridge's span, a
      // dormer's floor) stay for primitives of their own.
      const double side = std::min({std::abs(x - x0), std::abs(x - x1), std::abs(t - t0),
                                    std::abs(t - t1), std::abs(y - g)});
      if (std::min(side, roof_distance(std::clamp(x, x0, x1), y)) > near) continue;
      p.members.push_back(i);
    }
    // Local frame: x = d, y = up, z = d × up = e; the section lies at t0 along e, on the
    // terrain.
    const auto placed =
        place(frame_of(d, d.cross(Vec3::UnitZ())), Vec3(centre.x(), centre.y(), g) + t0 * e);
    if (!placed) continue;
    p.spec.type = PrimitiveType::Extrusion;
    p.spec.profile = profile;
    p.spec.height = t1 - t0;
    p.spec.placement = *placed;
    double roof_length = 0.0;
    for (std::size_t k = 2; k + 1 < profile.size(); ++k) {
      roof_length += (profile[k + 1] - profile[k]).norm();
    }
    p.area = roof_length * p.spec.height + 2.0 * ring_area(profile) +
             (profile[2].y() + profile.back().y()) * p.spec.height;
    for (auto i : p.members) taken[i] = 1;
    p.shapes = planes_explained_by(in, p.members);
    for (int s : p.shapes) shape_taken[static_cast<std::size_t>(s)] = 1;
    for (const auto& sl : group) {
      if (!shape_taken[static_cast<std::size_t>(sl.shape)]) {
        shape_taken[static_cast<std::size_t>(sl.shape)] = 1;
        p.shapes.push_back(sl.shape);
      }
    }
    std::sort(p.shapes.begin(), p.shapes.end());
    p.what = group.size() == 2 ? "gable roof from planes " + std::to_string(group[0].shape) +
                                     " and " + std::to_string(group[1].shape)
                               : what;
    out.push_back(std::move(p));
  }
  return out;
}

}  // namespace csgtile::fit::detail
