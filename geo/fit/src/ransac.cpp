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
#include "shape_merge.h"
#include "synth/random.h"

namespace csgtile::fit {

namespace {

using detail::PointGrid;
using kernel::Vec3;

constexpr int kSampledPerCell = 4;
// A twentieth of epsilon: the residual floor of exact points (see Detector::noise_floor).
constexpr double kFloorShare = 0.05;
constexpr double kSampleFactor = 4.0;

struct Candidate {
  double score = 0.0;
  std::uint64_t order = 0;  // draw order: ties go to the earlier candidate
  std::uint64_t stamp = 0;  // extractions when scored
  std::uint32_t seed = 0;
  Surface surface;
};

struct CandidateLess {
  bool operator()(const Candidate& a, const Candidate& b) const {
    if (a.score != b.score) return a.score < b.score;
    return a.order > b.order;
  }
};

class Detector {
 public:
  Detector(std::span<const Vec3> points, std::span<const Vec3> normals, const RansacOptions& o)
      : points_(points), normals_(normals), o_(o), random_(o.seed) {}

  RansacResult run();
  /// Whether run() stopped early because the options' interrupt fired.
  bool cancelled() const { return cancelled_; }

 private:
  bool compatible(const Surface& s, std::uint32_t i) const {
    if (std::abs(surface_distance(s, points_[i])) > o_.epsilon) return false;
    if (!has_normal_[i]) return true;
    return std::abs(surface_normal(s, points_[i]).dot(normals_[i])) >= cos_alpha_;
  }

