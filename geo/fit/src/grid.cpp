// The spatial grid of the RANSAC, the spacing estimate, and the ground grid's queries.

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>

#include <Eigen/Eigenvalues>
#include <Eigen/QR>

#include "fit_internal.h"

namespace csgtile::fit::detail {

namespace {

constexpr std::int64_t kBias = std::int64_t{1} << 20;  // 21 bits per coordinate

std::uint64_t pack(std::int64_t x, std::int64_t y, std::int64_t z) {
  const auto c = [](std::int64_t v) {
    return static_cast<std::uint64_t>(std::clamp<std::int64_t>(v + kBias, 0, 2 * kBias - 1));
  };
  return (c(x) << 42) | (c(y) << 21) | c(z);
}

// A well-mixed 64-bit hash (splitmix64's finaliser): shuffles points inside a cell.
std::uint64_t mix(std::uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

}  // namespace

PointGrid::PointGrid(std::span<const Vec3> points, std::span<const std::uint32_t> members,
                     double cell, std::uint64_t seed)
    : cell_(cell), cell_of_(points.size(), -1) {
  struct Entry {
    std::uint64_t key;
    std::uint64_t shuffle;
    std::uint32_t index;
  };
  std::vector<Entry> entries;
  entries.reserve(members.size());
  for (auto i : members) {
    const Vec3& p = points[i];
    const std::int64_t x = cell_index(p.x(), cell);
    const std::int64_t y = cell_index(p.y(), cell);
    const std::int64_t z = cell_index(p.z(), cell);
    entries.push_back({pack(x, y, z), mix(seed ^ (std::uint64_t{i} * 0x100000001b3ULL)), i});
  }
  std::sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) {
    if (a.key != b.key) return a.key < b.key;
    if (a.shuffle != b.shuffle) return a.shuffle < b.shuffle;
    return a.index < b.index;
  });
  order_.reserve(entries.size());
  begin_.push_back(0);
  for (std::size_t k = 0; k < entries.size(); ++k) {
    if (k > 0 && entries[k].key != entries[k - 1].key)
      begin_.push_back(static_cast<std::uint32_t>(k));
    if (k == 0 || entries[k].key != entries[k - 1].key) {
      const std::uint64_t key = entries[k].key;
      const auto mask = static_cast<std::uint64_t>(2 * kBias - 1);
      coords_.push_back({static_cast<std::int64_t>((key >> 42) & mask) - kBias,
                         static_cast<std::int64_t>((key >> 21) & mask) - kBias,
                         static_cast<std::int64_t>(key & mask) - kBias});
      lookup_.emplace(key, static_cast<int>(coords_.size() - 1));
    }
    order_.push_back(entries[k].index);
    cell_of_[entries[k].index] = static_cast<int>(coords_.size() - 1);
  }
  begin_.push_back(static_cast<std::uint32_t>(entries.size()));
  if (entries.empty()) begin_ = {0};
}

int PointGrid::find(std::int64_t x, std::int64_t y, std::int64_t z) const {
  if (std::abs(x) >= kBias || std::abs(y) >= kBias || std::abs(z) >= kBias) return -1;
  const auto it = lookup_.find(pack(x, y, z));
  return it == lookup_.end() ? -1 : it->second;
}

