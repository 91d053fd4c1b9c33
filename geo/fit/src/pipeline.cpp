// The ground filter and the fit pipeline: ground → outliers → voxels → normals → clusters →
// (grown regions →) per region RANSAC and primitives.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <optional>

#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>
#include <tbb/task_arena.h>

#include "column_ends.h"
#include "csgtile/fit/segment.h"
#include "fit_internal.h"
#include "house_overlaps.h"

namespace csgtile::fit {

namespace {

using kernel::Vec2;
using kernel::Vec3;

// Sliding minimum (or maximum) of a row of values over a window of 2·half + 1, ignoring
// infinities that mark empty cells (an all-empty window gives the empty mark back), in O(n)
// whatever the window (van Herk / Gil–Werman: the running extreme from each block's start
// and from its end, blocks of the window's width). `v`, `from_start`, `from_end`: scratch
// rows, kept by the caller across rows.
struct SlidingScratch {
  std::vector<double> v, from_start, from_end;
};
void sliding(std::vector<double>& row, int half, bool minimum, SlidingScratch& scratch) {
  const int n = static_cast<int>(row.size());
  if (n == 0) return;
  const double none = minimum ? INFINITY : -INFINITY;
  auto pick = [minimum](double a, double b) { return minimum ? std::min(a, b) : std::max(a, b); };
  const int w = 2 * half + 1;
  const int m = n + 2 * half;  // padded with `none` on both sides
  const int padded = ((m + w - 1) / w) * w;
  std::vector<double>& v = scratch.v;
  std::vector<double>& from_start = scratch.from_start;
  std::vector<double>& from_end = scratch.from_end;
  v.assign(static_cast<std::size_t>(padded), none);
  from_start.resize(v.size());
  from_end.resize(v.size());
  for (int i = 0; i < n; ++i) {
    const double x = row[static_cast<std::size_t>(i)];
    v[static_cast<std::size_t>(i + half)] = std::isfinite(x) ? x : none;
  }
  for (int b = 0; b < padded; b += w) {
    from_start[static_cast<std::size_t>(b)] = v[static_cast<std::size_t>(b)];
    for (int i = b + 1; i < b + w; ++i)
      from_start[static_cast<std::size_t>(i)] =
          pick(from_start[static_cast<std::size_t>(i - 1)], v[static_cast<std::size_t>(i)]);
    from_end[static_cast<std::size_t>(b + w - 1)] = v[static_cast<std::size_t>(b + w - 1)];
    for (int i = b + w - 2; i >= b; --i)
      from_end[static_cast<std::size_t>(i)] =
          pick(from_end[static_cast<std::size_t>(i + 1)], v[static_cast<std::size_t>(i)]);
  }
  for (int i = 0; i < n; ++i) {
    // The window over padded [i, i + w - 1]: the end of one block and the start of the next.
    const double x = pick(from_end[static_cast<std::size_t>(i)],
                          from_start[static_cast<std::size_t>(i + w - 1)]);
    row[static_cast<std::size_t>(i)] = std::isfinite(x) ? x : INFINITY;
  }
}

// Separable filter of a grid (nx × ny, row-major by y).
void filter2d(std::vector<double>& grid, int nx, int ny, int half, bool minimum) {
  std::vector<double> row;
  SlidingScratch scratch;
  for (int y = 0; y < ny; ++y) {
    row.assign(grid.begin() + static_cast<std::ptrdiff_t>(y) * nx,
               grid.begin() + static_cast<std::ptrdiff_t>(y + 1) * nx);
    sliding(row, half, minimum, scratch);
    std::copy(row.begin(), row.end(), grid.begin() + static_cast<std::ptrdiff_t>(y) * nx);
  }
  for (int x = 0; x < nx; ++x) {
    row.resize(static_cast<std::size_t>(ny));
    for (int y = 0; y < ny; ++y)
      row[static_cast<std::size_t>(y)] =
          grid[static_cast<std::size_t>(y) * static_cast<std::size_t>(nx) +
               static_cast<std::size_t>(x)];
    sliding(row, half, minimum, scratch);
    for (int y = 0; y < ny; ++y)
      grid[static_cast<std::size_t>(y) * static_cast<std::size_t>(nx) +
           static_cast<std::size_t>(x)] = row[static_cast<std::size_t>(y)];
  }
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

std::vector<char> ground_mask(std::span<const Vec3> points, std::span<const std::uint8_t> classes,
                              const GroundOptions& options) {
  std::vector<char> mask(points.size(), 0);
  if (!options.enabled || points.empty()) return mask;
  // A cloud classified for its ground alone (classes 0-2) may have left ground unclassified
  // (a flight line or a stretch the classifier did not reach): its class 2 and what the
  // filter below takes for ground among every point.
  std::vector<char> classified_ground;
  if (options.use_classification && classes.size() == points.size()) {
    bool any = false, others = false;
    for (std::size_t i = 0; i < points.size(); ++i) {
      mask[i] = classes[i] == 2 ? 1 : 0;
      any = any || mask[i] != 0;
      others = others || classes[i] > 2;
    }
    if (any && others) return mask;
    if (any) classified_ground = mask;
  }
  // Progressive morphological filter (Zhang et al. 2003): the grid of the lowest ground
  // points opened by squares of 3, 5, 9, 17 … cells up to `window`. At each step a point more
  // than the step's threshold above the opened surface stops being ground: `height` at the
  // first, then growing by `slope` times the window's growth (terrain rising no steeper than
  // that keeps its points; an opening keeps planar slopes anyway, it cuts hilltops and
  // structures) up to `max_height`. Small objects go at the small windows, a building at the
  // first window wider than it, whatever its size below `window`.
  double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
  for (const auto& p : points) {
    if (!p.allFinite()) continue;
    x0 = std::min(x0, p.x());
    y0 = std::min(y0, p.y());
    x1 = std::max(x1, p.x());
    y1 = std::max(y1, p.y());
  }
  if (!(x0 <= x1)) return mask;
  const double cell = options.cell;
  const double cells_x = std::floor((x1 - x0) / cell) + 1;
  const double cells_y = std::floor((y1 - y0) / cell) + 1;
  if (cells_x * cells_y > 5e7) return mask;  // a grid that large means a wrong cell size
  const int nx = static_cast<int>(cells_x), ny = static_cast<int>(cells_y);
  // Each finite point's cell, once for every step.
  std::vector<std::size_t> cell_of(points.size(), 0);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Vec3& p = points[i];
    if (!p.allFinite()) continue;
    mask[i] = 1;
    const int x = std::min(nx - 1, static_cast<int>((p.x() - x0) / cell));
    const int y = std::min(ny - 1, static_cast<int>((p.y() - y0) / cell));
    cell_of[i] =
        static_cast<std::size_t>(y) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(x);
  }
  const int widest = std::max(
      3, static_cast<int>(std::min(std::ceil(options.window / cell), 2.0 * (nx + ny))) | 1);
  std::vector<double> surface(static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny));
  int previous = 1;
  for (int width = 3;; width = std::min(2 * width - 1, widest)) {
    std::fill(surface.begin(), surface.end(), INFINITY);
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (mask[i]) surface[cell_of[i]] = std::min(surface[cell_of[i]], points[i].z());
    }
    const int half = width / 2;
    filter2d(surface, nx, ny, half, true);
    filter2d(surface, nx, ny, half, false);
    const double threshold =
        previous == 1 ? options.height
                      : std::min(options.height + options.slope * (width - previous) * cell,
                                 std::max(options.height, options.max_height));
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (!mask[i]) continue;
      const double g = surface[cell_of[i]];
      if (std::isfinite(g) && points[i].z() - g > threshold) mask[i] = 0;
    }
    if (width >= widest) break;
    previous = width;
  }
  for (std::size_t i = 0; i < classified_ground.size(); ++i) {
    mask[i] = static_cast<char>(mask[i] != 0 || classified_ground[i] != 0);
  }
  return mask;
}