  // Flood fill from `starts` through cells that hold compatible unassigned points. Sampled:
  // returns the extrapolated count of the component reached from the first start. Exact: the
  // largest component's points (ascending) in `out`, returns its size.
  double component(const Surface& s, std::span<const int> starts, bool sampled,
                   std::vector<std::uint32_t>* out);
  void draw();
  bool extract(const Candidate& c);
  std::vector<std::uint32_t> exact_inliers(const Surface& s, std::span<const std::uint32_t> near);
  std::optional<Surface> simpler(const Surface& s, std::span<const std::uint32_t> inliers);
  std::optional<Surface> by_evidence(const Surface& s, std::span<const std::uint32_t> inliers);
  double criterion(const Surface& s, std::span<const std::uint32_t> inliers) const;
  // At least 97 % of `inliers` are compatible with `alt`: it may stand for the shape.
  bool keeps_most(const Surface& alt, std::span<const std::uint32_t> inliers) const {
    std::size_t kept = 0;
    for (auto i : inliers) kept += compatible(alt, i) ? 1 : 0;
    return static_cast<double>(kept) >= 0.97 * static_cast<double>(inliers.size());
  }
  // RMS of the inliers' distances to the surface.
  double rms_of(const Surface& s, std::span<const std::uint32_t> inliers) const {
    double sum = 0.0;
    for (auto i : inliers) {
      const double d = surface_distance(s, points_[i]);
      sum += d * d;
    }
    return std::sqrt(sum / static_cast<double>(std::max<std::size_t>(inliers.size(), 1)));
  }
  // The residual below which points count as exact: the noise, at least a twentieth of epsilon.
  double noise_floor() const { return std::max(noise_, kFloorShare * o_.epsilon); }
  // How much better (by the criterion) another type must score to replace a shape.
  static double evidence_margin(std::span<const std::uint32_t> inliers) {
    return 2.0 * std::log(static_cast<double>(std::max<std::size_t>(inliers.size(), 1)));
  }
  Vec3 centroid_of(std::span<const std::uint32_t> inliers) const {
    Vec3 c = Vec3::Zero();
    for (auto i : inliers) c += points_[i];
    return c / static_cast<double>(std::max<std::size_t>(inliers.size(), 1));
  }
  std::optional<Surface> circle_along(const Vec3& axis,
                                      std::span<const std::uint32_t> inliers) const;
  std::optional<Surface> cylinder_from_normals(std::span<const std::uint32_t> inliers) const;
  std::optional<Surface> cone_from_normals(std::span<const std::uint32_t> inliers,
                                           const Vec3& inside) const;
  std::optional<Surface> wall_through_ring(const Surface& plane,
                                           std::span<const std::uint32_t> inliers);
  std::optional<Surface> cylinder_across_plane(const Surface& plane,
                                               std::span<const std::uint32_t> inliers) const;
  double probability(double n, std::uint64_t draws) const {
    const double remaining = static_cast<double>(std::max<std::size_t>(remaining_count_, 1));
    // A good minimal sample needs the seed in the shape, the right level, and the other
    // samples of the seed's cell in the shape too: kSampleFactor for the last, measured on
    // thin faces (a beam side in a cell shared with its neighbours).
    const double p =
        std::min(1.0, n / (remaining * static_cast<double>(levels_.size()) * kSampleFactor));
    if (p >= 1.0) return 1.0;
    return 1.0 - std::exp(static_cast<double>(draws) * std::log1p(-p));
  }
  void compact_remaining();
  void relabel();
  bool retype();
  std::pair<Vec3, Vec3> bounds(std::span<const std::uint32_t> members) const;
  void derive_scale(std::span<const std::uint32_t> members, const detail::NeighbourSample& sample,
                    RansacResult& result);
  void give_edges_to_smaller();
  // Starts a new visit of the connectivity grid (no cell visited yet).
  void new_visit() {
    if (++stamp_ == 0) {
      std::fill(cell_stamp_.begin(), cell_stamp_.end(), 0);
      stamp_ = 1;
    }
  }
  // Calls `f(j)` once for each point of the cells next to (or holding) one of `inliers`.
  template <typename F>
  void for_points_near(std::span<const std::uint32_t> inliers, F&& f) {
    new_visit();
    for (auto i : inliers) {
      const int cell = grid_->cell_of(i);
      if (cell < 0) continue;
      for_unvisited_neighbours(cell, [&](int next) {
        for (auto j : grid_->points(next)) f(j);
      });
    }
  }
  // Calls `f(next)` for each cell of the 3×3×3 block around `cell` not visited yet, marking it.
  template <typename F>
  void for_unvisited_neighbours(int cell, F&& f) {
    const auto& c = grid_->coords(cell);
    for (int dx = -1; dx <= 1; ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dz = -1; dz <= 1; ++dz) {
          const int next = grid_->find(c[0] + dx, c[1] + dy, c[2] + dz);
          if (next < 0 || cell_stamp_[static_cast<std::size_t>(next)] == stamp_) continue;
          cell_stamp_[static_cast<std::size_t>(next)] = stamp_;
          f(next);
        }
      }
    }
  }

  std::span<const Vec3> points_;
  std::span<const Vec3> normals_;
  RansacOptions o_;
  geo::detail::Random random_;
  double cos_alpha_ = 0.0;
  double noise_ = 0.0;      // estimated noise (derived epsilon), else 0
  double spacing_ = 0.0;    // the region's point spacing (RansacResult::spacing)
  bool exact_ = false;      // epsilon derived and the noise under a twentieth of it
  bool cancelled_ = false;  // the interrupt fired: run() returned early
  std::vector<char> has_normal_;
  std::vector<int> assignment_;
  std::vector<std::uint32_t> remaining_;  // may hold assigned points until compacted
  std::size_t remaining_count_ = 0;
  std::unique_ptr<PointGrid> grid_;                 // connectivity grid
  std::vector<std::unique_ptr<PointGrid>> levels_;  // sampling grids, growing cells
  std::vector<std::uint32_t> cell_stamp_;
  std::uint32_t stamp_ = 0;
  std::priority_queue<Candidate, std::vector<Candidate>, CandidateLess> heap_;
  std::uint64_t draws_ = 0;
  std::uint64_t extractions_ = 0;
  std::vector<DetectedShape> shapes_;
};

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

