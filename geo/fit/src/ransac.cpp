// Efficient RANSAC after Schnabel, Wahl and Klein (2007), "Efficient RANSAC for point-cloud
// shape detection":
//  - candidates from minimal samples with normals, drawn locally: a seed point, then the
//    other samples from the seed's cell in one of several grid levels (their octree cells);
//  - a candidate's score is the size of the connected component of compatible points (within
//    epsilon, normal within alpha) reached from the seed through a grid of cluster_epsilon
//    cells; while searching, only the first few (shuffled) points of each cell are tested and
//    the count is extrapolated, so a score costs about the number of cells the shape covers;
//  - candidates are kept in a max-heap across draws; a score is recomputed lazily when the
//    candidate reaches the top after points were removed (scores only fall);
//  - the best candidate is extracted once the probability of having drawn a larger shape,
//    1 - (1 - n / (N · levels))^draws, reaches `probability`; drawing stops when that holds
//    for a shape of min_points;
//  - an extracted shape is refitted by least squares, its component recomputed, and the refit
//    kept only when it explains at least as many points; a curved shape that a plane (a cone
//    or torus that a cylinder, a torus that a sphere) explains as well is replaced by the
//    simpler one.

#include <algorithm>
#include <cmath>
#include <numbers>
#include <queue>
#include <vector>

#include <Eigen/Dense>

#include "facets.h"
#include "fit_internal.h"
#include "plane2d.h"
#include "ransac_detector.h"
#include "shape_merge.h"

