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
//    kept only when it explains at least as many points; a curved shape that a plane (or a
//    cone that a cylinder) explains as well is replaced by the simpler one.

#include <algorithm>
#include <cmath>
#include <numbers>
#include <queue>

#include "fit_internal.h"
#include "synth/random.h"

namespace csgtile::fit {

namespace {

using detail::PointGrid;
using kernel::Vec3;

constexpr int kSampledPerCell = 4;
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

  std::span<const Vec3> points_;
  std::span<const Vec3> normals_;
  RansacOptions o_;
  geo::detail::Random random_;
  double cos_alpha_ = 0.0;
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
  if (++stamp_ == 0) {
    std::fill(cell_stamp_.begin(), cell_stamp_.end(), 0);
    stamp_ = 1;
  }
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
      const auto& c = grid_->coords(cell);
      for (int dx = -1; dx <= 1; ++dx) {
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dz = -1; dz <= 1; ++dz) {
            const int next = grid_->find(c[0] + dx, c[1] + dy, c[2] + dz);
            if (next < 0 || cell_stamp_[static_cast<std::size_t>(next)] == stamp_) continue;
            cell_stamp_[static_cast<std::size_t>(next)] = stamp_;
            queue.push_back(next);
          }
        }
      }
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

std::optional<Surface> Detector::simpler(const Surface& s, std::span<const std::uint32_t> inliers) {
  // A simpler surface replaces a curved one when it keeps nearly all of its points: fewer
  // parameters at equal error (a plane patch is also a large-radius cylinder).
  auto keeps = [&](const Surface& alt) {
    std::size_t kept = 0;
    for (auto i : inliers) kept += compatible(alt, i) ? 1 : 0;
    return static_cast<double>(kept) >= 0.97 * static_cast<double>(inliers.size());
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
  if (s.type == ShapeType::Torus) {
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
  if (static_cast<long long>(inliers.size()) < o_.min_points) return false;
  if ((surface.type == ShapeType::Cylinder || surface.type == ShapeType::Sphere) &&
      surface.radius >= o_.max_radius) {
    return false;
  }
  DetectedShape shape;
  shape.surface = surface;
  double sum = 0.0;
  for (auto i : inliers) {
    const double d = surface_distance(surface, points_[i]);
    sum += d * d;
    assignment_[i] = static_cast<int>(shapes_.size());
  }
  shape.rms = std::sqrt(sum / static_cast<double>(inliers.size()));
  remaining_count_ -= inliers.size();
  shape.inliers = std::move(inliers);
  shapes_.push_back(std::move(shape));
  ++extractions_;
  if (remaining_.size() > 2 * remaining_count_ + 64) compact_remaining();
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
    return result;
  }
  result.spacing = detail::estimate_spacing(points_, members);
  // Connectivity: three typical spacings, but enough for the sparser parts of the cloud too
  // (terrestrial scans mix dense near surfaces with sparse far ones).
  double beta = o_.cluster_epsilon > 0.0 ? o_.cluster_epsilon
                                         : std::max(1.5 * result.spacing,
                                                    detail::neighbour_reach(points_, members, 0.9));
  beta = std::max(beta, o_.epsilon);
  result.cluster_epsilon = beta;
  grid_ = std::make_unique<PointGrid>(points_, members, beta, o_.seed);
  cell_stamp_.assign(grid_->cell_count(), 0);
  Vec3 lo = points_[members[0]], hi = lo;
  for (auto i : members) {
    lo = lo.cwiseMin(points_[i]);
    hi = hi.cwiseMax(points_[i]);
  }
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
  if (!(options.epsilon > 0.0) || !std::isfinite(options.epsilon)) {
    return kernel::Error{ErrorCode::InvalidArgument, "fit option epsilon must be > 0"};
  }
  if (!(options.normal_deviation_deg > 0.0 && options.normal_deviation_deg < 90.0)) {
    return kernel::Error{ErrorCode::InvalidArgument,
                         "fit option normal_deviation_deg must be in (0, 90)"};
  }
  if (!(options.cluster_epsilon >= 0.0) || !std::isfinite(options.cluster_epsilon)) {
    return kernel::Error{ErrorCode::InvalidArgument, "fit option cluster_epsilon must be >= 0"};
  }
  if (options.min_points < 3) {
    return kernel::Error{ErrorCode::InvalidArgument, "fit option min_points must be >= 3"};
  }
  if (!(options.probability > 0.0 && options.probability < 1.0)) {
    return kernel::Error{ErrorCode::InvalidArgument, "fit option probability must be in (0, 1)"};
  }
  if (!(options.max_radius > 0.0)) {
    return kernel::Error{ErrorCode::InvalidArgument, "fit option max_radius must be > 0"};
  }
  Detector detector(points, normals, options);
  return detector.run();
}

}  // namespace csgtile::fit