// Bayesian information criterion of a surface on points: n·ln(RSS/n) + k·ln(n), k its
// parameter count, the residual floored at the noise (or a twentieth of epsilon on exact
// points), so that on noisy points the simpler surface wins at equal error and on exact ones
// the surface whose error is clearly smaller does.
double Detector::criterion(const Surface& s, std::span<const std::uint32_t> inliers) const {
  const double n = static_cast<double>(std::max<std::size_t>(inliers.size(), 1));
  double rss = 0.0;
  for (auto i : inliers) {
    const double d = surface_distance(s, points_[i]);
    rss += d * d;
  }
  const double floor = noise_floor();
  return n * std::log(std::max(rss / n, floor * floor)) +
         detail::parameter_count(s.type) * std::log(n);
}

// A cylinder through points with normals: its axis is the direction the normals avoid (the
// least principal direction of their scatter), its circle the least-squares one of the points
// projected across the axis; refined by least squares. nullopt for too few normals.
std::optional<Surface> Detector::cylinder_from_normals(
    std::span<const std::uint32_t> inliers) const {
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  std::size_t count = 0;
  for (auto i : inliers) {
    if (!has_normal_[i]) continue;
    scatter += normals_[i] * normals_[i].transpose();
    ++count;
  }
  if (count < 5) return std::nullopt;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(scatter);
  if (eig.info() != Eigen::Success) return std::nullopt;
  const auto s = circle_along(eig.eigenvectors().col(0).normalized(), inliers);
  if (!s) return std::nullopt;
  return detail::refine_surface(*s, points_, inliers);
}

// The cylinder along `axis` through the least-squares circle of the points seen along it (not
// refined); nullopt when no circle fits or its radius reaches max_radius.
std::optional<Surface> Detector::circle_along(const Vec3& axis,
                                              std::span<const std::uint32_t> inliers) const {
  if (inliers.empty()) return std::nullopt;
  Vec3 e1, e2;
  detail::orthonormal_basis(axis, e1, e2);
  const Vec3 origin = points_[inliers[0]];
  std::vector<kernel::Vec2> across;
  across.reserve(inliers.size());
  for (auto i : inliers) {
    const Vec3 d = points_[i] - origin;
    across.emplace_back(d.dot(e1), d.dot(e2));
  }
  const auto circle = detail::fit_circle(across);
  if (!circle || !(circle->radius < o_.max_radius)) return std::nullopt;
  Surface s;
  s.type = ShapeType::Cylinder;
  s.axis = detail::canonical_axis(axis);
  s.point = origin + circle->centre.x() * e1 + circle->centre.y() * e2;
  s.radius = circle->radius;
  return s;
}

// A cylinder through the points of a plane that bend away from it: their heights over the
// plane as a quadratic h(u, v); the direction it curves most along is across the axis, its
// curvature 1/r. Refined by least squares; nullopt when the points do not curve.
std::optional<Surface> Detector::cylinder_across_plane(
    const Surface& plane, std::span<const std::uint32_t> inliers) const {
  if (inliers.size() < 8) return std::nullopt;
  Vec3 e1, e2;
  detail::orthonormal_basis(plane.axis, e1, e2);
  const Vec3 centre = centroid_of(inliers);
  Eigen::MatrixXd a(inliers.size(), 6);
  Eigen::VectorXd h(inliers.size());
  for (std::size_t k = 0; k < inliers.size(); ++k) {
    const Vec3 d = points_[inliers[k]] - centre;
    const double u = d.dot(e1), v = d.dot(e2);
    a.row(static_cast<Eigen::Index>(k)) << u * u, u * v, v * v, u, v, 1.0;
    h(static_cast<Eigen::Index>(k)) = d.dot(plane.axis);
  }
  const Eigen::VectorXd c = a.colPivHouseholderQr().solve(h);
  if (!c.allFinite()) return std::nullopt;
  Eigen::Matrix2d hessian;
  hessian << 2.0 * c(0), c(1), c(1), 2.0 * c(2);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(hessian);
  if (eig.info() != Eigen::Success) return std::nullopt;
  const int most = std::abs(eig.eigenvalues()(0)) > std::abs(eig.eigenvalues()(1)) ? 0 : 1;
  const double k = eig.eigenvalues()(most);
  if (!(std::abs(k) > 0.0) || !std::isfinite(k)) return std::nullopt;
  const Eigen::Vector2d along = eig.eigenvectors().col(1 - most);
  Surface s;
  s.type = ShapeType::Cylinder;
  s.radius = 1.0 / std::abs(k);
  if (!(s.radius < o_.max_radius)) return std::nullopt;
  s.axis = detail::canonical_axis((along.x() * e1 + along.y() * e2).normalized());
  // The centre of curvature lies on the side the points bend towards.
  s.point = centre + (k > 0.0 ? 1.0 : -1.0) * s.radius * plane.axis;
  return detail::refine_surface(s, points_, inliers);
}

