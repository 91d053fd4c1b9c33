// The roof partition of a building seen from the air (issue #18 item 3): the building's
// outline, as cells of a grid in its principal frame, is partitioned among its roof planes —
// each cell labelled with the plane that explains its points best, smoothed so that
// neighbouring cells prefer one label (iterated conditional modes on a Potts energy), cells
// no plane explains grouped into flat pieces of one height (LoD1.2: the 70th percentile of
// their points) — and each part (cells of one label) becomes the linear extrusion of its
// polygon from the building's ground up past its roof, cut by the half-space under its
// plane. The parts' polygons share their boundaries exactly (partition.cpp), so the parts
// tile the outline and the assembly fuses them into one solid without gaps or overlaps.

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>

#include "fit_internal.h"
#include "footprint_clip.h"
#include "houses.h"
#include "part_contacts.h"
#include "partition.h"
#include "plane2d.h"

namespace csgtile::fit::detail {

namespace {

// A roof label: the plane n·p = d (n.z > 0), from a detected shape, or flat at a height.
struct RoofPlane {
  Vec3 n = Vec3::UnitZ();
  double d = 0.0;
  int shape = -1;           // −1: a flat piece of points no plane explains
  std::vector<int> merged;  // the detected shapes it stands for (ascending after sort)
  double z(double x, double y) const { return (d - n.x() * x - n.y() * y) / n.z(); }
};

constexpr int kFree = -2;  // a cell no plane explains (yet): becomes part of a flat piece

}  // namespace

std::vector<Proposal> propose_roof_partition(const ProposalInput& in,
                                             std::vector<Rejection>& rejected) {
  std::vector<Proposal> out;
  const PrimitiveOptions& o = *in.options;
  if (o.ground == nullptr || !o.roof_partition) return out;
  const double spacing = in.shapes->spacing;
  if (!(spacing > 0.0)) return out;
  const auto& shapes = in.shapes->shapes;
  const double cos_wall = std::cos(75.0 * std::numbers::pi / 180.0);
  // Points on walls take no part in the roof's heights: the inliers of steep planes, and
  // points whose own normal is steep (walls seen too sparsely for a plane of their own, which
  // would otherwise pull the cells along a building's edge down to flat pieces under its roof).
  std::vector<char> wall(in.points.size(), 0);
  for (std::size_t s = 0; s < shapes.size(); ++s) {
    if (shapes[s].surface.type != ShapeType::Plane ||
        std::abs(shapes[s].surface.axis.z()) >= cos_wall) {
      continue;
    }
    for (auto i : shapes[s].inliers) wall[i] = 1;
  }
  if (in.normals.size() == in.points.size()) {
    for (std::size_t i = 0; i < in.points.size(); ++i) {
      if (in.normals[i].allFinite() && std::abs(in.normals[i].z()) < cos_wall) wall[i] = 1;
    }
  }
  std::vector<std::uint32_t> pts;
  std::vector<Vec2> flat;
  for (std::uint32_t i = 0; i < in.points.size(); ++i) {
    if ((*in.used)[i] || !in.points[i].allFinite()) continue;
    pts.push_back(i);
    flat.emplace_back(in.points[i].x(), in.points[i].y());
  }
  if (static_cast<long long>(pts.size()) < std::max<long long>(in.ransac->min_points, 8)) {
    return out;
  }
  // The building's bounds: its footprint, or else the outline derived from its points
  // (roof.cpp: traced, simplified, its edges along the main directions and on the outermost
  // points, or on the facade where the scan sees it under the eaves), so that walls stand
  // where the points end rather than on the grid's lines. The
  // partition is clipped to them; with neither (no outline could be derived), the grid's
  // cells holding points are the outline.
  const bool footprinted = o.footprint != nullptr && !o.footprint->empty();
  std::vector<geo::FootprintPolygon> derived;
  if (!footprinted) {
    std::string why;
    std::vector<double> heights;
    for (const auto i : pts) heights.push_back(in.points[i].z());
    const auto outline = roof_outline(
        in, flat, [](const Vec3&) { return false; }, why, &heights);
    if (outline) derived.push_back(outline_polygon(*outline));
  }
  const std::vector<geo::FootprintPolygon>* bounds =
      footprinted ? o.footprint : (derived.empty() ? nullptr : &derived);
  // The grid, in the frame of the bounds (walls along its axes stay straight), or of the
  // points, over them and the points.
  const auto frame = bounds != nullptr ? footprint_frame(*bounds) : principal_frame(flat);
  if (!frame) return out;
  const Vec2 u = frame->u, v = frame->v;
  double a0 = frame->a0, a1 = frame->a1, b0 = frame->b0, b1 = frame->b1;
  std::optional<FootprintClip> clip;
  if (bounds != nullptr) {
    clip.emplace(*bounds, u, v);
    if (!clip->extent(a0, a1, b0, b1)) {
      rejected.push_back(
          {"roof partition", "its footprint has no area", static_cast<long long>(pts.size())});
      return out;
    }
    for (const Vec2& q : flat) {
      a0 = std::min(a0, q.dot(u)), a1 = std::max(a1, q.dot(u));
      b0 = std::min(b0, q.dot(v)), b1 = std::max(b1, q.dot(v));
    }
  }
  if (!footprinted && std::min(a1 - a0, b1 - b0) < o.min_building_width) return out;
  const double cell = 1.5 * spacing;
  if (((a1 - a0) / cell + 5.0) * ((b1 - b0) / cell + 5.0) > 4e6) {
    rejected.push_back({"roof partition", "too large an outline for its grid",
                        static_cast<long long>(pts.size())});
    return out;
  }
  LabelGrid grid;
  grid.nx = static_cast<int>((a1 - a0) / cell) + 5;
  grid.ny = static_cast<int>((b1 - b0) / cell) + 5;
  const int nx = grid.nx, ny = grid.ny;
  const auto ncell = static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny);
  const double ga = a0 - 2.0 * cell, gb = b0 - 2.0 * cell;
  auto cell_of = [&](const Vec2& p) {
    const int i = std::clamp(static_cast<int>(std::floor((p.dot(u) - ga) / cell)), 0, nx - 1);
    const int j = std::clamp(static_cast<int>(std::floor((p.dot(v) - gb) / cell)), 0, ny - 1);
    return static_cast<std::size_t>(j) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(i);
  };
  // Points per cell (all, and those not on walls), as index lists.
  std::vector<std::vector<std::uint32_t>> in_cell(ncell), roof_in_cell(ncell);
  for (std::size_t k = 0; k < pts.size(); ++k) {
    const std::size_t c = cell_of(flat[k]);
    in_cell[c].push_back(pts[k]);
    if (!wall[pts[k]]) roof_in_cell[c].push_back(pts[k]);
  }
  // The 4-neighbours of cell c inside the grid, as cell indices.
  auto for_each_neighbour = [&](std::size_t c, const auto& visit) {
    const int i = static_cast<int>(c % static_cast<std::size_t>(nx)),
              j = static_cast<int>(c / static_cast<std::size_t>(nx));
    if (i + 1 < nx) visit(c + 1);
    if (i > 0) visit(c - 1);
    if (j + 1 < ny) visit(c + static_cast<std::size_t>(nx));
    if (j > 0) visit(c - static_cast<std::size_t>(nx));
  };
  // A free cell's cost and the height band of a point at the top of its cell.
  const double tau = std::max(0.25, 2.5 * in.ransac->epsilon);
  // The outline: with a footprint, the cells meeting it; else cells holding points, closed
  // over the gaps between scan lines (3 × 3), with holes under 4 m² filled (larger ones are
  // courtyards).
  std::vector<char> mask(ncell, 0);
  std::vector<double> area_in;  // with bounds: each cell's area inside them
  if (bounds != nullptr) {
    area_in.assign(ncell, 0.0);
    for (std::size_t c = 0; c < ncell; ++c) {
      const std::size_t column = c % static_cast<std::size_t>(nx);
      const std::size_t row = c / static_cast<std::size_t>(nx);
      const double ca = ga + static_cast<double>(column) * cell;
      const double cb = gb + static_cast<double>(row) * cell;
      area_in[c] = clip->area_in(ca, cb, ca + cell, cb + cell);
      mask[c] = area_in[c] > 1e-6 * cell * cell ? 1 : 0;
    }
  } else {
    for (std::size_t c = 0; c < ncell; ++c) mask[c] = in_cell[c].empty() ? 0 : 1;
    close_cells(mask, nx, ny);
  }
  if (bounds == nullptr) {
    LabelGrid empty{nx, ny, std::vector<int>(ncell, -1)};
    for (std::size_t c = 0; c < ncell; ++c) empty.label[c] = mask[c] ? -1 : 0;
    const Components holes = label_components(empty);
    std::vector<long long> size(static_cast<std::size_t>(holes.count), 0);
    std::vector<char> border(static_cast<std::size_t>(holes.count), 0);
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) {
        const int h = holes.of[static_cast<std::size_t>(j * nx + i)];
        if (h < 0) continue;
        ++size[static_cast<std::size_t>(h)];
        if (i == 0 || j == 0 || i == nx - 1 || j == ny - 1) border[static_cast<std::size_t>(h)] = 1;
      }
    }
    for (std::size_t c = 0; c < ncell; ++c) {
      const int h = holes.of[c];
      if (h >= 0 && !border[static_cast<std::size_t>(h)] &&
          static_cast<double>(size[static_cast<std::size_t>(h)]) * cell * cell < 4.0) {
        mask[c] = 1;
      }
    }
  }
  auto world = [&](double a, double b) { return Vec2(a * u + b * v); };
  // A structure seen from the side or from below (a gate, a frame of beams scanned from the
  // ground) is no building seen from the air: the air sees no ground under a roof. Over the
  // outline's interior (cells farther than a terrain cell from its edge), the terrain grid
  // must be mostly empty; a region with no such interior is left to the other steps. (A
  // footprint says it is a building.)
  if (!footprinted) {
    const GroundGrid& t = *o.ground;
    const int margin = static_cast<int>(std::ceil(t.cell / cell)) + 1;
    std::vector<char> inner = mask;
    for (int pass = 0; pass < margin; ++pass) {
      std::vector<char> next = inner;
      for (std::size_t c = 0; c < ncell; ++c) {
        if (!inner[c]) continue;
        int inside = 0;  // 4-neighbours in the grid and in the interior
        for_each_neighbour(c, [&](std::size_t k) { inside += inner[k] ? 1 : 0; });
        if (inside < 4) next[c] = 0;
      }
      inner = std::move(next);
    }
    long long interior = 0, seen_ground = 0;
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) {
        if (!inner[static_cast<std::size_t>(j * nx + i)]) continue;
        ++interior;
        const Vec2 w = world(ga + (i + 0.5) * cell, gb + (j + 0.5) * cell);
        const double gi = std::floor((w.x() - t.x0) / t.cell),
                     gj = std::floor((w.y() - t.y0) / t.cell);
        if (gi < 0 || gj < 0 || gi >= t.nx || gj >= t.ny) continue;
        const double h = t.z[static_cast<std::size_t>(gj) * static_cast<std::size_t>(t.nx) +
                             static_cast<std::size_t>(gi)];
        seen_ground += std::isfinite(h) ? 1 : 0;
      }
    }
    if (interior == 0 || 2 * seen_ground > interior) {
      rejected.push_back({"roof partition",
                          interior == 0
                              ? std::string("no outline wider than the terrain grid")
                              : "the ground is seen under " + std::to_string(seen_ground) + " of " +
                                    std::to_string(interior) +
                                    " cells of its interior (not a building seen from the air)",
                          static_cast<long long>(pts.size())});
      return out;
    }
  }

  // The terrain under the building: the lowest level around its outline.
  double g = lowest_ground_under(*o.ground, convex_hull(flat));
  if (!std::isfinite(g)) {
    const Vec2 mid = world(0.5 * (a0 + a1), 0.5 * (b0 + b1));
    g = o.ground->median_near(mid.x(), mid.y(), 0.5 * std::hypot(a1 - a0, b1 - b0));
  }
  if (!std::isfinite(g)) return out;
  // Candidate planes: the roof planes (not walls), regularised — near-coplanar ones (normals
  // within the angle tolerance, each through the other's centroid within half of `tau`)
  // merged and refitted, near-horizontal ones made horizontal at their median height — each
  // over the cells of its inliers grown by two cells.
  std::vector<RoofPlane> planes;
  std::vector<std::vector<std::uint32_t>> plane_points;
  {
    const double cos_tol = std::cos(o.angle_tolerance_deg * std::numbers::pi / 180.0);
    std::vector<int> roofs;
    for (std::size_t s = 0; s < shapes.size(); ++s) {
      const Surface& sf = shapes[s].surface;
      if (sf.type == ShapeType::Plane && !(*in.absorbed)[s] && std::abs(sf.axis.z()) >= cos_wall) {
        roofs.push_back(static_cast<int>(s));
      }
    }
    std::stable_sort(roofs.begin(), roofs.end(), [&](int x, int y) {
      return shapes[static_cast<std::size_t>(x)].inliers.size() >
             shapes[static_cast<std::size_t>(y)].inliers.size();
    });
    auto centroid = [&](const std::vector<std::uint32_t>& list) {
      Vec3 c = Vec3::Zero();
      for (auto i : list) c += in.points[i];
      return Vec3(c / static_cast<double>(std::max<std::size_t>(1, list.size())));
    };
    for (int s : roofs) {
      const Surface& sf = shapes[static_cast<std::size_t>(s)].surface;
      RoofPlane p;
      p.n = sf.axis.z() > 0.0 ? sf.axis : Vec3(-sf.axis);
      p.d = p.n.dot(sf.point);
      p.shape = s;
      std::vector<std::uint32_t> mine;
      for (auto i : shapes[static_cast<std::size_t>(s)].inliers) {
        if (!(*in.used)[i]) mine.push_back(i);
      }
      if (mine.empty()) continue;
      const Vec3 c = centroid(mine);
      bool merged = false;
      for (std::size_t k = 0; k < planes.size() && !merged; ++k) {
        RoofPlane& q = planes[k];
        const Vec3 cq = centroid(plane_points[k]);
        if (!(q.n.dot(p.n) >= cos_tol && std::abs(q.z(c.x(), c.y()) - c.z()) <= 0.5 * tau &&
              std::abs(p.z(cq.x(), cq.y()) - cq.z()) <= 0.5 * tau)) {
          continue;
        }
        auto& list = plane_points[k];
        list.insert(list.end(), mine.begin(), mine.end());
        std::sort(list.begin(), list.end());
        list.erase(std::unique(list.begin(), list.end()), list.end());
        if (const auto refit = fit_plane(in.points, list);
            refit && std::abs(refit->axis.z()) >= cos_wall) {  // else the plane stays
          q.n = refit->axis.z() > 0.0 ? refit->axis : Vec3(-refit->axis);
          q.d = q.n.dot(refit->point);
        }
        q.merged.push_back(s);
        merged = true;
      }
      if (!merged) {
        p.merged = {s};
        planes.push_back(p);
        plane_points.push_back(std::move(mine));
      }
    }
    // A plane within the angle tolerance of horizontal is made horizontal only where the
    // horizontal still explains its points: over them (a 5 % trim at each end) the tilted
    // plane rises less than half of `tau` above or below the median height. A wide, slightly
    // sloping roof keeps its slope.
    for (std::size_t k = 0; k < planes.size(); ++k) {
      if (planes[k].n.z() < cos_tol) continue;
      std::vector<double> z;
      for (auto i : plane_points[k]) z.push_back(in.points[i].z());
      std::nth_element(z.begin(), z.begin() + static_cast<std::ptrdiff_t>(z.size() / 2), z.end());
      const double level = z[z.size() / 2];
      std::vector<double> off;
      off.reserve(plane_points[k].size());
      for (auto i : plane_points[k]) {
        off.push_back(std::abs(planes[k].z(in.points[i].x(), in.points[i].y()) - level));
      }
      const auto q = static_cast<std::ptrdiff_t>(0.95 * static_cast<double>(off.size() - 1));
      std::nth_element(off.begin(), off.begin() + q, off.end());
      if (off[static_cast<std::size_t>(q)] > 0.5 * tau) continue;
      planes[k].n = Vec3::UnitZ();
      planes[k].d = level;
    }
  }
  std::vector<std::vector<int>> candidates(ncell);
  std::vector<int> marked(ncell, -1);  // the last plane that listed the cell
  for (std::size_t id = 0; id < planes.size(); ++id) {
    for (auto i : plane_points[id]) {
      const std::size_t c = cell_of(Vec2(in.points[i].x(), in.points[i].y()));
      const int ci = static_cast<int>(c % static_cast<std::size_t>(nx)),
                cj = static_cast<int>(c / static_cast<std::size_t>(nx));
      for (int dj = -2; dj <= 2; ++dj) {
        for (int di = -2; di <= 2; ++di) {
          const int x = ci + di, y = cj + dj;
          if (x < 0 || y < 0 || x >= nx || y >= ny) continue;
          const auto k = static_cast<std::size_t>(y * nx + x);
          if (marked[k] == static_cast<int>(id)) continue;
          marked[k] = static_cast<int>(id);
          candidates[k].push_back(static_cast<int>(id));
        }
      }
    }
  }
  // Data cost: the mean vertical residual of a cell's roof points under a label, each capped;
  // a free cell costs `tau`; a cell without roof points costs nothing under any label.
  const double cap = 2.0 * tau;
  const double lambda = 0.3 * tau;
  auto cost = [&](std::size_t c, int label) {
    const auto& list = roof_in_cell[c];
    if (list.empty()) return 0.0;
    if (label == kFree) return tau;
    const RoofPlane& p = planes[static_cast<std::size_t>(label)];
    double sum = 0.0;
    for (auto i : list) {
      const Vec3& q = in.points[i];
      sum += std::min(std::abs(q.z() - p.z(q.x(), q.y())), cap);
    }
    return sum / static_cast<double>(list.size());
  };
  std::vector<int> label(ncell, -1);
  std::vector<std::size_t> queue;
  for (std::size_t c = 0; c < ncell; ++c) {
    if (!mask[c]) continue;
    if (roof_in_cell[c].empty()) continue;
    int best = kFree;
    double best_cost = tau;
    for (int l : candidates[c]) {
      const double e = cost(c, l);
      if (e < best_cost) {
        best_cost = e;
        best = l;
      }
    }
    label[c] = best;
    queue.push_back(c);
  }
  if (queue.empty()) return out;
  // Cells without roof points take a neighbour's label (breadth first, in cell order).
  for (std::size_t h = 0; h < queue.size(); ++h) {
    const std::size_t c = queue[h];
    for_each_neighbour(c, [&](std::size_t k) {
      if (!mask[k] || label[k] != -1) return;
      label[k] = label[c];
      queue.push_back(k);
    });
  }
  for (std::size_t c = 0; c < ncell; ++c) {
    if (mask[c] && label[c] == -1) mask[c] = 0;
  }
  // Smoothing: each cell takes the label of least cost + λ per 4-neighbour labelled otherwise.
  auto neighbours = [&](std::size_t c) {
    std::array<int, 4> l{-1, -1, -1, -1};
    std::size_t n = 0;
    for_each_neighbour(c, [&](std::size_t x) {
      if (mask[x]) l[n] = label[x];
      ++n;
    });
    return l;
  };
  for (int sweep = 0; sweep < 6; ++sweep) {
    bool changed = false;
    for (std::size_t c = 0; c < ncell; ++c) {
      if (!mask[c]) continue;
      const auto nb = neighbours(c);
      std::vector<int> options{label[c], kFree};
      options.insert(options.end(), candidates[c].begin(), candidates[c].end());
      for (int l : nb) {
        if (l != -1) options.push_back(l);
      }
      auto energy = [&](int l) {
        double e = cost(c, l);
        for (int m : nb) e += (m != -1 && m != l) ? lambda : 0.0;
        return e;
      };
      int best = label[c];
      double best_e = energy(best);
      for (int l : options) {
        const double e = energy(l);
        if (e < best_e - 1e-12) {
          best_e = e;
          best = l;
        }
      }
      if (best != label[c]) {
        label[c] = best;
        changed = true;
      }
    }
    if (!changed) break;
  }
  // With bounds, cells mostly outside them (eaves, points of walls) take the label of their
  // neighbour most inside them: label boundaries then meet the bounds' edge where roofs
  // meet, instead of running along it (slivers between a part and the edge).
  if (bounds != nullptr) {
    for (int pass = 0; pass < 2; ++pass) {
      std::vector<int> next = label;
      for (std::size_t c = 0; c < ncell; ++c) {
        if (!mask[c] || area_in[c] >= 0.5 * cell * cell) continue;
        double most = area_in[c];
        for_each_neighbour(c, [&](std::size_t k) {
          if (mask[k] && label[k] != -1 && area_in[k] > most) {
            most = area_in[k];
            next[c] = label[k];
          }
        });
      }
      label = std::move(next);
    }
  }
  // Free cells become flat pieces: connected cells whose highest roof points differ by less
  // than a step, each at the 70th percentile of its points' heights. The step is the largest
  // residual the labelling accepts (the cost's cap, 2 tau), at least a quarter of the lowest
  // building: a roof structure a metre above the roof around it is its own piece (a 1 m step
  // made one piece of both, at a height explaining neither).
  {
    const double step = std::max(2.0 * tau, 0.25 * o.min_building_height);
    std::vector<double> top(ncell, NAN);  // of all points: a wall's cell is as high as it
    for (std::size_t c = 0; c < ncell; ++c) {
      for (auto i : in_cell[c]) {
        top[c] = std::isnan(top[c]) ? in.points[i].z() : std::max(top[c], in.points[i].z());
      }
    }
    // Pieces grow from their highest cell down to a step below it: grown cell to cell alone,
    // a sloping strip (a mansard's steep edge, a curved roof no plane fits) drifted up or down
    // by less than a step per cell into one piece metres high, at a height explaining none of it.
    std::vector<std::size_t> order;
    for (std::size_t c = 0; c < ncell; ++c) {
      if (mask[c] && label[c] == kFree) order.push_back(c);
    }
    std::stable_sort(order.begin(), order.end(), [&](std::size_t x, std::size_t y) {
      if (std::isnan(top[y])) return !std::isnan(top[x]);
      return !std::isnan(top[x]) && top[x] > top[y];
    });
    std::vector<char> seen(ncell, 0);
    for (const std::size_t start : order) {
      if (seen[start]) continue;
      std::vector<std::size_t> piece{start};
      seen[start] = 1;
      const double highest = top[start];
      for (std::size_t h = 0; h < piece.size(); ++h) {
        const std::size_t c = piece[h];
        if (std::isnan(top[c])) continue;  // an empty cell joins a piece but bridges none
        for_each_neighbour(c, [&](std::size_t k) {
          if (!mask[k] || label[k] != kFree || seen[k]) return;
          if (!std::isnan(top[k]) &&
              (std::abs(top[c] - top[k]) >= step || !(highest - top[k] < step))) {
            return;
          }
          seen[k] = 1;
          piece.push_back(k);
        });
      }
      std::vector<double> z;
      for (auto c : piece) {
        for (auto i : roof_in_cell[c]) z.push_back(in.points[i].z());
      }
      RoofPlane p;
      if (!z.empty()) {
        std::sort(z.begin(), z.end());
        p.d = z[static_cast<std::size_t>(0.7 * static_cast<double>(z.size() - 1))];
      } else {
        p.d = NAN;  // no points: taken by a neighbour below
      }
      const int id = static_cast<int>(planes.size());
      planes.push_back(p);
      for (auto c : piece) label[c] = id;
    }
  }
  grid.label = label;
  for (std::size_t c = 0; c < ncell; ++c) {
    if (!mask[c]) grid.label[c] = -1;
  }
  auto pointless = [&](int l) { return std::isnan(planes[static_cast<std::size_t>(l)].d); };
  // Small parts (under a square metre, or four cells) and pieces without points join the
  // neighbour they share most of their boundary with; pinches are joined through a cell.
  const long long min_cells =
      std::max<long long>(4, static_cast<long long>(std::ceil(1.0 / (cell * cell))));
  for (int round = 0; round < 32; ++round) {
    bool changed = false;
    const Components comp = label_components(grid);
    std::vector<long long> size(static_cast<std::size_t>(comp.count), 0);
    for (std::size_t c = 0; c < ncell; ++c) {
      if (comp.of[c] >= 0) ++size[static_cast<std::size_t>(comp.of[c])];
    }
    // Border lengths with each neighbouring part (by component, so that a target is known
    // by its size).
    std::vector<std::map<int, long long>> border(static_cast<std::size_t>(comp.count));
    for (std::size_t c = 0; c < ncell; ++c) {
      const int k = comp.of[c];
      if (k < 0) continue;
      for_each_neighbour(c, [&](std::size_t x) {
        const int m = comp.of[x];
        if (m < 0 || m == k || pointless(grid.label[x])) return;
        ++border[static_cast<std::size_t>(k)][m];
      });
    }
    // A small part joins the neighbour larger than itself (ties: the lower component, so that
    // two small neighbours never swap labels) whose plane explains its roof points best (the
    // sum of their capped vertical residuals; ties: the longest shared boundary): by boundary
    // alone, a strip of a steep roof edge took the flat roof above it. A piece without points
    // joins the neighbour it shares most boundary with.
    std::vector<int> target(static_cast<std::size_t>(comp.count), -2);  // -2: stays
    std::vector<int> comp_label(static_cast<std::size_t>(comp.count), -1);
    std::vector<std::vector<std::size_t>> cells_of(static_cast<std::size_t>(comp.count));
    for (std::size_t c = 0; c < ncell; ++c) {
      if (comp.of[c] < 0) continue;
      comp_label[static_cast<std::size_t>(comp.of[c])] = grid.label[c];
      cells_of[static_cast<std::size_t>(comp.of[c])].push_back(c);
    }
    auto residual = [&](std::size_t k, int l) {  // the labelling's cost, summed over points
      double sum = 0.0;
      for (auto c : cells_of[k]) sum += cost(c, l) * static_cast<double>(roof_in_cell[c].size());
      return sum;
    };
    for (int k = 0; k < comp.count; ++k) {
      const auto ks = static_cast<std::size_t>(k);
      const bool empty = pointless(comp_label[ks]);
      if (!empty && size[ks] >= min_cells) continue;
      long long most = 0;
      double least = std::numeric_limits<double>::infinity();
      int best = -1;
      for (const auto& [m, n] : border[ks]) {
        const auto ms = static_cast<std::size_t>(m);
        if (empty) {
          if (n > most) most = n, best = m;
          continue;
        }
        const bool larger = size[ms] > size[ks] || (size[ms] == size[ks] && m < k);
        if (!larger) continue;
        const double r = residual(ks, comp_label[ms]);
        if (r < least - 1e-9 || (r <= least + 1e-9 && n > most)) {
          least = r;
          most = n;
          best = m;
        }
      }
      if (best >= 0) {
        target[ks] = comp_label[static_cast<std::size_t>(best)];
      } else if (empty) {
        target[ks] = -1;  // no neighbour, no points: dropped
      }
    }
    for (std::size_t c = 0; c < ncell; ++c) {
      const int k = comp.of[c];
      if (k < 0 || target[static_cast<std::size_t>(k)] == -2) continue;
      grid.label[c] = target[static_cast<std::size_t>(k)];
      changed = true;
    }
    changed = unpinch(grid) > 0 || changed;
    if (!changed) break;
  }
  // Two more passes (each changes the grid): still pinched after both, the partition fails.
  const bool pinched = unpinch(grid) > 0;
  if (pinched && unpinch(grid) > 0) {
    rejected.push_back({"roof partition", "its parts could not be made free of pinches",
                        static_cast<long long>(pts.size())});
    return out;
  }
  // The parts' polygons, then their solids.
  const auto parts = partition_polygons(grid, 0.9);
  // The terrain under each part: the lowest ground around its outline; a part inside a large
  // roof (no ground seen near it) stands on the highest of its neighbours' (repeatedly: never
  // below the terrain any neighbour sees), else on the building's lowest level. Bases within the
  // ground filter's tolerance are snapped to one level after the fit (bases.cpp).
  std::vector<double> bases(parts.size(), NAN);
  {
    for (std::size_t k = 0; k < parts.size(); ++k) {
      std::vector<Vec2> footprint;
      for (const auto& q : parts[k].outer) {
        footprint.push_back(world(ga + q.x() * cell, gb + q.y() * cell));
      }
      bases[k] = lowest_ground_under(*o.ground, footprint);
    }
    for (bool changed = true; changed;) {
      changed = false;
      std::vector<double> next = bases;
      for (std::size_t k = 0; k < parts.size(); ++k) {
        if (std::isfinite(bases[k])) continue;
        for (int n : parts[k].neighbours) {
          const double b = bases[static_cast<std::size_t>(n)];
          if (std::isfinite(b) && !(next[k] >= b)) next[k] = b;
        }
        changed = changed || std::isfinite(next[k]);
      }
      bases = std::move(next);
    }
    for (auto& b : bases) {
      if (!std::isfinite(b)) b = g;
    }
    // A building on terrain level within a metre stands on one level, at most half a metre
    // under the terrain around any part and at most half a metre above it: its parts'
    // bottoms are one face (steps of a few decimetres under a roof are no terrain a model
    // should follow, and they burden the fuse with slivers).
    const auto [lo, hi] = std::minmax_element(bases.begin(), bases.end());
    if (lo != bases.end() && *hi - *lo <= 1.0) {
      std::fill(bases.begin(), bases.end(), std::max(*lo, *hi - 0.5));
    }
  }
  // A point just inside a part's hole (a clockwise ring, grid units): beside its first edge,
  // on its right.
  auto inside_hole = [](const std::vector<Eigen::Vector2d>& h) {
    const Eigen::Vector2d d = h[1] - h[0];
    return Eigen::Vector2d(0.5 * (h[0] + h[1]) +
                           1e-3 * Eigen::Vector2d(d.y(), -d.x()).normalized());
  };
  // Without a footprint, the block's houses (houses.h): two parts are one house where their
  // roofs meet along their shared cell edges — at each edge's middle, their heights within a
  // step (as for flat pieces) plus the difference of their slopes over a cell (a ridge found
  // up to a cell off its line); an edge where the two share no wall (one's base above the
  // other's roof) joins nothing. A house is at least min_house_area, 1.5 m (or the narrowest
  // building) wide, with a tenth of its boundary outside (no parapet, no structure on a roof).
  std::vector<int> house_of_part;
  if (!footprinted && o.split_houses && parts.size() > 1) {
    const double step = std::max(2.0 * tau, 0.25 * o.min_building_height);
    std::vector<int> part_of(ncell, -1);
    for (std::size_t k = 0; k < parts.size(); ++k) {
      if (parts[k].label < 0) continue;
      for (auto c : parts[k].cells) part_of[static_cast<std::size_t>(c)] = static_cast<int>(k);
    }
    std::vector<HousePart> house_parts(parts.size());
    std::map<std::pair<int, int>, PartBoundary> boundary;
    // The edge between cells c and d (d < 0: off the grid), its middle at (mi, mj) in cells.
    auto edge = [&](std::ptrdiff_t c, std::ptrdiff_t d, double mi, double mj) {
      const int a = c < 0 ? -1 : part_of[static_cast<std::size_t>(c)];
      const int b = d < 0 ? -1 : part_of[static_cast<std::size_t>(d)];
      if (a == b) return;
      // Its length is on the outside of either part unless they share a wall there.
      auto outside = [&] {
        for (const int k : {a, b}) {
          if (k >= 0) house_parts[static_cast<std::size_t>(k)].outside += cell;
        }
      };
      for (const int k : {a, b}) {
        if (k >= 0) house_parts[static_cast<std::size_t>(k)].perimeter += cell;
      }
      if (a < 0 || b < 0) {
        outside();
        return;
      }
      const RoofPlane& pa =
          planes[static_cast<std::size_t>(parts[static_cast<std::size_t>(a)].label)];
      const RoofPlane& pb =
          planes[static_cast<std::size_t>(parts[static_cast<std::size_t>(b)].label)];
      const Vec2 w = world(ga + mi * cell, gb + mj * cell);
      const double za = pa.z(w.x(), w.y()), zb = pb.z(w.x(), w.y());
      // No wall in common there (one stands wholly above the other's roof, on higher ground):
      // no contact, for the houses as for the fuse.
      if (!(std::min(za, zb) -
                std::max(bases[static_cast<std::size_t>(a)], bases[static_cast<std::size_t>(b)]) >
            0.1)) {
        outside();
        return;
      }
      PartBoundary& e = boundary[{std::min(a, b), std::max(a, b)}];
      e.a = std::min(a, b);
      e.b = std::max(a, b);
      e.length += cell;
      ++e.edges;
      const Vec2 slope_a(-pa.n.x() / pa.n.z(), -pa.n.y() / pa.n.z());
      const Vec2 slope_b(-pb.n.x() / pb.n.z(), -pb.n.y() / pb.n.z());
      const double apart = std::abs(za - zb);
      if (apart <= step + (slope_a - slope_b).norm() * cell) ++e.continuous;
    };
    for (int j = -1; j < ny; ++j) {
      for (int i = -1; i < nx; ++i) {
        const std::ptrdiff_t c = i < 0 || j < 0 ? -1 : static_cast<std::ptrdiff_t>(j) * nx + i;
        const std::ptrdiff_t right =
            i + 1 < nx && j >= 0 ? static_cast<std::ptrdiff_t>(j) * nx + i + 1 : -1;
        const std::ptrdiff_t up =
            j + 1 < ny && i >= 0 ? static_cast<std::ptrdiff_t>(j + 1) * nx + i : -1;
        if (j >= 0) edge(c, right, i + 1.0, j + 0.5);
        if (i >= 0) edge(c, up, i + 0.5, j + 1.0);
      }
    }
    for (std::size_t k = 0; k < parts.size(); ++k) {
      house_parts[k].area = static_cast<double>(parts[k].cells.size()) * cell * cell;
    }
    std::vector<PartBoundary> boundaries;
    for (const auto& [pair, e] : boundary) boundaries.push_back(e);
    HouseRules rules;
    rules.min_area = o.min_house_area;
    rules.min_width = std::max(1.5, o.min_building_width);
    house_of_part = group_houses(house_parts, boundaries, rules);
    // A part inside another's hole (a tower, a roof structure) is that part's house: a tilted
    // roof is not cut around it (below), the two overlap, and two houses never overlap.
    for (std::size_t k = 0; k < parts.size(); ++k) {
      for (const auto& h : parts[k].holes) {
        if (h.size() < 3) continue;
        const Eigen::Vector2d inside = inside_hole(h);
        for (std::size_t m = 0; m < parts.size(); ++m) {
          const int from = house_of_part[m], to = house_of_part[k];
          if (m == k || from == to || parts[m].outer.size() < 3 ||
              !inside_ring(inside, parts[m].outer)) {
            continue;
          }
          for (int& x : house_of_part) x = x == from ? to : x;
        }
      }
    }
  }
  // Whether a plane stands high enough over a part (on `base`) to be its roof, and the lowest
  // and highest it reaches over a polygon's corners.
  auto reach = [&](const RoofPlane& plane, double base, const std::vector<Vec2>& ring, double& low,
                   double& high) {
    low = INFINITY, high = -INFINITY;
    for (const auto& q : ring) {
      const Vec2 w = world(q.x(), q.y());
      low = std::min(low, plane.z(w.x(), w.y()));
      high = std::max(high, plane.z(w.x(), w.y()));
    }
    return plane.shape >= 0 && low - base >= 0.5 * o.min_building_height;
  };
  auto skipped = [&](const PartPolygon& part) { return part.outer.size() < 3 || part.label < 0; };
  // Each part's polygon in the frame. With a footprint (or a derived outline), its pieces
  // inside it, their vertices snapped across the parts, then shared by the walls the snap
  // moved them off (share_vertices). Slivers are left out: under a hundredth of a cell in a
  // footprint (which the building covers exactly), under a cell in a derived outline (a corner
  // the outline cuts off a part: a speck touching the part at a point, whose footprint is then
  // in pieces).
  const double snap_distance = std::min(0.05, 0.1 * cell);
  std::optional<VertexSnap> snap;
  if (clip) snap.emplace(snap_distance);
  std::vector<std::vector<FramePolygon>> part_pieces(parts.size());
  for (std::size_t k = 0; k < parts.size(); ++k) {
    const PartPolygon& part = parts[k];
    if (skipped(part)) continue;
    const RoofPlane& plane = planes[static_cast<std::size_t>(part.label)];
    FramePolygon whole;
    for (const auto& q : part.outer) whole.outer.emplace_back(ga + q.x() * cell, gb + q.y() * cell);
    double low = 0.0, high = 0.0;
    const bool tilted_whole = reach(plane, bases[k], whole.outer, low, high);
    for (const auto& h : part.holes) {
      if (tilted_whole) {
        // A tilted roof around an inner part that stands higher (a chimney, a dormer, a
        // tower) is not cut around it: the two overlap and the fuse joins them. Its face then
        // has no inner ring lying on the lines of its outer one (grid lines), which the
        // mesher's hole bridging cannot always tell apart in the roof's tilted parameter plane.
        const Eigen::Vector2d inside = inside_hole(h);
        bool filled_higher = false;
        for (std::size_t m = 0; m < parts.size() && !filled_higher; ++m) {
          if (m == k || parts[m].label < 0 || parts[m].outer.size() < 3 ||
              !inside_ring(inside, parts[m].outer)) {
            continue;
          }
          const Vec2 w = world(ga + inside.x() * cell, gb + inside.y() * cell);
          const RoofPlane& other = planes[static_cast<std::size_t>(parts[m].label)];
          filled_higher = !std::isnan(other.d) && other.z(w.x(), w.y()) >= plane.z(w.x(), w.y());
        }
        if (filled_higher) continue;
      }
      std::vector<Vec2> hole;
      for (const auto& q : h) hole.emplace_back(ga + q.x() * cell, gb + q.y() * cell);
      whole.holes.push_back(std::move(hole));
    }
    if (clip) {
      const double least = (footprinted ? 0.01 : 1.0) * cell * cell;
      for (const FramePolygon& piece : clip->clip(whole, least)) {
        if (auto snapped = snap->snap(piece)) part_pieces[k].push_back(std::move(*snapped));
      }
    } else {
      part_pieces[k].push_back(std::move(whole));
    }
  }
  if (clip) share_vertices(part_pieces, snap_distance);
  // Each piece a proposal; each point goes with the piece it lies in, else with the largest.
  for (std::size_t k = 0; k < parts.size(); ++k) {
    const PartPolygon& part = parts[k];
    if (skipped(part)) continue;
    const RoofPlane& plane = planes[static_cast<std::size_t>(part.label)];
    const std::string what = "roof partition part " + std::to_string(k) +
                             (plane.shape >= 0 ? " of plane " + std::to_string(plane.shape)
                                               : std::string(" (flat, LoD1.2)"));
    std::vector<std::uint32_t> members;
    for (auto c : part.cells) {
      members.insert(members.end(), in_cell[static_cast<std::size_t>(c)].begin(),
                     in_cell[static_cast<std::size_t>(c)].end());
    }
    std::sort(members.begin(), members.end());
    const double base = bases[k];
    double low = 0.0, high = 0.0;
    const std::vector<FramePolygon>& pieces = part_pieces[k];
    std::vector<std::vector<std::uint32_t>> piece_members(pieces.size());
    for (auto i : members) {
      const Vec2 ab(in.points[i].x() * u.x() + in.points[i].y() * u.y(),
                    in.points[i].x() * v.x() + in.points[i].y() * v.y());
      std::size_t at = 0;
      for (std::size_t m = 0; m < pieces.size(); ++m) {
        if (inside_ring(ab, pieces[m].outer)) {
          at = m;
          break;
        }
      }
      if (!pieces.empty()) piece_members[at].push_back(i);
    }
    for (std::size_t m = 0; m < pieces.size(); ++m) {
      const FramePolygon& piece = pieces[m];
      const std::string piece_what =
          pieces.size() > 1 ? what + " piece " + std::to_string(m) : what;
      Proposal p;
      p.members = std::move(piece_members[m]);
      RoofOutline outline;
      outline.u = u;
      outline.v = v;
      outline.cell = cell;
      outline.seen_cells = part.cells.size();
      outline.profile = piece.outer;
      outline.holes = piece.holes;
      OutlineGround under;
      for (const auto& q : outline.profile) {
        under.footprint.push_back(world(q.x(), q.y()));
        under.centre += q / static_cast<double>(outline.profile.size());
      }
      under.world_centre = world(under.centre.x(), under.centre.y());
      under.ground = base;
      const bool tilted = reach(plane, base, outline.profile, low, high);
      double roof = high;
      if (!tilted) {
        // Flat, or a plane that would reach down to the terrain: LoD1.2 at the 70th
        // percentile of the part's points.
        std::vector<double> z;
        for (auto i : members) {
          if (!wall[i]) z.push_back(in.points[i].z());
        }
        if (z.empty()) continue;
        std::sort(z.begin(), z.end());
        roof = z[static_cast<std::size_t>(0.7 * static_cast<double>(z.size() - 1))];
      }
      if (roof - base < 0.5 * o.min_building_height) {
        rejected.push_back({piece_what, "not a building's height above the terrain",
                            static_cast<long long>(p.members.size())});
        continue;
      }
      auto spec = outline_extrusion(outline, under, tilted ? high - base + 1.0 : roof - base);
      if (!spec) continue;
      p.spec = std::move(*spec);
      if (tilted) {
        const kernel::Location loc = p.spec.placement;
        const Vec3 nl = loc.rotation().transpose() * plane.n;
        p.spec.clips.push_back(
            Eigen::Vector4d(nl.x(), nl.y(), nl.z(), plane.d - plane.n.dot(loc.translation())));
        p.shapes = plane.merged;
        std::sort(p.shapes.begin(), p.shapes.end());
      }
      const double area = polygon_area(outline.profile, outline.holes);
      p.area = area / (tilted ? plane.n.z() : 1.0) +
               polygon_perimeter(outline.profile, outline.holes) * (0.5 * (low + high) - base);
      p.what = piece_what;
      if (!house_of_part.empty()) p.house = house_of_part[k];
      out.push_back(std::move(p));
    }
  }
  // Parts meeting at one vertex only with another between them stand over the same heights
  // there (a flat roof raised at most a fifth of the lowest building's height), or no longer
  // meet (a corner cut by a fifth of a cell).
  close_point_contacts(out, 0.2 * o.min_building_height, 0.2 * cell);
  return out;
}

}  // namespace csgtile::fit::detail