namespace {

// Distances to the k-th neighbour over a deterministic sample of the members (at least half of
// the sample; empty when the points are too few or all duplicates).
constexpr std::size_t kNeighbours = 16;

// The noise of a neighbourhood: its points' RMS distance to their least-squares plane; but
// where they lie on two sheets (both sides of a plate or a wall thinner than the
// neighbourhood), that plane runs between the sheets and the RMS is half their separation,
// not noise. Two sheets are found as the best split of the points into two levels along the
// plane's normal (1-D two-means, each side three points or more), the normal then taken again
// from the two sides' pooled spread about their own centres (the sheets' common direction,
// which a lopsided sample tilts the first plane away from), and split again. They are two
// when their levels lie more than four times their own spread apart (one noisy sheet: under
// three times) and at least `min_gap` apart; the noise is then that spread. Sheets closer than
// `min_gap` are one surface seen twice (overlapping flight strips, a registration offset),
// whose offset is noise to any model of it.
template <std::size_t N>
double sheet_residual(std::span<const Vec3> points, const std::array<std::uint32_t, N>& hood,
                      const Vec3& centre, Vec3 normal, double min_gap) {
  std::array<double, N> d{};
  auto levels = [&](const Vec3& n) {
    for (std::size_t h = 0; h < N; ++h) d[h] = (points[hood[h]] - centre).dot(n);
  };
  levels(normal);
  double sum = 0.0;
  for (double v : d) sum += v * v;
  const double rms = std::sqrt(sum / static_cast<double>(N));
  // The best split into levels below and above a threshold: `within` (RMS about each side's
  // mean), the gap between the means and the threshold.
  struct Split {
    double within = INFINITY, gap = 0.0, at = 0.0;
  };
  auto split = [&]() {
    std::array<double, N> sorted = d;
    std::sort(sorted.begin(), sorted.end());
    Split best;
    double low = 0.0, low2 = 0.0, all = 0.0, all2 = 0.0;
    for (double v : sorted) {
      all += v;
      all2 += v * v;
    }
    for (std::size_t k = 0; k + 1 < N; ++k) {
      low += sorted[k];
      low2 += sorted[k] * sorted[k];
      const auto a = static_cast<double>(k + 1), b = static_cast<double>(N - k - 1);
      if (k + 1 < 3 || N - k - 1 < 3) continue;
      const double ma = low / a, mb = (all - low) / b;
      const double ss = (low2 - a * ma * ma) + ((all2 - low2) - b * mb * mb);
      if (ss < best.within) best = {ss, mb - ma, 0.5 * (sorted[k] + sorted[k + 1])};
    }
    best.within = std::sqrt(std::max(best.within, 0.0) / static_cast<double>(N));
    return best;
  };
  Split s = split();
  if (!std::isfinite(s.within)) return rms;
  // The sheets' own normal: the least direction of the pooled spread about each side's centre.
  Vec3 mean[2] = {Vec3::Zero(), Vec3::Zero()};
  double count[2] = {0.0, 0.0};
  for (std::size_t h = 0; h < N; ++h) {
    const int side = d[h] > s.at;
    mean[side] += points[hood[h]];
    count[side] += 1.0;
  }
  mean[0] /= count[0];
  mean[1] /= count[1];
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (std::size_t h = 0; h < N; ++h) {
    const Vec3 q = points[hood[h]] - mean[d[h] > s.at];
    cov += q * q.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  const Vec3 n = eig.eigenvectors().col(0);
  if (n.allFinite() && n.norm() > 0.5) {
    normal = n.normalized();
    levels(normal);
    s = split();
    if (!std::isfinite(s.within)) return rms;
  }
  return s.gap > 4.0 * s.within && s.gap >= min_gap ? std::min(s.within, rms) : rms;
}

// The RMS distance of a neighbourhood from the quadric height field over its plane (w = a u² +
// b uv + c v² + d u + e v + f in the plane's frame), scaled by √(N / (N - 6)) for the
// parameters fitted: the noise of exact points on a curved surface is nil, where the plane's
// residual is the surface's bending across the neighbourhood. NaN when the neighbourhood spans
// too little of its plane to fit the quadric.
template <std::size_t N>
double quadric_residual(std::span<const Vec3> points, const std::array<std::uint32_t, N>& hood,
                        const Vec3& centre, const Vec3& normal) {
  static_assert(N > 6);
  Vec3 e1, e2;
  orthonormal_basis(normal, e1, e2);
  Eigen::Matrix<double, N, 6> a;
  Eigen::Matrix<double, N, 1> w;
  for (std::size_t h = 0; h < N; ++h) {
    const Vec3 q = points[hood[h]] - centre;
    const double u = q.dot(e1), v = q.dot(e2);
    const auto r = static_cast<Eigen::Index>(h);
    a.row(r) << u * u, u * v, v * v, u, v, 1.0;
    w(r) = q.dot(normal);
  }
  const Eigen::ColPivHouseholderQR<Eigen::Matrix<double, N, 6>> qr(a);
  if (qr.rank() < 6) return std::numeric_limits<double>::quiet_NaN();
  const Eigen::Matrix<double, 6, 1> theta = qr.solve(w);
  const double sum = (a * theta - w).squaredNorm();
  return std::sqrt(sum / static_cast<double>(N - 6));
}

// With `residuals`: also, per sampled point found, the noise of its neighbourhood (the point
// and its 16 nearest, sheet_residual) — the scan's noise where the surface is flat, more on
// curved parts and edges.
std::vector<double> kth_neighbour_distances(std::span<const Vec3> points,
                                            std::span<const std::uint32_t> members,
                                            std::vector<double>* residuals = nullptr,
                                            std::vector<double>* curved = nullptr) {
  if (members.size() <= kNeighbours) return {};
  Vec3 lo = points[members[0]], hi = lo;
  for (auto i : members) {
    lo = lo.cwiseMin(points[i]);
    hi = hi.cwiseMax(points[i]);
  }
  // Start from the spacing of points spread over a surface filling the bounding box.
  double cell = std::max((hi - lo).norm() / std::sqrt(static_cast<double>(members.size())), 1e-6);
  const std::size_t samples = std::min<std::size_t>(members.size(), 2000);
  const std::size_t stride = members.size() / samples;
  for (int attempt = 0; attempt < 16; ++attempt) {
    const PointGrid grid(points, members, cell, 0);
    std::vector<double> found;
    if (residuals != nullptr) residuals->clear();
    if (curved != nullptr) curved->clear();
    std::array<double, kNeighbours> best{};
    std::array<std::uint32_t, kNeighbours> who{};
    std::size_t missed = 0;  // samples whose k-th neighbour lies beyond the cell
    for (std::size_t k = 0; k < samples; ++k) {
      // An attempt that can no longer find half of its samples is given up at once: the
      // next cell, twice as wide, is tried as it would be after the last sample.
      if (2 * missed > samples) break;
      const std::uint32_t i = members[k * stride];
      const auto& c = grid.coords(grid.cell_of(i));
      best.fill(INFINITY);
      who.fill(i);
      for (int dx = -1; dx <= 1; ++dx) {
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dz = -1; dz <= 1; ++dz) {
            const int cc = grid.find(c[0] + dx, c[1] + dy, c[2] + dz);
            if (cc < 0) continue;
            for (auto j : grid.points(cc)) {
              if (j == i) continue;
              // Squared: the square root only for the neighbours kept (the same order).
              const double d = (points[j] - points[i]).squaredNorm();
              if (!(d > 0.0) || d >= best.back()) continue;
              // Insertion keeps the distances sorted and the indices beside them.
              std::size_t at = kNeighbours - 1;
              while (at > 0 && best[at - 1] > d) {
                best[at] = best[at - 1];
                who[at] = who[at - 1];
                --at;
              }
              best[at] = d;
              who[at] = j;
            }
          }
        }
      }
      for (double& b : best) b = std::sqrt(b);
      if (!(best.back() <= cell)) {
        ++missed;
      } else {
        found.push_back(best.back());
        if (residuals != nullptr) {
          std::array<std::uint32_t, kNeighbours + 1> hood{};
          hood[0] = i;
          std::copy(who.begin(), who.end(), hood.begin() + 1);
          // A neighbourhood that spans no plane (collinear) says nothing of the noise.
          if (const auto plane = fit_plane(points, hood)) {
            residuals->push_back(
                sheet_residual(points, hood, plane->point, plane->axis, best.back() / 8.0));
            if (curved != nullptr) {
              const double r = quadric_residual(points, hood, plane->point, plane->axis);
              if (std::isfinite(r)) curved->push_back(r);
            }
          }
        }
      }
    }
    if (found.size() * 2 >= samples) return found;
    cell *= 2.0;
  }
  return {};
}