namespace csgtile::fit {

using kernel::Vec3;

namespace detail {

// Passes of relabel() after its refits: each moves the points next to a shape's own, so a
// shape takes back a region another holds in as many passes as the region is cells wide.
constexpr int kRelabelPasses = 64;

double Detector::component(const Surface& s, std::span<const int> starts, bool sampled,
                           std::vector<std::uint32_t>* out) {
  new_visit();
  std::vector<std::uint32_t> best, current;
  double first_score = -1.0;
  std::vector<int> queue;
  for (int start : starts) {
    if (start < 0 || cell_stamp_[static_cast<std::size_t>(start)] == stamp_) continue;
    cell_stamp_[static_cast<std::size_t>(start)] = stamp_;
    queue.assign(1, start);
    current.clear();
    double score = 0.0;
    for (std::size_t head = 0; head < queue.size(); ++head) {
      const int cell = queue[head];
      const auto pts = grid_->points(cell);
      const std::size_t tested =
          sampled ? std::min<std::size_t>(pts.size(), kSampledPerCell) : pts.size();
      std::size_t hits = 0;
      for (std::size_t k = 0; k < tested; ++k) {
        const std::uint32_t i = pts[k];
        if (assignment_[i] >= 0 || !compatible(s, i)) continue;
        ++hits;
        if (out != nullptr) current.push_back(i);
      }
      if (hits == 0) continue;
      score +=
          static_cast<double>(hits) * static_cast<double>(pts.size()) / static_cast<double>(tested);
      for_unvisited_neighbours(cell, [&](int next) { queue.push_back(next); });
    }
    if (first_score < 0.0) first_score = score;
    if (out != nullptr && current.size() > best.size()) best.swap(current);
    if (sampled) break;
  }
  if (out != nullptr) {
    std::sort(best.begin(), best.end());
    *out = std::move(best);
    return static_cast<double>(out->size());
  }
  return std::max(first_score, 0.0);
}

std::vector<std::uint32_t> Detector::exact_inliers(const Surface& s,
                                                   std::span<const std::uint32_t> near) {
  std::vector<int> starts;
  starts.reserve(near.size());
  for (auto i : near) starts.push_back(grid_->cell_of(i));
  std::vector<std::uint32_t> out;
  component(s, starts, false, &out);
  return out;
}

void Detector::compact_remaining() {
  std::erase_if(remaining_, [&](std::uint32_t i) { return assignment_[i] >= 0; });
}

void Detector::draw() {
  ++draws_;
  if (remaining_.empty()) return;
  const std::uint32_t seed = remaining_[random_.below(remaining_.size())];
  if (assignment_[seed] >= 0 || !has_normal_[seed]) return;
  const std::size_t level = random_.below(levels_.size());
  const PointGrid& grid = *levels_[level];
  const auto cell = grid.points(grid.cell_of(seed));
  constexpr std::size_t kSamples = 7;
  std::vector<Vec3> p{points_[seed]};
  std::vector<Vec3> n{normals_[seed]};
  for (int attempt = 0; attempt < 40 && p.size() < kSamples; ++attempt) {
    const std::uint32_t j = cell[random_.below(cell.size())];
    if (j == seed || assignment_[j] >= 0 || !has_normal_[j]) continue;
    // Normals are unoriented: turn each towards the seed's, as for a smooth patch.
    p.push_back(points_[j]);
    n.push_back(normals_[j].dot(normals_[seed]) < 0.0 ? Vec3(-normals_[j]) : normals_[j]);
  }
  if (p.size() < 4) return;
  const std::span<const Vec3> p4(p.data(), 4), n4(n.data(), 4);
  std::optional<Surface> made[kShapeTypeCount];
  if (o_.shapes[0]) made[0] = detail::plane_from_samples(p4, n4);
  if (o_.shapes[1]) made[1] = detail::sphere_from_samples(p4, n4, o_.max_radius);
  if (o_.shapes[2]) made[2] = detail::cylinder_from_samples(p4, n4, o_.max_radius);
  if (o_.shapes[3]) made[3] = detail::cone_from_samples(p4, n4, o_.max_radius);
  if (o_.shapes[4] && p.size() >= 6) made[4] = detail::torus_from_samples(p, n, o_.max_radius);
  const int starts[1] = {grid_->cell_of(seed)};
  for (auto& m : made) {
    if (!m) continue;
    const Surface& s = *m;
    const std::size_t used = s.type == ShapeType::Torus ? p.size() : 4;
    bool ok = true;
    for (std::size_t k = 0; k < used && ok; ++k) {
      ok = std::abs(surface_distance(s, p[k])) <= o_.epsilon &&
           std::abs(surface_normal(s, p[k]).dot(n[k])) >= cos_alpha_;
    }
    if (!ok) continue;
    const double score = component(s, starts, true, nullptr);
    if (score < 0.5 * static_cast<double>(o_.min_points)) continue;
    heap_.push(Candidate{score, draws_ * kShapeTypeCount + static_cast<std::uint64_t>(s.type),
                         extractions_, seed, s});
  }
}

bool Detector::extract(const Candidate& c) {
  const std::uint32_t seed_only[1] = {c.seed};
  Surface surface = c.surface;
  std::vector<std::uint32_t> inliers = exact_inliers(surface, seed_only);
  if (static_cast<long long>(inliers.size()) < o_.min_points) return false;
  // Refit while the inliers grow: a candidate from a small patch of a large surface reaches
  // the rest of it step by step as its parameters improve.
  for (int round = 0; round < 12; ++round) {
    const auto refit = detail::refine_surface(surface, points_, inliers);
    if (!refit) break;
    auto again = exact_inliers(*refit, inliers);
    if (again.size() < inliers.size()) break;
    const bool grew = again.size() > inliers.size() + inliers.size() / 200;
    surface = *refit;
    inliers = std::move(again);
    if (!grew) break;
  }
  if (auto core = exact_core(surface, inliers)) {
    auto again = exact_inliers(*core, inliers);
    if (static_cast<long long>(again.size()) >= o_.min_points) {
      surface = *core;
      inliers = std::move(again);
    }
  }
  if (auto alt = simpler(surface, inliers)) {
    auto again = exact_inliers(*alt, inliers);
    if (again.size() * 100 >= inliers.size() * 97) {
      surface = *alt;
      inliers = std::move(again);
      if (auto refit = detail::refine_surface(surface, points_, inliers)) {
        auto more = exact_inliers(*refit, inliers);
        if (more.size() >= inliers.size()) {
          surface = *refit;
          inliers = std::move(more);
        }
      }
    }
  }
  if (o_.by_evidence) {
    if (auto alt = by_evidence(surface, inliers)) {
      auto again = exact_inliers(*alt, inliers);
      if (again.size() * 100 >= inliers.size() * 97) {
        surface = *alt;
        inliers = std::move(again);
      }
    }
  }
  if (o_.by_evidence && exact_ && surface.type != ShapeType::Plane) {
    // A curved candidate holding an exact planar facet its own surface does not fit (a face
    // of a polygonal prism in the band of the cylinder around it) is facets: the largest is
    // taken as a plane instead, grown from its points; the others come in later rounds.
    const double floor = noise_floor();
    const auto facet =
        detail::largest_exact_facet(points_, normals_, has_normal_, inliers, floor, cos_alpha_,
                                    static_cast<std::size_t>(o_.min_points), 0.5 * spacing_);
    if (facet && rms_of(surface, facet->points) > 2.0 * floor) {
      surface = facet->plane;
      inliers = exact_inliers(surface, facet->points);
    }
  }
  if (static_cast<long long>(inliers.size()) < o_.min_points) return false;
  // On exact clouds a curved candidate whose points do not fit it (median residual over the
  // floor) is a compromise between surfaces (free_inexact's rule): it is not taken, so that it
  // holds no points of the surfaces around it while they are searched (a torus of rms 0.04
  // over the points of a small hole's wall and the plates' rims). Planes are taken: a plane
  // holding a neighbour's band is mended by free_inexact's exact best half.
  if (exact_ && surface.type != ShapeType::Plane && !fits_exactly(surface, inliers)) {
    return false;
  }
  if ((surface.type == ShapeType::Cylinder || surface.type == ShapeType::Sphere) &&
      surface.radius >= o_.max_radius) {
    return false;
  }
  DetectedShape shape;
  shape.surface = surface;
  for (auto i : inliers) assignment_[i] = static_cast<int>(shapes_.size());
  shape.rms = rms_of(surface, inliers);
  remaining_count_ -= inliers.size();
  shape.inliers = std::move(inliers);
  shapes_.push_back(std::move(shape));
  ++extractions_;
  if (remaining_.size() > 2 * remaining_count_ + 64) compact_remaining();
  return true;
}

// After detection, every point goes to the shape that explains it best among the shapes whose
// inliers reach its cell's neighbourhood: a shape found first no longer keeps the points of a
// neighbour it took at their shared edge (smaller distance wins; a point keeps its shape on a
// tie), and points no shape took join one they lie on (within epsilon; their normal, often
// spoilt at an edge, is not asked). Shapes whose points changed are refitted (twice at most);
// a shape left with fewer than min_points is dissolved and its points labelled again. Then,
// with the surfaces fixed, the passes go on while points move (kRelabelPasses at most; each
// point only ever moves closer): a shape takes back the whole of a region another took from
// it, not only its rim (a flat cone's patches, taken for planes that fit them within
// epsilon). The last labelling is made with the final surfaces, so labels and surfaces agree.
void Detector::relabel() {
  const std::size_t n = points_.size();
  std::vector<double> best(n);
  std::vector<int> label(n);
  int passes = 0;
  for (int refits = 0;;) {
    std::fill(best.begin(), best.end(), INFINITY);
    std::fill(label.begin(), label.end(), -1);
    for (std::size_t i = 0; i < n; ++i) {
      const int a = assignment_[i];
      if (a >= 0) {
        best[i] =
            std::abs(surface_distance(shapes_[static_cast<std::size_t>(a)].surface, points_[i]));
        label[i] = a;
      }
    }
    for (std::size_t s = 0; s < shapes_.size(); ++s) {
      const Surface& surface = shapes_[s].surface;
      for_points_near(shapes_[s].inliers, [&](std::uint32_t j) {
        if (label[j] == static_cast<int>(s)) return;
        const double d = std::abs(surface_distance(surface, points_[j]));
        if (d > o_.epsilon || !(d < best[j])) return;
        // A point of another shape must face like this one; a free point need not.
        if (label[j] >= 0 && has_normal_[j] &&
            std::abs(surface_normal(surface, points_[j]).dot(normals_[j])) < cos_alpha_) {
          return;
        }
        best[j] = d;
        label[j] = static_cast<int>(s);
      });
    }
    std::vector<std::vector<std::uint32_t>> members(shapes_.size());
    for (std::size_t i = 0; i < n; ++i) {
      if (label[i] >= 0) {
        members[static_cast<std::size_t>(label[i])].push_back(static_cast<std::uint32_t>(i));
      }
    }
    bool changed = false, dissolved = false;
    for (std::size_t s = 0; s < shapes_.size(); ++s) {
      changed = changed || members[s] != shapes_[s].inliers;
      dissolved = dissolved || static_cast<long long>(members[s].size()) < o_.min_points;
    }
    // A shape free_inexact() emptied is dissolved though no point moved.
    if (!changed && !dissolved) break;
    const bool refit = !dissolved && refits < 2;
    std::vector<DetectedShape> kept;
    std::vector<int> renumber(shapes_.size(), -1);
    for (std::size_t s = 0; s < shapes_.size(); ++s) {
      if (static_cast<long long>(members[s].size()) < o_.min_points) continue;
      DetectedShape shape = std::move(shapes_[s]);
      if (refit && members[s] != shape.inliers) {
        if (auto better = detail::refine_surface(shape.surface, points_, members[s])) {
          // On exact clouds, to its own points: the refit to all compromises again.
          if (auto core = exact_core(*better, members[s])) better = core;
          // Kept only when it keeps every point it was refitted to.
          std::size_t within = 0;
          for (auto i : members[s])
            within += std::abs(surface_distance(*better, points_[i])) <= o_.epsilon ? 1 : 0;
          if (within == members[s].size()) shape.surface = *better;
        }
      }
      shape.inliers = std::move(members[s]);
      renumber[s] = static_cast<int>(kept.size());
      kept.push_back(std::move(shape));
    }
    shapes_ = std::move(kept);
    for (std::size_t i = 0; i < n; ++i) {
      assignment_[i] = label[i] >= 0 ? renumber[static_cast<std::size_t>(label[i])] : -1;
    }
    if (refit) {
      ++refits;
    } else if (!dissolved && ++passes >= kRelabelPasses) {
      break;  // labelled with the final surfaces
    }
  }
  for (auto& shape : shapes_) shape.rms = rms_of(shape.surface, shape.inliers);
}

// The half of `inliers` that `s` fits best (ascending indices), in `half`.
void Detector::best_fitting_half(const Surface& s, std::span<const std::uint32_t> inliers,
                                 std::vector<std::uint32_t>& half) const {
  const std::size_t count = inliers.size() / 2;
  std::vector<std::pair<double, std::uint32_t>> by_fit;
  by_fit.reserve(inliers.size());
  for (auto i : inliers) by_fit.emplace_back(std::abs(surface_distance(s, points_[i])), i);
  std::nth_element(by_fit.begin(), by_fit.begin() + static_cast<std::ptrdiff_t>(count),
                   by_fit.end());
  half.clear();
  for (std::size_t k = 0; k < count; ++k) half.push_back(by_fit[k].second);
  std::sort(half.begin(), half.end());
}

// The surface through the half of `inliers` it fits best (least trimmed squares, a few steps):
// a plane, or `start`'s type refined from it; with its RMS on that half. nullopt for too few
// points or a refit that fails.
std::optional<Detector::Core> Detector::best_half(std::span<const std::uint32_t> inliers,
                                                  const Surface* start) const {
  if (inliers.size() / 2 < 3) return std::nullopt;
  auto fit = [&](std::span<const std::uint32_t> pts) {
    return start ? detail::refine_surface(*start, points_, pts) : detail::fit_plane(points_, pts);
  };
  auto current = fit(inliers);
  std::vector<std::uint32_t> half;
  for (int step = 0; current && step < 4; ++step) {
    best_fitting_half(*current, inliers, half);
    current = fit(half);
  }
  if (!current) return std::nullopt;
  return Core{*current, rms_of(*current, half)};
}

std::optional<Detector::Core> Detector::exact_half(const DetectedShape& shape) const {
  const Surface* start = shape.surface.type == ShapeType::Plane ? nullptr : &shape.surface;
  auto core = best_half(shape.inliers, start);
  if (!core || !exact_fit(core->rms)) return std::nullopt;
  return core;
}

// On an exact cloud every true surface fits its points to the noise floor. A shape that fits
// most of its points so (median residual within the floor) but holds points more than three
// floors off it holds a neighbour's points; a shape that fits most of its points worse is a
// compromise between surfaces (a cone through a cylinder's end and the sphere of a rounded
// corner, one torus over two fillets). A shape whose best half fits its surface exactly (within
// kExactShare floors) holds a neighbour's points wherever they are off that surface by ten times
// its RMS, even within the floors (a spot face a few thousandths below the face around it; a
// face's band tangent to a small ball).
// Those points, and all of a compromise's, are freed for a second search; the shape keeps the
// rest (a compromise nothing: relabel() drops it). The number freed.
std::size_t Detector::free_inexact() {
  const double floor = noise_floor();
  std::size_t freed = 0;
  for (auto& shape : shapes_) {
    if (shape.inliers.empty()) continue;
    std::vector<double> residual = residuals(shape.surface, shape.inliers);
    const bool dissolve = detail::median_of(residual) > floor;
    double off = kOnSurfaceFloors * floor;
    if (!dissolve) {
      if (const auto core = exact_half(shape)) {
        residual = residuals(core->surface, shape.inliers);
        off = exact_reach(core->rms);
      }
    }
    std::vector<std::uint32_t> kept;
    for (std::size_t k = 0; k < shape.inliers.size(); ++k) {
      const std::uint32_t i = shape.inliers[k];
      if (dissolve || residual[k] > off) {
        assignment_[i] = -1;
        if (has_normal_[i]) remaining_.push_back(i);
        ++remaining_count_;
        ++freed;
      } else {
        kept.push_back(i);
      }
    }
    shape.inliers = std::move(kept);
  }
  return freed;
}

// Types again on the final points: a curved shape found first may have held a neighbour's
// edge points that relabel() gave back (the belt of a wide cylinder between two fillets, taken
// with their rims for the sphere through it); on its own points another type can be the
// better. Planes are left as extraction decided. A curved shape becomes a plane (a cone of
// half-angle 89.97° left with one face's points) unless its points lie on one circle of that
// plane (a hole's wall that gave its rims away, seen as one ring, which a plane fits as well)
// or the curved surface fits them a hundred times better (by_evidence's rule for planes, which
// would turn the plane back). True when a shape changed type.
bool Detector::retype() {
  bool changed = false;
  for (auto& shape : shapes_) {
    if (shape.surface.type == ShapeType::Plane) continue;
    auto alt = by_evidence(shape.surface, shape.inliers);
    if (!alt) continue;
    if (alt->type == ShapeType::Plane) {
      if (on_one_circle(alt->axis, shape.inliers)) continue;
      if (rms_of(shape.surface, shape.inliers) <= 0.01 * rms_of(*alt, shape.inliers)) continue;
    }
    shape.surface = *alt;
    changed = true;
  }
  return changed;
}

// Edges: a point within epsilon of two neighbouring shapes lies on both (at their shared edge
// its normal belongs to neither); it goes to the smallest of them that has at most half the
// points of its present one, since a small feature (a hole's wall, a fillet, a boss) needs its
// rims while a large face loses nothing to speak of. On noisy clouds once, among the points next
// to that shape's inliers (growing further would run along the line where the two unbounded
// surfaces meet, past the feature). On exact clouds, where a point taken must lie on both
// surfaces (within ten times the shape's RMS where it fits its own points exactly, else
// kOnSurfaceFloors floors), it grows along the edge from each point taken: a face found in one
// sector of a ring whose points are nearly all rims (the larger neighbours took the rest before it
// was found) takes its rims around the whole ring. No shape is left under min_points: a shape that
// would be keeps its points.
void Detector::give_edges_to_smaller() {
  const std::size_t n = points_.size();
  std::vector<int> moved(assignment_);
  auto size_of = [&](int s) { return shapes_[static_cast<std::size_t>(s)].inliers.size(); };
  std::vector<std::uint32_t> frontier, taken;
  for (std::size_t s = 0; s < shapes_.size(); ++s) {
    const int self = static_cast<int>(s);
    // On exact clouds, on a shape fitting its own points exactly: within ten times its RMS.
    double on = kOnSurfaceFloors * noise_floor();
    if (exact_ && exact_fit(shapes_[s].rms)) on = exact_reach(shapes_[s].rms);
    auto take = [&](std::uint32_t j) {
      const int now = assignment_[j];
      if (now < 0 || now == self || 2 * size_of(self) > size_of(now)) return;
      const double d = std::abs(surface_distance(shapes_[s].surface, points_[j]));
      if (d > o_.epsilon) return;
      // On exact clouds only a point on both surfaces: a band of a face tangent to a fillet lies
      // within epsilon of the fillet but on the face.
      if (exact_ &&
          d > std::max(on, std::abs(surface_distance(shapes_[static_cast<std::size_t>(now)].surface,
                                                     points_[j])))) {
        return;
      }
      // The smallest candidate wins; on equal sizes the shape found first.
      if (moved[j] != now && size_of(moved[j]) <= size_of(self)) return;
      if (moved[j] != self && exact_) taken.push_back(j);
      moved[j] = self;
    };
    frontier.assign(shapes_[s].inliers.begin(), shapes_[s].inliers.end());
    while (!frontier.empty()) {
      taken.clear();
      for_points_near(frontier, take);
      frontier.swap(taken);
    }
  }
  std::vector<long long> left(shapes_.size(), 0);
  for (std::size_t i = 0; i < n; ++i) {
    if (moved[i] >= 0) ++left[static_cast<std::size_t>(moved[i])];
  }
  for (std::size_t i = 0; i < n; ++i) {
    const int from = assignment_[i];
    if (from >= 0 && moved[i] != from && left[static_cast<std::size_t>(from)] < o_.min_points) {
      moved[i] = from;  // its shape would fall under min_points: it stays
    }
  }
  assignment_ = std::move(moved);
  for (auto& shape : shapes_) shape.inliers.clear();
  for (std::size_t i = 0; i < n; ++i) {
    if (assignment_[i] >= 0) {
      shapes_[static_cast<std::size_t>(assignment_[i])].inliers.push_back(
          static_cast<std::uint32_t>(i));
    }
  }
  for (auto& shape : shapes_) shape.rms = rms_of(shape.surface, shape.inliers);
}

// Points no shape holds that lie on a shape's surface (within epsilon; on exact clouds within
// kOnSurfaceFloors floors) and are reached from its points through points on that surface
// (free ones, or another shape's: the rims a plate's faces hold along a sparse disc's edge)
// join it, the nearest surface when several. The last step with `relabel` (after
// merge_same_surface): pieces of one surface fitted each to its own short arc reached only
// their own points, and the points between them stayed free; the merged surface reaches them.
void Detector::adopt_free() {
  const double on = exact_ ? std::min(o_.epsilon, kOnSurfaceFloors * noise_floor()) : o_.epsilon;
  std::vector<double> best(points_.size(), INFINITY);
  std::vector<int> label(points_.size(), -1);
  std::vector<std::size_t> reached(points_.size(), 0);  // shape index + 1 that reached it
  std::vector<std::uint32_t> frontier, next;
  for (std::size_t s = 0; s < shapes_.size(); ++s) {
    const Surface& surface = shapes_[s].surface;
    for (auto i : shapes_[s].inliers) reached[i] = s + 1;
    frontier.assign(shapes_[s].inliers.begin(), shapes_[s].inliers.end());
    while (!frontier.empty()) {
      next.clear();
      for_points_near(frontier, [&](std::uint32_t j) {
        if (reached[j] == s + 1) return;
        const double d = std::abs(surface_distance(surface, points_[j]));
        if (d > on) return;
        reached[j] = s + 1;
        next.push_back(j);
        if (assignment_[j] < 0 && d < best[j]) {
          best[j] = d;
          label[j] = static_cast<int>(s);
        }
      });
      frontier.swap(next);
    }
  }
  bool joined = false;
  for (std::size_t i = 0; i < points_.size(); ++i) {
    if (label[i] < 0) continue;
    assignment_[i] = label[i];
    shapes_[static_cast<std::size_t>(label[i])].inliers.push_back(static_cast<std::uint32_t>(i));
    joined = true;
  }
  if (joined) {
    for (auto& shape : shapes_) std::sort(shape.inliers.begin(), shape.inliers.end());
  }
}

std::pair<Vec3, Vec3> Detector::bounds(std::span<const std::uint32_t> members) const {
  if (members.empty()) return {Vec3::Zero(), Vec3::Zero()};
  Vec3 lo = points_[members[0]], hi = lo;
  for (auto i : members) {
    lo = lo.cwiseMin(points_[i]);
    hi = hi.cwiseMax(points_[i]);
  }
  return {lo, hi};
}

// Options left to the cloud (0) from its own spacing (result.spacing), noise, size and
// extent; the options used go to `result`.
void Detector::derive_scale(std::span<const std::uint32_t> members,
                            const detail::NeighbourSample& sample, RansacResult& result) {
  const auto [lo, hi] = bounds(members);
  const bool derived = !(o_.epsilon > 0.0);
  if (derived) {
    // The noise where the region is flattest (a low quantile: curvature and edges raise the
    // others), and a tenth of the spacing for exact points.
    result.noise = sample.noise(0.05);
    // Exact points on curved surfaces only (a small part sampled coarsely, fillets and tubes
    // everywhere): the planes through their neighbourhoods bend with the surface, the quadrics
    // do not. On a scan the two agree within the quadric's overfitting.
    if (const double curved = sample.curved_noise(0.05); curved < 0.1 * result.noise) {
      result.noise = curved;
    }
    o_.epsilon = std::max(3.0 * result.noise, 0.1 * result.spacing);
    if (!(o_.epsilon > 0.0)) o_.epsilon = 1e-6 * std::max((hi - lo).maxCoeff(), 1e-9);
  }
  if (o_.min_points <= 0) {
    o_.min_points = std::max<long long>(8, static_cast<long long>(members.size() / 1000));
  }
  if (!(o_.max_radius > 0.0)) o_.max_radius = 10.0 * std::max((hi - lo).maxCoeff(), o_.epsilon);
  noise_ = result.noise;
  spacing_ = result.spacing;
  exact_ = derived && noise_ <= kFloorShare * o_.epsilon;
  result.epsilon = o_.epsilon;
  result.min_points = o_.min_points;
  result.max_radius = o_.max_radius;
}

// Draws candidates and extracts the best while one of min_points may still be missed (the
// search of the module comment). False when the interrupt fired.
bool Detector::search() {
  constexpr int kBatch = 64;
  for (;;) {
    if (o_.interrupt.fired()) {
      cancelled_ = true;
      return false;
    }
    for (int b = 0; b < kBatch; ++b) draw();
    while (!heap_.empty()) {
      Candidate top = heap_.top();
      if (top.stamp != extractions_) {
        heap_.pop();
        if (assignment_[top.seed] >= 0) continue;
        const int starts[1] = {grid_->cell_of(top.seed)};
        top.score = component(top.surface, starts, true, nullptr);
        top.stamp = extractions_;
        if (top.score >= 0.5 * static_cast<double>(o_.min_points)) heap_.push(top);
        continue;
      }
      if (probability(top.score, draws_) < o_.probability) break;
      heap_.pop();
      extract(top);
    }
    if (remaining_count_ < static_cast<std::size_t>(o_.min_points)) break;
    if (remaining_.size() > 2 * remaining_count_ + 64) compact_remaining();
    const bool heap_done = heap_.empty() || heap_.top().score < static_cast<double>(o_.min_points);
    if (heap_done && probability(static_cast<double>(o_.min_points), draws_) >= o_.probability)
      break;
    if (draws_ >= o_.max_candidates) break;
  }
  return true;
}

RansacResult Detector::run() {
  RansacResult result;
  const std::size_t n = points_.size();
  cos_alpha_ = std::cos(o_.normal_deviation_deg * std::numbers::pi / 180.0);
  has_normal_.assign(n, 0);
  assignment_.assign(n, -1);
  std::vector<std::uint32_t> members;
  for (std::size_t i = 0; i < n; ++i) {
    if (!points_[i].allFinite()) continue;
    members.push_back(static_cast<std::uint32_t>(i));
    const double len = normals_[i].norm();
    has_normal_[i] = (std::isfinite(len) && std::abs(len - 1.0) < 1e-3) ? 1 : 0;
  }
  result.assignment.assign(n, -1);
  std::size_t seeds = 0;
  for (auto i : members) seeds += has_normal_[i] ? 1 : 0;
  if (members.size() < static_cast<std::size_t>(std::max<long long>(o_.min_points, 3)) ||
      seeds < 4) {
    result.reason = members.empty() ? "no finite points"
                                    : "too few points with normals for a shape of " +
                                          std::to_string(o_.min_points) + " points (" +
                                          std::to_string(seeds) + " with normals)";
    // Even a region too small to search reports the options it stands for, so that no 0
    // (derived) reaches the steps after the detection.
    const detail::NeighbourSample sample(points_, members, !(o_.epsilon > 0.0));
    if (!members.empty() && o_.epsilon == 0.0) result.spacing = sample.spacing();
    derive_scale(members, sample, result);
    return result;
  }
  // One neighbour search for the spacing, the noise and the reach; the plane residuals also
  // when epsilon is given, for the primitives' quality (RansacResult::plane_noise).
  const detail::NeighbourSample sample(points_, members, true, !(o_.epsilon > 0.0));
  result.spacing = sample.spacing();
  derive_scale(members, sample, result);
  // What estimate_noise gives over every point of the region, when the sample holds them all.
  if (members.size() == points_.size()) result.plane_noise = sample.noise(0.05);
  const auto [lo, hi] = bounds(members);
  // Connectivity: three typical spacings, but enough for the sparser parts of the cloud too
  // (terrestrial scans mix dense near surfaces with sparse far ones).
  double beta = o_.cluster_epsilon > 0.0
                    ? o_.cluster_epsilon
                    : o_.cluster_scale * std::max(1.5 * result.spacing, sample.reach(0.9));
  beta = std::max(beta, o_.epsilon);
  result.cluster_epsilon = beta;
  grid_ = std::make_unique<PointGrid>(points_, members, beta, o_.seed);
  cell_stamp_.assign(grid_->cell_count(), 0);
  const double extent = std::max((hi - lo).maxCoeff(), beta);
  for (double cell = 2.0 * beta; levels_.size() < 10; cell *= 2.0) {
    levels_.push_back(
        std::make_unique<PointGrid>(points_, members, cell, o_.seed + levels_.size() + 1));
    if (cell >= extent) break;
  }
  for (auto i : members) {
    if (has_normal_[i]) remaining_.push_back(i);
  }
  remaining_count_ = members.size();

  if (!search()) return result;
  if (o_.relabel && !shapes_.empty()) {
    relabel();
    // On exact clouds, points that fit their shape only within epsilon belong to a surface not
    // found yet (a bore's wall whose points the fillets beside it held), as do the points of a
    // shape that fits none exactly: freed, searched again, labelled again.
    if (const std::size_t freed = exact_ ? free_inexact() : 0; freed > 0) {
      if (freed >= static_cast<std::size_t>(o_.min_points)) {
        heap_ = {};
        searched_ += draws_;
        draws_ = 0;
        if (!search()) return result;
      }
      relabel();  // also the freed points no new shape took, back to the shape they fit best
    }
    if (o_.by_evidence && retype()) relabel();
    // Exact points no shape took, on one surface the search could not see by their normals.
    if (exact_) {
      trim_to_exact_cores();
      fit_leftovers();
    }
  }
  if (o_.edges_to_smaller && !shapes_.empty()) give_edges_to_smaller();
  if (o_.merge_same_surface &&
      detail::merge_same_surface(points_, shapes_, assignment_, o_.epsilon,
                                 exact_ ? kExactShare * noise_floor() : 0.0) > 0) {
    for (auto& shape : shapes_) shape.rms = rms_of(shape.surface, shape.inliers);
  }
  if (o_.relabel && !shapes_.empty()) {
    adopt_free();
    for (auto& shape : shapes_) shape.rms = rms_of(shape.surface, shape.inliers);
  }
  result.candidates = searched_ + draws_;
  result.assignment = assignment_;
  result.shapes = std::move(shapes_);
  if (result.shapes.empty()) {
    result.reason = "no shape of " + std::to_string(o_.min_points) + " points within epsilon " +
                    std::to_string(o_.epsilon) + " m found (" + std::to_string(draws_) +
                    " samples drawn)";
  }
  return result;
}

}  // namespace detail

kernel::Result<RansacResult> detect_shapes(std::span<const Vec3> points,
                                           std::span<const Vec3> normals,
                                           const RansacOptions& options) {
  using kernel::ErrorCode;
  if (points.size() != normals.size()) {
    return kernel::Error{ErrorCode::InvalidArgument,
                         "detect_shapes: " + std::to_string(points.size()) + " points but " +
                             std::to_string(normals.size()) + " normals"};
  }
  if (points.size() >= (std::size_t{1} << 31)) {
    return kernel::Error{ErrorCode::InvalidArgument, "detect_shapes: more than 2^31 points"};
  }
  if (!(options.epsilon >= 0.0) || !std::isfinite(options.epsilon)) {
    return kernel::Error{ErrorCode::InvalidArgument,
                         "fit option epsilon must be >= 0 (0: from the cloud)"};
  }
  if (!(options.normal_deviation_deg > 0.0 && options.normal_deviation_deg < 90.0)) {
    return kernel::Error{ErrorCode::InvalidArgument,
                         "fit option normal_deviation_deg must be in (0, 90)"};
  }
  if (!(options.cluster_scale > 0.0) || !std::isfinite(options.cluster_scale)) {
    return kernel::Error{ErrorCode::InvalidArgument, "fit option cluster_scale must be > 0"};
  }
  if (!(options.cluster_epsilon >= 0.0) || !std::isfinite(options.cluster_epsilon)) {
    return kernel::Error{ErrorCode::InvalidArgument, "fit option cluster_epsilon must be >= 0"};
  }
  if (options.min_points != 0 && options.min_points < 3) {
    return kernel::Error{ErrorCode::InvalidArgument,
                         "fit option min_points must be >= 3 (or 0: from the cloud)"};
  }
  if (!(options.probability > 0.0 && options.probability < 1.0)) {
    return kernel::Error{ErrorCode::InvalidArgument, "fit option probability must be in (0, 1)"};
  }
  if (!(options.max_radius >= 0.0) || !std::isfinite(options.max_radius)) {
    return kernel::Error{ErrorCode::InvalidArgument,
                         "fit option max_radius must be >= 0 (0: from the cloud)"};
  }
  detail::Detector detector(points, normals, options);
  RansacResult result = detector.run();
  if (detector.cancelled()) return options.interrupt.error("while detecting shapes");
  return result;
}

}  // namespace csgtile::fit