kernel::Result<FitOutput> fit_point_cloud(std::span<const Vec3> points,
                                          std::span<const std::uint8_t> classes,
                                          const FitPipelineOptions& options,
                                          std::span<const geo::Footprint> footprints,
                                          std::span<const std::uint8_t> returns,
                                          const TileShare* share) {
  using kernel::ErrorCode;
  auto bad = [](const std::string& what) {
    return kernel::Error{ErrorCode::InvalidArgument, "fit option " + what};
  };
  if (!classes.empty() && classes.size() != points.size())
    return bad("classes: size differs from points");
  if (!returns.empty() && returns.size() != points.size())
    return bad("returns: size differs from points");
  if (share != nullptr &&
      (share->foreign.size() != points.size() || share->footprints.size() != footprints.size())) {
    return bad("tile share: size differs from the points or the footprints");
  }
  if (options.outliers.neighbours < 2) return bad("outliers.neighbours must be >= 2");
  if (!(options.outliers.std_ratio > 0.0)) return bad("outliers.std_ratio must be > 0");
  if (!(options.voxel.size >= 0.0) || !std::isfinite(options.voxel.size))
    return bad("voxel.size must be >= 0");
  if (options.normals.neighbours < 3) return bad("normals.neighbours must be >= 3");
  if (!(options.ground.cell > 0.0) || !(options.ground.window > 0.0) ||
      !(options.ground.height >= 0.0) || !(options.ground.slope >= 0.0) ||
      !(options.ground.max_height >= 0.0)) {
    return bad(
        "ground.cell and ground.window must be > 0, ground.height, ground.slope and "
        "ground.max_height >= 0");
  }
  if (!(options.clusters.tolerance >= 0.0)) return bad("clusters.tolerance must be >= 0");
  if (options.regions.enabled) {
    if (options.regions.neighbours < 3) return bad("regions.neighbours must be >= 3");
    if (!(options.regions.smoothness_deg > 0.0) || !(options.regions.smoothness_deg <= 180.0))
      return bad("regions.smoothness_deg must be in (0, 180]");
    if (!(options.regions.curvature > 0.0)) return bad("regions.curvature must be > 0");
    if (options.regions.min_points < 1) return bad("regions.min_points must be >= 1");
  }

  FitOutput out;
  out.input_points = static_cast<long long>(points.size());
  auto start = std::chrono::steady_clock::now();

  const auto ground = ground_mask(points, classes, options.ground);
  // The points above the ground, by input index (not copied: they are nearly all of them).
  std::vector<std::uint32_t> above_index;
  above_index.reserve(points.size());
  // Terrain heights (lowest ground point per cell) for roofs seen from the air.
  GroundGrid terrain;
  {
    double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (!ground[i] || !points[i].allFinite()) continue;
      x0 = std::min(x0, points[i].x());
      y0 = std::min(y0, points[i].y());
      x1 = std::max(x1, points[i].x());
      y1 = std::max(y1, points[i].y());
    }
    terrain.cell = 2.0 * options.ground.cell;
    const double cells_x = (x1 - x0) / terrain.cell + 1.0, cells_y = (y1 - y0) / terrain.cell + 1.0;
    if (x0 <= x1 && cells_x * cells_y < 5e7) {
      terrain.x0 = x0;
      terrain.y0 = y0;
      terrain.nx = static_cast<int>((x1 - x0) / terrain.cell) + 1;
      terrain.ny = static_cast<int>((y1 - y0) / terrain.cell) + 1;
      terrain.z.assign(static_cast<std::size_t>(terrain.nx) * static_cast<std::size_t>(terrain.ny),
                       NAN);
      terrain.mean.assign(terrain.z.size(), 0.0);
    }
  }
  std::vector<std::uint32_t> terrain_count(terrain.z.size(), 0);
  // Only inputs that carry a classification are filtered (a LAS whose points are all class 0
  // or 1, never classified or unclassified, keeps every point, as with no classes at all): by
  // `keep` when some point carries a kept class, else by `drop`.
  const auto listed = [](const std::vector<std::uint8_t>& list, std::uint8_t c) {
    return std::find(list.begin(), list.end(), c) != list.end();
  };
  // Among neighbours, from this tile's own points (a neighbour classified otherwise does not
  // change how this tile's points are read).
  auto own = [&](std::size_t i) { return share == nullptr || share->foreign[i] == 0; };
  bool classified = false, by_keep = false, vegetation_classed = false;
  if (classes.size() == points.size()) {
    for (std::size_t i = 0; i < classes.size(); ++i) {
      if (!own(i)) continue;
      classified = classified || classes[i] > 1;
      by_keep = by_keep || listed(options.classes.keep, classes[i]);
      vegetation_classed = vegetation_classed || (classes[i] >= 3 && classes[i] <= 5);
    }
    by_keep = by_keep && classified;
  }
  // Vegetation is found from the points where the classes do not tell it: unclassified
  // inputs, and tiles classified for their ground only (ground 2, the rest unclassified 1: no
  // kept class such as buildings, no vegetation class 3-5).
  const bool find_vegetation = !classified || (!by_keep && !vegetation_classed);
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite()) continue;
    if (!ground[i] && classified &&
        (by_keep ? !listed(options.classes.keep, classes[i])
                 : listed(options.classes.drop, classes[i]))) {
      ++out.other_class_points;
      continue;
    }
    if (ground[i]) {
      ++out.ground_points;
      if (terrain.nx > 0) {
        const auto x = static_cast<std::size_t>((points[i].x() - terrain.x0) / terrain.cell);
        const auto y = static_cast<std::size_t>((points[i].y() - terrain.y0) / terrain.cell);
        const std::size_t c = y * static_cast<std::size_t>(terrain.nx) + x;
        double& h = terrain.z[c];
        if (!(h <= points[i].z())) h = points[i].z();
        terrain.mean[c] += points[i].z();
        ++terrain_count[c];
      }
    } else {
      above_index.push_back(static_cast<std::uint32_t>(i));
    }
  }
  for (std::size_t c = 0; c < terrain.mean.size(); ++c) {
    terrain.mean[c] = terrain_count[c] > 0 ? terrain.mean[c] / terrain_count[c] : NAN;
  }
  PrimitiveOptions primitive_options = options.primitives;
  // Blocks are buildings' (LoD1.2 of what no surface explains): only where the points are
  // known to be buildings' — a tile classified with a kept class — never trees'.
  primitive_options.blocks = options.primitives.blocks && by_keep;
  if (primitive_options.ground == nullptr && terrain.nx > 0) primitive_options.ground = &terrain;
  out.seconds.emplace_back("ground", seconds_since(start));

  if (options.interrupt.fired()) return options.interrupt.error("before the fit's outliers stage");
  start = std::chrono::steady_clock::now();
  std::vector<Vec3> clean;
  std::vector<std::uint32_t> clean_index;  // input index of each point of `clean`
  {
    const auto kept = remove_statistical_outliers(points, above_index, options.outliers);
    clean.reserve(kept.size());
    clean_index.reserve(kept.size());
    for (auto k : kept) {
      clean.push_back(points[above_index[k]]);
      clean_index.push_back(above_index[k]);
    }
    out.outlier_points = static_cast<long long>(above_index.size() - kept.size());
  }
  std::vector<std::uint32_t>().swap(above_index);
  out.seconds.emplace_back("outliers", seconds_since(start));

  start = std::chrono::steady_clock::now();
  // Without downsampling the fitted cloud is the cleaned one itself (voxel_downsample would
  // copy it: its points are finite and within PCL's range already), not a second copy of
  // nearly the whole input.
  std::vector<Vec3> downsampled;
  if (options.voxel.size > 0.0) downsampled = voxel_downsample(clean, options.voxel);
  const std::vector<Vec3>& cloud = options.voxel.size > 0.0 ? downsampled : clean;
  out.fitted_points = static_cast<long long>(cloud.size());
  // Each fitted point's input point: its own (no downsampling), else the nearest cleaned
  // point's (-1: none); found once, when first asked.
  std::optional<std::vector<std::int64_t>> cloud_input;
  auto input_of = [&]() -> const std::vector<std::int64_t>& {
    if (!cloud_input) {
      const bool same = !(options.voxel.size > 0.0) && cloud.size() == clean.size();
      const std::vector<std::int32_t> nearest =
          same ? std::vector<std::int32_t>{} : detail::nearest_of(cloud, clean);
      cloud_input.emplace(cloud.size(), -1);
      for (std::size_t k = 0; k < cloud.size(); ++k) {
        const std::int32_t c = same ? static_cast<std::int32_t>(k) : nearest[k];
        if (c >= 0) (*cloud_input)[k] = clean_index[static_cast<std::size_t>(c)];
      }
    }
    return *cloud_input;
  };
  // A neighbour's point of the fitted cloud.
  std::vector<std::uint8_t> foreign;
  if (share != nullptr) {
    for (std::uint8_t f : share->foreign) out.neighbour_points += f ? 1 : 0;
    foreign.assign(cloud.size(), 0);
    for (std::size_t k = 0; k < cloud.size(); ++k) {
      if (const std::int64_t i = input_of()[k]; i >= 0) {
        foreign[k] = share->foreign[static_cast<std::size_t>(i)];
      }
    }
  }
  out.seconds.emplace_back("voxels", seconds_since(start));

  if (options.interrupt.fired()) return options.interrupt.error("before the fit's normals stage");
  start = std::chrono::steady_clock::now();
  std::vector<Vec3> normals;
  std::vector<double> curvature;
  detail::normals_and_curvature(cloud, options.normals.neighbours, normals, curvature,
                                options.normals.sharp);
  out.seconds.emplace_back("normals", seconds_since(start));

  // Vegetation (where the classes do not tell it): excluded from the regions.
  std::vector<char> excluded(cloud.size(), 0);
  if (options.vegetation.enabled && find_vegetation && !cloud.empty()) {
    start = std::chrono::steady_clock::now();
    // Each fitted point's pulse: its input point's.
    std::vector<char> several(cloud.size(), 0);
    if (!returns.empty()) {
      for (std::size_t k = 0; k < cloud.size(); ++k) {
        if (const std::int64_t i = input_of()[k]; i >= 0) {
          several[k] = returns[static_cast<std::size_t>(i)] > 1 ? 1 : 0;
        }
      }
    }
    excluded = detail::vegetation_mask(cloud, curvature, several, options.vegetation);
    for (char e : excluded) out.vegetation_points += e ? 1 : 0;
    out.seconds.emplace_back("vegetation", seconds_since(start));
  }

  if (options.interrupt.fired()) return options.interrupt.error("before the fit's clusters stage");
  start = std::chrono::steady_clock::now();
  // Footprints first: each one's points are a region; the points of none are clustered.
  std::vector<std::vector<std::uint32_t>> clusters;
  std::vector<int> region_footprint;  // per region: its footprint, -1 for a cluster
  // Per region: 1 when it is a building fitted in parts by neighbouring tiles (ShareKind::
  // own_points): its parts fuse across the seam only as one building, so it is not split into
  // houses.
  std::vector<char> region_in_parts;
  std::vector<geo::Footprint> straight_footprints;  // the footprints used (outlives the fit)
  if (!footprints.empty()) {
    // Walls digitised with nearly collinear vertices are made straight (within 1 cm).
    straight_footprints.assign(footprints.begin(), footprints.end());
    for (geo::Footprint& f : straight_footprints) {
      for (geo::FootprintPolygon& p : f.polygons) {
        p.outer = detail::straightened_ring(p.outer, 0.01);
        for (auto& h : p.holes) h = detail::straightened_ring(h, 0.01);
      }
    }
    footprints = straight_footprints;
  }
  if (footprints.empty() && out.vegetation_points == 0 && share == nullptr) {
    clusters = euclidean_clusters(cloud, options.clusters, &out.cluster_tolerance);
    region_footprint.assign(clusters.size(), -1);
  } else {
    const std::vector<int> of = detail::footprint_of_points(cloud, footprints, kFootprintBuffer);
    std::vector<std::vector<std::uint32_t>> members(footprints.size());
    std::vector<std::uint32_t> loose;  // cloud indices of the points in no footprint
    std::vector<Vec3> rest;
    auto kind_of = [&](int f) {
      return share != nullptr ? share->footprints[static_cast<std::size_t>(f)] : ShareKind::whole;
    };
    for (std::uint32_t i = 0; i < cloud.size(); ++i) {
      if (excluded[i]) continue;
      if (of[i] >= 0) {
        const ShareKind kind = kind_of(of[i]);
        if (kind == ShareKind::none || (kind == ShareKind::own_points && foreign[i])) {
          ++out.points_left_to_neighbours;  // that footprint's building is a neighbour's
          continue;
        }
        members[static_cast<std::size_t>(of[i])].push_back(i);
      } else {
        loose.push_back(i);
        rest.push_back(cloud[i]);
      }
    }
    for (std::size_t f = 0; f < footprints.size(); ++f) {
      if (kind_of(static_cast<int>(f)) == ShareKind::none) continue;
      if (members[f].size() < 8) {
        out.rejected.push_back({"footprint " + footprints[f].id,
                                "only " + std::to_string(members[f].size()) +
                                    " points of buildings in it: no building made",
                                static_cast<long long>(members[f].size())});
        out.footprints_without_building.push_back(footprints[f].id);
        continue;
      }
      out.footprint_points += static_cast<long long>(members[f].size());
      clusters.push_back(std::move(members[f]));
      region_footprint.push_back(static_cast<int>(f));
    }
    out.footprint_regions = static_cast<int>(clusters.size());
    for (auto& c : euclidean_clusters(rest, options.clusters, &out.cluster_tolerance)) {
      for (auto& i : c) i = loose[i];
      if (share != nullptr && share->clusters) {
        // The cluster's share, from its points' box (the same in every tile that sees the
        // whole cluster).
        Vec2 lo(INFINITY, INFINITY), hi(-INFINITY, -INFINITY);
        for (auto i : c) {
          lo = lo.cwiseMin(Vec2(cloud[i].x(), cloud[i].y()));
          hi = hi.cwiseMax(Vec2(cloud[i].x(), cloud[i].y()));
        }
        const ShareKind kind = share->clusters(lo, hi, out.cluster_tolerance);
        if (kind == ShareKind::none) {
          ++out.clusters_left_to_neighbours;
          out.points_left_to_neighbours += static_cast<long long>(c.size());
          continue;
        }
        if (kind == ShareKind::own_points) {
          ++out.clusters_split_with_neighbours;
          const auto size = c.size();
          std::erase_if(c, [&](std::uint32_t i) { return foreign[i] != 0; });
          out.points_left_to_neighbours += static_cast<long long>(size - c.size());
          if (c.empty()) continue;
          region_in_parts.resize(clusters.size(), 0);
          region_in_parts.push_back(1);
        }
      }
      clusters.push_back(std::move(c));
      region_footprint.push_back(-1);
    }
  }
  long long clustered = 0;
  for (const auto& c : clusters) clustered += static_cast<long long>(c.size());
  out.small_cluster_points =
      out.fitted_points - out.vegetation_points - clustered - out.points_left_to_neighbours;
  out.seconds.emplace_back("clusters", seconds_since(start));

  if (options.regions.enabled && footprints.empty()) {
    // Each cluster becomes its grown regions (in region_growing's order) followed by its
    // points in none of them as one leftover region, so that no point is lost to the RANSAC.
    // Regions are numbered in cluster order, then in that order within a cluster.
    start = std::chrono::steady_clock::now();
    std::vector<std::vector<std::uint32_t>> split;
    std::vector<char> split_in_parts;
    std::vector<Vec3> p, n;
    std::vector<double> k;
    region_in_parts.resize(clusters.size(), 0);
    for (std::size_t ci = 0; ci < clusters.size(); ++ci) {
      const auto& cluster = clusters[ci];
      p.clear();
      n.clear();
      k.clear();
      for (auto i : cluster) {
        p.push_back(cloud[i]);
        n.push_back(normals[i]);
        k.push_back(curvature[i]);
      }
      const auto grown = region_growing(p, n, options.regions, k);
      std::vector<char> taken(cluster.size(), 0);
      for (const auto& g : grown) {
        std::vector<std::uint32_t> members;
        members.reserve(g.size());
        for (auto local : g) {
          members.push_back(cluster[local]);
          taken[local] = 1;
        }
        split.push_back(std::move(members));
        split_in_parts.push_back(region_in_parts[ci]);
      }
      std::vector<std::uint32_t> rest;
      for (std::size_t local = 0; local < cluster.size(); ++local) {
        if (!taken[local]) rest.push_back(cluster[local]);
      }
      if (!rest.empty()) {
        split.push_back(std::move(rest));
        split_in_parts.push_back(region_in_parts[ci]);
      }
    }
    clusters = std::move(split);
    region_in_parts = std::move(split_in_parts);
    region_footprint.assign(clusters.size(), -1);  // grown regions: never with footprints
    out.seconds.emplace_back("regions", seconds_since(start));
  }
  out.regions = static_cast<int>(clusters.size());

  // Segments: each point of the fitted cloud gets its surface (numbered across regions).
  std::vector<std::int32_t> cloud_segment;
  if (options.keep_segments) cloud_segment.assign(cloud.size(), -1);

  // The regions are independent (each its own seed): detected and fitted at once, on up to
  // `threads` cores, then gathered in region order, so the output is the same on any number
  // of threads.
  struct RegionFit {
    std::optional<kernel::Error> error;
    std::vector<Vec3> p, n;  // kept past the fit for FitOutput::detections only
    RansacOptions ransac;
    RansacResult detected;
    bool with_primitives = false;  // primitives_from_shapes ran (`fitted` is the region's)
    FittedPrimitives fitted;
    double detect_seconds = 0.0, primitives_seconds = 0.0;
  };
  std::vector<RegionFit> fits(clusters.size());
  auto fit_region = [&](std::size_t r) {
    RegionFit& f = fits[r];
    if (options.interrupt.fired()) {
      f.error = options.interrupt.error("while fitting region " + std::to_string(r) + " of " +
                                        std::to_string(clusters.size()));
      return;
    }
    const auto t0 = std::chrono::steady_clock::now();
    f.p.reserve(clusters[r].size());
    f.n.reserve(clusters[r].size());
    for (auto i : clusters[r]) {
      f.p.push_back(cloud[i]);
      f.n.push_back(normals[i]);
    }
    f.ransac = options.ransac;
    f.ransac.seed = options.ransac.seed * 0x9E3779B97F4A7C15ULL + r;
    f.ransac.interrupt = options.interrupt;  // a stop also ends a long region's search
    auto detected = detect_shapes(f.p, f.n, f.ransac);
    if (!detected.ok()) {
      f.error = detected.error();
      return;
    }
    f.detected = std::move(detected).value();
    // Options the region derived from its points (0 in the options) are the primitives' too.
    if (f.detected.epsilon > 0.0) f.ransac.epsilon = f.detected.epsilon;
    if (f.detected.min_points > 0) f.ransac.min_points = f.detected.min_points;
    if (f.detected.max_radius > 0.0) f.ransac.max_radius = f.detected.max_radius;
    f.detect_seconds = seconds_since(t0);
    const int footprint = region_footprint[r];
    // A building region without a surface is still a building: its block (LoD1.2).
    f.with_primitives =
        !f.detected.shapes.empty() ||
        (primitive_options.ground != nullptr && (primitive_options.blocks || footprint >= 0));
    if (f.with_primitives) {
      const auto t1 = std::chrono::steady_clock::now();
      PrimitiveOptions region_options = primitive_options;
      if (r < region_in_parts.size() && region_in_parts[r]) region_options.split_houses = false;
      if (footprint >= 0) {
        region_options.footprint = &footprints[static_cast<std::size_t>(footprint)].polygons;
      }
      f.fitted = primitives_from_shapes(f.p, f.n, f.detected, region_options, f.ransac,
                                        static_cast<int>(r));
      if (footprint >= 0) {
        for (auto& prim : f.fitted.primitives)
          prim.building = footprints[static_cast<std::size_t>(footprint)].id;
      }
      f.primitives_seconds = seconds_since(t1);
    }
    if (!options.keep_detections) {  // the region's copy of its points is done with
      std::vector<Vec3>().swap(f.p);
      std::vector<Vec3>().swap(f.n);
    }
  };
  {
    // More threads than cores would only be refused by TBB (with a warning).
    const int cores = tbb::info::default_concurrency();
    tbb::task_arena arena(options.threads > 0 ? std::min(options.threads, cores) : cores);
    arena.execute([&] {
      tbb::parallel_for(std::size_t{0}, clusters.size(), fit_region, tbb::simple_partitioner());
    });
  }
  double ransac_seconds = 0.0, primitives_seconds = 0.0;
  std::vector<int> primitive_region;    // per primitive of out.primitives
  std::vector<double> primitive_reach;  // per primitive: its region's noise margin (members)
  for (std::size_t r = 0; r < clusters.size(); ++r) {
    RegionFit& f = fits[r];
    if (f.error) return *f.error;
    ransac_seconds += f.detect_seconds;
    primitives_seconds += f.primitives_seconds;
    const RansacResult& detected = f.detected;
    const int footprint = region_footprint[r];
    out.candidates += detected.candidates;
    if (options.keep_segments) {
      const auto first = static_cast<std::int32_t>(out.segments.size());
      for (const auto& shape : detected.shapes) {
        out.segments.push_back({static_cast<int>(r), shape.surface,
                                static_cast<long long>(shape.inliers.size()), shape.rms});
      }
      const auto& assignment = detected.assignment;
      for (std::size_t k = 0; k < clusters[r].size() && k < assignment.size(); ++k) {
        if (assignment[k] >= 0) cloud_segment[clusters[r][k]] = first + assignment[k];
      }
    }
    FitRegion stats;
    stats.points = static_cast<long long>(clusters[r].size());
    stats.spacing = detected.spacing;
    stats.cluster_epsilon = detected.cluster_epsilon;
    stats.epsilon = f.ransac.epsilon;
    stats.min_points = f.ransac.min_points;
    stats.shapes = static_cast<int>(detected.shapes.size());
    stats.candidates = detected.candidates;
    if (footprint >= 0) stats.building = footprints[static_cast<std::size_t>(footprint)].id;
    out.region_stats.push_back(stats);
    if (detected.shapes.empty()) {
      out.rejected.push_back({"region " + std::to_string(r), detected.reason,
                              static_cast<long long>(clusters[r].size())});
    }
    if (f.with_primitives) {
      FittedPrimitives& fitted = f.fitted;
      out.region_stats.back().primitives = static_cast<int>(fitted.primitives.size());
      const double reach = detail::member_reach(f.ransac.epsilon, detected.cluster_epsilon);
      for (auto& prim : fitted.primitives) {
        out.primitives.push_back(std::move(prim));
        primitive_region.push_back(static_cast<int>(r));
        primitive_reach.push_back(reach);
      }
      for (auto& rej : fitted.rejected) {
        rej.what = "region " + std::to_string(r) + " " + rej.what;
        out.rejected.push_back(std::move(rej));
      }
      for (std::size_t k = 0; k < out.per_type.size(); ++k) out.per_type[k] += fitted.per_type[k];
      out.assigned_points += fitted.assigned_points;
    }
    if (options.keep_detections) {
      out.detections.push_back({std::move(f.p), std::move(f.n), std::move(f.detected)});
    }
  }
  // A column fitted apart from the members it carries (its top hidden among them, its points
  // a region of their own) meets them.
  if (primitive_options.boxes) {
    detail::columns_into_members(
        out.primitives, primitive_reach,
        std::cos(primitive_options.angle_tolerance_deg * std::numbers::pi / 180.0));
  }
  // One ground per building: parts standing within the ground filter's height tolerance of
  // each other stand on one base (no sliver steps when they are fused).
  if (options.ground.enabled) detail::snap_extrusion_bases(out.primitives, options.ground.height);
  // Houses of different regions whose solids overlap (a storey clustered apart from the roof
  // beside it) are one house: two buildings never overlap (5 cm: more than touching).
  detail::join_overlapping_houses(out.primitives, primitive_region, 0.05);
  out.unassigned_points = out.fitted_points - out.assigned_points;
  if (options.keep_segments) {
    // Input point → fitted-cloud point: the same point when nothing was downsampled (or
    // dropped), else the nearest downsampled one.
    out.point_segment.assign(points.size(), -1);
    const bool same = !(options.voxel.size > 0.0) && cloud.size() == clean.size();
    const std::vector<std::int32_t> nearest =
        same ? std::vector<std::int32_t>{} : detail::nearest_of(clean, cloud);
    for (std::size_t k = 0; k < clean.size(); ++k) {
      const std::int32_t c = same ? static_cast<std::int32_t>(k) : nearest[k];
      if (c >= 0) out.point_segment[clean_index[k]] = cloud_segment[static_cast<std::size_t>(c)];
    }
  }
  if (options.keep_structure_points) {
    for (std::size_t k = 0; k < cloud.size(); ++k) {
      if (!excluded[k] && (foreign.empty() || !foreign[k]))
        out.structure_points.push_back(cloud[k]);
    }
  }
  // Seconds of the regions' detections and fits, summed over the regions (CPU time).
  out.seconds.emplace_back("ransac", ransac_seconds);
  out.seconds.emplace_back("primitives", primitives_seconds);
  return out;
}

}  // namespace csgtile::fit