double quantile_of(std::vector<double> values, double quantile) {
  if (values.empty()) return 0.0;
  const auto k = std::min(values.size() - 1,
                          static_cast<std::size_t>(quantile * static_cast<double>(values.size())));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

}  // namespace

NeighbourSample::NeighbourSample(std::span<const Vec3> points,
                                 std::span<const std::uint32_t> members, bool with_noise,
                                 bool with_curved) {
  distances_ = kth_neighbour_distances(points, members, with_noise ? &residuals_ : nullptr,
                                       with_noise && with_curved ? &curved_ : nullptr);
}

double NeighbourSample::spacing(double quantile) const {
  // Density spacing 1/sqrt(points per unit area) = r_k·sqrt(π/k).
  return quantile_of(distances_, quantile) *
         std::sqrt(std::numbers::pi / static_cast<double>(kNeighbours));
}

double NeighbourSample::reach(double quantile) const { return quantile_of(distances_, quantile); }

double NeighbourSample::noise(double quantile) const { return quantile_of(residuals_, quantile); }

double NeighbourSample::curved_noise(double quantile) const {
  return quantile_of(curved_, quantile);
}

double estimate_spacing(std::span<const Vec3> points, std::span<const std::uint32_t> members,
                        double quantile) {
  return NeighbourSample(points, members, false).spacing(quantile);
}

