// The RANSAC's detector (ransac.cpp: the search, extraction and labelling; ransac_evidence.cpp:
// the choice of a shape's type by the evidence of its points). Internal to the fit target.

#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <queue>
#include <span>
#include <utility>
#include <vector>

#include "fit_internal.h"
#include "residuals.h"
#include "synth/random.h"

namespace csgtile::fit::detail {

constexpr int kSampledPerCell = 4;
// A twentieth of epsilon: the residual floor of exact points (see Detector::noise_floor).
constexpr double kFloorShare = 0.05;
// On exact clouds, the RMS of a surface fitted to its own points (a shape's best half, a
// merged pair) within which they are exact: a hundredth of the noise floor.
constexpr double kExactShare = 0.01;
constexpr double kSampleFactor = 4.0;
// On exact clouds, a point within this many noise floors of a surface lies on it (the second
// search's freeing, edges_to_smaller's points on both surfaces, the leftovers' shapes).
constexpr double kOnSurfaceFloors = 3.0;

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
  std::optional<Surface> exact_core(const Surface& s, std::span<const std::uint32_t> inliers);
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
    return detail::surface_rms(s, points_, inliers);
  }
  // The inliers' absolute distances to the surface, in their order.
  std::vector<double> residuals(const Surface& s, std::span<const std::uint32_t> inliers) const {
    std::vector<double> r;
    r.reserve(inliers.size());
    for (auto i : inliers) r.push_back(std::abs(surface_distance(s, points_[i])));
    return r;
  }
  // Whether the median of the inliers' residuals is within the noise floor.
  bool fits_exactly(const Surface& s, std::span<const std::uint32_t> inliers) const {
    return inliers.empty() || detail::median_of(residuals(s, inliers)) <= noise_floor();
  }
  // On exact clouds, whether a surface fitting its own points with RMS `rms` fits them exactly,
  // and how far from it a point still lies on it: ten times that RMS.
  bool exact_fit(double rms) const { return rms <= kExactShare * noise_floor(); }
  double exact_reach(double rms) const { return std::max(10.0 * rms, kExactShare * noise_floor()); }
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
  bool search();
  void relabel();
  std::size_t free_inexact();
  // A surface fitted to the half of some inliers it fits best, and its RMS on that half.
  struct Core {
    Surface surface;
    double rms = 0.0;
  };
  std::optional<Core> best_half(std::span<const std::uint32_t> inliers,
                                const Surface* start = nullptr) const;
  // The best half of a shape's inliers (a plane's a plane, a curved shape its own type refined)
  // when it fits its surface exactly (exact_fit), else nullopt.
  std::optional<Core> exact_half(const DetectedShape& shape) const;
  void best_fitting_half(const Surface& s, std::span<const std::uint32_t> inliers,
                         std::vector<std::uint32_t>& half) const;
  std::optional<Surface> on_one_circle(const Vec3& axis,
                                       std::span<const std::uint32_t> inliers) const;
  bool retype();
  std::pair<Vec3, Vec3> bounds(std::span<const std::uint32_t> members) const;
  void derive_scale(std::span<const std::uint32_t> members, const NeighbourSample& sample,
                    RansacResult& result);
  void give_edges_to_smaller();
  void adopt_free();
  // ransac_leftovers.cpp
  std::size_t trim_to_exact_cores();
  std::size_t fit_leftovers();
  std::size_t small_exact_shapes(std::span<const std::uint32_t> group,
                                 const std::vector<Vec3>& axes);
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
  std::uint64_t searched_ = 0;  // draws of the searches before the present one
  std::uint64_t extractions_ = 0;
  std::vector<DetectedShape> shapes_;
};

}  // namespace csgtile::fit::detail