// A plane whose points lie on one circle of it is the ring where a cylinder's wall (a hole, a
// pin) meets the plane: when points of other shapes or none lie on that cylinder next to the
// ring but off its plane (the wall's rims and rows), the cylinder.
std::optional<Surface> Detector::wall_through_ring(const Surface& plane,
                                                   std::span<const std::uint32_t> inliers) {
  if (inliers.size() < 6) return std::nullopt;
  auto wall = circle_along(plane.axis, inliers);
  // On the circle: every point within the noise floor of the cylinder.
  if (!wall || !(rms_of(*wall, inliers) <= noise_floor())) return std::nullopt;
  std::size_t off = 0;
  for_points_near(inliers, [&](std::uint32_t j) {
    if (std::abs(surface_distance(*wall, points_[j])) <= o_.epsilon &&
        std::abs(surface_distance(plane, points_[j])) > o_.epsilon) {
      ++off;
    }
  });
  if (2 * off < inliers.size()) return std::nullopt;
  // The ring's normals are those of the plane it was taken for (a sparse wall's points find
  // their neighbours on the ring): no evidence against the wall.
  for (auto i : inliers) has_normal_[i] = 0;
  return wall;
}

// A cone through points with normals: turned towards `inside` (a point on the cone's concave
// side, e.g. the centre of a sphere fitted to the same points), a cone's normals all make the
// angle 90° − θ with its axis, so their tips lie on one plane whose normal is the axis (the
// least principal direction of their centred scatter) at distance sin θ from the origin; the
// apex is the point every tangent plane passes through (least squares). Refined by least
// squares; nullopt for too few normals, a cylinder (θ under a degree) or a singular apex.
std::optional<Surface> Detector::cone_from_normals(std::span<const std::uint32_t> inliers,
                                                   const Vec3& inside) const {
  std::vector<Vec3> in;
  std::vector<std::uint32_t> used;
  for (auto i : inliers) {
    if (!has_normal_[i]) continue;
    in.push_back(normals_[i].dot(inside - points_[i]) < 0.0 ? Vec3(-normals_[i]) : normals_[i]);
    used.push_back(i);
  }
  if (in.size() < 6) return std::nullopt;
  Vec3 mean = Vec3::Zero();
  for (const Vec3& n : in) mean += n;
  mean /= static_cast<double>(in.size());
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const Vec3& n : in) scatter += (n - mean) * (n - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(scatter);
  if (eig.info() != Eigen::Success) return std::nullopt;
  Vec3 axis = eig.eigenvectors().col(0).normalized();
  double sin_angle = mean.dot(axis);
  if (sin_angle < 0.0) {
    axis = -axis;
    sin_angle = -sin_angle;
  }
  if (!(sin_angle > std::sin(std::numbers::pi / 180.0)) || !(sin_angle < 1.0)) return std::nullopt;
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  Vec3 b = Vec3::Zero();
  for (std::size_t k = 0; k < in.size(); ++k) {
    const Eigen::Matrix3d nn = in[k] * in[k].transpose();
    a += nn;
    b += nn * points_[used[k]];
  }
  const Eigen::FullPivLU<Eigen::Matrix3d> lu(a);
  if (!lu.isInvertible()) return std::nullopt;
  Surface s;
  s.type = ShapeType::Cone;
  s.point = lu.solve(b);
  s.axis = axis;
  s.angle = std::asin(sin_angle);
  if (!s.point.allFinite()) return std::nullopt;
  return detail::refine_surface(s, points_, inliers);
}