double neighbour_reach(std::span<const Vec3> points, std::span<const std::uint32_t> members,
                       double quantile) {
  return NeighbourSample(points, members, false).reach(quantile);
}

double estimate_noise(std::span<const Vec3> points, std::span<const std::uint32_t> members,
                      double quantile) {
  // The plane residuals only: the quadric fits behind curved_noise are a RANSAC's question.
  std::vector<double> residuals;
  kth_neighbour_distances(points, members, &residuals, nullptr);
  return quantile_of(std::move(residuals), quantile);
}

}  // namespace csgtile::fit::detail

namespace csgtile::fit {

double GroundGrid::lowest_near(double x, double y, double radius) const {
  if (nx <= 0 || ny <= 0 || !(cell > 0.0)) return NAN;
  if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(radius)) return NAN;
  // Clamped in double before the conversion: a far or huge coordinate stays in range.
  const auto clamp_x = [&](double v) {
    return static_cast<int>(
        std::clamp(std::floor((v - x0) / cell), 0.0, static_cast<double>(nx - 1)));
  };
  const auto clamp_y = [&](double v) {
    return static_cast<int>(
        std::clamp(std::floor((v - y0) / cell), 0.0, static_cast<double>(ny - 1)));
  };
  double best = NAN;
  for (int j = clamp_y(y - radius); j <= clamp_y(y + radius); ++j) {
    for (int i = clamp_x(x - radius); i <= clamp_x(x + radius); ++i) {
      const double h = z[static_cast<std::size_t>(j) * static_cast<std::size_t>(nx) +
                         static_cast<std::size_t>(i)];
      if (std::isfinite(h) && !(h >= best)) best = h;
    }
  }
  return best;
}

double GroundGrid::median_near(double x, double y, double radius) const {
  if (nx <= 0 || ny <= 0 || !(cell > 0.0)) return NAN;
  const std::vector<double>& level = mean.size() == z.size() ? mean : z;
  if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(radius)) return NAN;
  // Clamped in double before the conversion: a far or huge coordinate stays in range.
  const auto clamp_x = [&](double v) {
    return static_cast<int>(
        std::clamp(std::floor((v - x0) / cell), 0.0, static_cast<double>(nx - 1)));
  };
  const auto clamp_y = [&](double v) {
    return static_cast<int>(
        std::clamp(std::floor((v - y0) / cell), 0.0, static_cast<double>(ny - 1)));
  };
  std::vector<double> found;
  for (int j = clamp_y(y - radius); j <= clamp_y(y + radius); ++j) {
    for (int i = clamp_x(x - radius); i <= clamp_x(x + radius); ++i) {
      const double h = level[static_cast<std::size_t>(j) * static_cast<std::size_t>(nx) +
                             static_cast<std::size_t>(i)];
      if (std::isfinite(h)) found.push_back(h);
    }
  }
  if (found.empty()) return NAN;
  const auto mid = found.begin() + static_cast<std::ptrdiff_t>(found.size() / 2);
  std::nth_element(found.begin(), mid, found.end());
  return *mid;
}

}  // namespace csgtile::fit