// Type selection by evidence: the plane and the cylinder (for a sphere also the cone) that fit
// the same points are compared by the criterion above; another type replaces the shape when
// it keeps nearly all of its points and scores clearly better, or, where the errors lie below
// the criterion's floor, when its error is a small share of the shape's (a tenth; a hundredth
// for a plane within the floor). A plane is only questioned on exact clouds: a ring of a hole's
// wall, a strip of a wide cylinder.
std::optional<Surface> Detector::by_evidence(const Surface& s,
                                             std::span<const std::uint32_t> inliers) {
  if (s.type == ShapeType::Plane) {
    // A plane stays a plane unless its points stray from it by more than a quarter of the floor
    // and a cylinder through them is exact, within the floor and within a tenth of the plane's
    // error (a narrow strip of a wide cylinder, the root of a gear between two teeth, bends by
    // less than the floor; what marks it is the cylinder's far smaller error): on exact clouds
    // only, since on noisy ones the edge points it took from its neighbours would bend a
    // cylinder towards them (and a bent plane is never exact).
    if (!exact_) return std::nullopt;
    if (auto wall = wall_through_ring(s, inliers)) return wall;
    const double floor = noise_floor();
    const double flat = rms_of(s, inliers);
    if (!(flat > 0.25 * floor)) return std::nullopt;
    auto cylinder = cylinder_across_plane(s, inliers);
    if (!cylinder || !keeps_most(*cylinder, inliers)) return std::nullopt;
    const double bent = rms_of(*cylinder, inliers);
    if (!(bent <= std::min(floor, 0.1 * flat))) return std::nullopt;
    // Within the floor the criterion sees no difference: a strip bending by less than the
    // floor is a cylinder only when the cylinder fits it a hundred times better.
    if (flat <= floor) return bent <= 0.01 * flat ? cylinder : std::nullopt;
    if (criterion(*cylinder, inliers) < criterion(s, inliers) - evidence_margin(inliers)) {
      return cylinder;
    }
    return std::nullopt;
  }
  std::vector<Surface> options;
  if (auto plane = detail::fit_plane(points_, inliers)) options.push_back(*plane);
  if (s.type != ShapeType::Cylinder && o_.shapes[static_cast<int>(ShapeType::Cylinder)]) {
    if (auto cylinder = cylinder_from_normals(inliers)) options.push_back(*cylinder);
  }
  if (s.type == ShapeType::Sphere && o_.shapes[static_cast<int>(ShapeType::Cone)]) {
    // A wide cone's belt is nearly a sphere's: its normals tell them apart.
    if (auto cone = cone_from_normals(inliers, s.point)) options.push_back(*cone);
  }
  std::erase_if(options, [&](const Surface& alt) { return !keeps_most(alt, inliers); });
  double best = criterion(s, inliers) - evidence_margin(inliers);
  std::optional<Surface> chosen;
  for (const Surface& alt : options) {
    const double score = criterion(alt, inliers);
    if (score < best) {
      best = score;
      chosen = alt;
    }
  }
  if (chosen) return chosen;
  // Below the floor the criterion cannot tell errors apart, so the surface of fewer parameters
  // wins. But a surface whose points fit another to a tenth of the floor and of its own error
  // has them exact on the other (the belt of a cylinder, taken for the sphere through its
  // middle circle, fits that sphere within a cloud-wide noise estimate and the cylinder to
  // rounding): the other, the one of fewest parameters when several are.
  const double own = rms_of(s, inliers);
  const double exact = 0.1 * std::min(noise_floor(), own);
  for (const Surface& alt : options) {
    if (!(rms_of(alt, inliers) <= exact)) continue;
    if (!chosen || detail::parameter_count(alt.type) < detail::parameter_count(chosen->type)) {
      chosen = alt;
    }
  }
  return chosen;
}

std::optional<Surface> Detector::simpler(const Surface& s, std::span<const std::uint32_t> inliers) {
  // A simpler surface replaces a curved one when it keeps nearly all of its points: fewer
  // parameters at equal error (a plane patch is also a large-radius cylinder). With
  // `by_evidence`, only when it also scores no worse by the information criterion (on exact
  // points a fillet's plane keeps its points but not its error).
  const double own = o_.by_evidence ? criterion(s, inliers) : 0.0;
  auto keeps = [&](const Surface& alt) {
    if (o_.by_evidence && criterion(alt, inliers) > own) return false;
    return keeps_most(alt, inliers);
  };
  if (s.type != ShapeType::Plane) {
    if (auto plane = detail::fit_plane(points_, inliers); plane && keeps(*plane)) return plane;
  }
  if (s.type == ShapeType::Cone || s.type == ShapeType::Torus) {
    Surface cylinder;
    cylinder.type = ShapeType::Cylinder;
    cylinder.axis = s.axis;
    cylinder.point = s.point;
    double sum = 0.0;
    for (auto i : inliers)
      sum += (points_[i] - s.point - (points_[i] - s.point).dot(s.axis) * s.axis).norm();
    cylinder.radius = sum / static_cast<double>(std::max<std::size_t>(inliers.size(), 1));
    if (auto refined = detail::refine_surface(cylinder, points_, inliers);
        refined && refined->radius < o_.max_radius && keeps(*refined)) {
      return refined;
    }
  }
  if (s.type == ShapeType::Torus && !inliers.empty()) {
    // A torus whose tube is seen over a short arc of a large circle: the cylinder along the
    // tube, its axis the circle's tangent at the points' centroid.
    const Vec3 centroid = centroid_of(inliers);
    const Vec3 w = centroid - s.point - (centroid - s.point).dot(s.axis) * s.axis;
    if (w.norm() > 0.0) {
      const Vec3 u = w.normalized();
      Surface tube;
      tube.type = ShapeType::Cylinder;
      tube.axis = detail::canonical_axis(s.axis.cross(u).normalized());
      tube.point = s.point + s.radius * u;
      tube.radius = s.radius2;
      if (auto refined = detail::refine_surface(tube, points_, inliers);
          refined && refined->radius < o_.max_radius && keeps(*refined)) {
        return refined;
      }
    }
    Surface sphere;
    sphere.type = ShapeType::Sphere;
    sphere.point = s.point;
    sphere.radius = s.radius + s.radius2;
    if (auto refined = detail::refine_surface(sphere, points_, inliers);
        refined && refined->radius < o_.max_radius && keeps(*refined)) {
      return refined;
    }
  }
  return std::nullopt;
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
// a shape left with fewer than min_points is dissolved and its points labelled again. The
// last labelling is made with the final surfaces, so labels and surfaces agree.
void Detector::relabel() {
  const std::size_t n = points_.size();
  std::vector<double> best(n);
  std::vector<int> label(n);
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
    if (!changed) break;
    const bool refit = !dissolved && refits < 2;
    std::vector<DetectedShape> kept;
    std::vector<int> renumber(shapes_.size(), -1);
    for (std::size_t s = 0; s < shapes_.size(); ++s) {
      if (static_cast<long long>(members[s].size()) < o_.min_points) continue;
      DetectedShape shape = std::move(shapes_[s]);
      if (refit && members[s] != shape.inliers) {
        if (auto better = detail::refine_surface(shape.surface, points_, members[s])) {
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
    } else if (!dissolved) {
      break;  // labelled with the final surfaces
    }
  }
  for (auto& shape : shapes_) shape.rms = rms_of(shape.surface, shape.inliers);
}

// Types again on the final points: a curved shape found first may have held a neighbour's
// edge points that relabel() gave back (the belt of a wide cylinder between two fillets, taken
// with their rims for the sphere through it); on its own points another curved type can be
// the better. Planes are left as extraction decided, in both directions: a curved shape that
// gave its rims away may be left with points on one circle (a hole's wall seen as one ring),
// which a plane fits as well. True when a shape changed type.
bool Detector::retype() {
  bool changed = false;
  for (auto& shape : shapes_) {
    if (shape.surface.type == ShapeType::Plane) continue;
    auto alt = by_evidence(shape.surface, shape.inliers);
    if (!alt || alt->type == ShapeType::Plane) continue;
    shape.surface = *alt;
    changed = true;
  }
  return changed;
}

// Edges: a point within epsilon of two neighbouring shapes lies on both (at their shared edge
// its normal belongs to neither); it goes to the smallest of them that has at most half the
// points of its present one — once, among the points next to that shape's inliers (growing
// further would run along the line where the two unbounded surfaces meet, past the feature) —,
// since a small feature (a hole's wall, a fillet, a boss) needs its rims while a large face loses
// nothing to speak of. No shape is left under min_points: a shape that would be keeps its points.
void Detector::give_edges_to_smaller() {
  const std::size_t n = points_.size();
  std::vector<int> moved(assignment_);
  auto size_of = [&](int s) { return shapes_[static_cast<std::size_t>(s)].inliers.size(); };
  for (std::size_t s = 0; s < shapes_.size(); ++s) {
    const int self = static_cast<int>(s);
    for_points_near(shapes_[s].inliers, [&](std::uint32_t j) {
      const int now = assignment_[j];
      if (now < 0 || now == self || 2 * size_of(self) > size_of(now)) return;
      if (std::abs(surface_distance(shapes_[s].surface, points_[j])) > o_.epsilon) return;
      // The smallest candidate wins; on equal sizes the shape found first.
      if (moved[j] != now && size_of(moved[j]) <= size_of(self)) return;
      moved[j] = self;
    });
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
  // One neighbour search for the spacing, the noise and the reach.
  const detail::NeighbourSample sample(points_, members, !(o_.epsilon > 0.0));
  result.spacing = sample.spacing();
  derive_scale(members, sample, result);
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

  constexpr int kBatch = 64;
  for (;;) {
    if (o_.interrupt.fired()) {
      cancelled_ = true;
      return result;
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
  if (o_.relabel && !shapes_.empty()) {
    relabel();
    if (o_.by_evidence && retype()) relabel();
  }
  if (o_.edges_to_smaller && !shapes_.empty()) give_edges_to_smaller();
  if (o_.merge_same_surface &&
      detail::merge_same_surface(points_, shapes_, assignment_, o_.epsilon) > 0) {
    for (auto& shape : shapes_) shape.rms = rms_of(shape.surface, shape.inliers);
  }
  result.candidates = draws_;
  result.assignment = assignment_;
  result.shapes = std::move(shapes_);
  if (result.shapes.empty()) {
    result.reason = "no shape of " + std::to_string(o_.min_points) + " points within epsilon " +
                    std::to_string(o_.epsilon) + " m found (" + std::to_string(draws_) +
                    " samples drawn)";
  }
  return result;
}

}  // namespace

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
  Detector detector(points, normals, options);
  RansacResult result = detector.run();
  if (detector.cancelled()) return options.interrupt.error("while detecting shapes");
  return result;
}

}  // namespace csgtile::fit
