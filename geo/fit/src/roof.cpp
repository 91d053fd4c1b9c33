// Extrusions from a flat roof seen from the air, whose walls the scan barely sees: the
// outline of the roof's points (an occupancy grid in the roof's principal frame, closed over
// the gaps between scan lines, its boundary traced, simplified and its edges snapped to the
// principal directions and moved onto the outermost roof points) is the footprint, the roof
// the top, the terrain under it (the ground grid) the bottom. Inner rings of the outline are
// courtyards unless something stands on the roof there (a stair housing is no hole).
//
// Kept only when it describes the region more briefly than the box around its footprint:
// description length = points unexplained (neither inside the solid nor within the outline's
// precision of its walls) + roof area the primitive claims but no roof point
// covers (× point density) + λ · parameters, as in extrusion.cpp. The box of an L-shaped
// block claims a roof over the empty corner, the extrusion does not.

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numbers>

#include <Eigen/Eigenvalues>

#include "fit_internal.h"
#include "partition.h"
#include "plane2d.h"

namespace csgtile::fit::detail {

namespace {

// Whether segments ab and cd share a point (crossing, touching or overlapping).
bool segments_meet(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) {
  const double o1 = cross2(a, b, c), o2 = cross2(a, b, d), o3 = cross2(c, d, a),
               o4 = cross2(c, d, b);
  const auto opposite = [](double x, double y) { return (x > 0 && y < 0) || (x < 0 && y > 0); };
  if (opposite(o1, o2) && opposite(o3, o4)) return true;
  const auto on = [](const Vec2& p, const Vec2& q, const Vec2& r) {  // r on segment pq
    return std::min(p.x(), q.x()) <= r.x() && r.x() <= std::max(p.x(), q.x()) &&
           std::min(p.y(), q.y()) <= r.y() && r.y() <= std::max(p.y(), q.y());
  };
  return (o1 == 0 && on(a, b, c)) || (o2 == 0 && on(a, b, d)) || (o3 == 0 && on(c, d, a)) ||
         (o4 == 0 && on(c, d, b));
}

// Per edge of `ring` (edge k from vertex k): 1 when it meets an edge other than its
// neighbours, or folds back onto one. Zero-length edges (a vertex repeated) are no edges: the
// edges on either side of them are neighbours.
std::vector<char> crossing_edges(const std::vector<Vec2>& ring) {
  const std::size_t n = ring.size();
  std::vector<char> out(n, 0);
  if (n < 3) return out;
  std::vector<std::size_t> edge;  // the edges of non-zero length, in order
  for (std::size_t k = 0; k < n; ++k) {
    if ((ring[(k + 1) % n] - ring[k]).norm() > 1e-9) edge.push_back(k);
  }
  const std::size_t m = edge.size();
  for (std::size_t i = 0; i < m; ++i) {
    const Vec2 &a = ring[edge[i]], &b = ring[(edge[i] + 1) % n];
    const std::size_t next = edge[(i + 1) % m];
    const Vec2& c = ring[(next + 1) % n];
    if (m > 2 && cross2(b, a, c) == 0.0 && (a - b).dot(c - b) > 0.0) {
      out[edge[i]] = out[next] = 1;
    }
    for (std::size_t j = i + 2; j < m; ++j) {
      if (i == 0 && j == m - 1) continue;
      if (segments_meet(a, b, ring[edge[j]], ring[(edge[j] + 1) % n])) {
        out[edge[i]] = out[edge[j]] = 1;
      }
    }
  }
  return out;
}

using kernel::PrimitiveType;
using kernel::Vec2;

// The boundary loops of the occupied cells of a grid (nx × ny, a one-cell empty border),
// with the occupied side on the left: outer rings counter-clockwise, holes clockwise. At a
// vertex where two loops touch diagonally the trace turns left, keeping them apart.
std::vector<std::vector<std::array<int, 2>>> trace(const std::vector<char>& occ, int nx, int ny) {
  auto at = [&](int i, int j) {
    return i >= 0 && j >= 0 && i < nx && j < ny &&
           occ[static_cast<std::size_t>(j) * static_cast<std::size_t>(nx) +
               static_cast<std::size_t>(i)];
  };
  struct Edge {
    std::array<int, 2> a, b;
  };
  std::vector<Edge> edges;
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      if (!at(i, j)) continue;
      if (!at(i, j - 1)) edges.push_back({{i, j}, {i + 1, j}});
      if (!at(i + 1, j)) edges.push_back({{i + 1, j}, {i + 1, j + 1}});
      if (!at(i, j + 1)) edges.push_back({{i + 1, j + 1}, {i, j + 1}});
      if (!at(i - 1, j)) edges.push_back({{i, j + 1}, {i, j}});
    }
  }
  std::map<std::array<int, 2>, std::vector<std::size_t>> from;
  for (std::size_t e = 0; e < edges.size(); ++e) from[edges[e].a].push_back(e);
  std::vector<char> done(edges.size(), 0);
  std::vector<std::vector<std::array<int, 2>>> loops;
  for (std::size_t first = 0; first < edges.size(); ++first) {
    if (done[first]) continue;
    std::vector<std::array<int, 2>> loop;
    std::size_t e = first;
    for (;;) {
      done[e] = 1;
      loop.push_back(edges[e].a);
      const auto& out = from[edges[e].b];
      std::size_t next = edges.size();
      const int dx = edges[e].b[0] - edges[e].a[0], dy = edges[e].b[1] - edges[e].a[1];
      int best_turn = -2;
      for (auto k : out) {
        if (done[k]) continue;
        const int ex = edges[k].b[0] - edges[k].a[0], ey = edges[k].b[1] - edges[k].a[1];
        const int turn = dx * ey - dy * ex;  // +1 left, 0 straight, -1 right
        if (turn > best_turn) {
          best_turn = turn;
          next = k;
        }
      }
      if (next == edges.size()) break;
      e = next;
    }
    if (loop.size() >= 4) loops.push_back(std::move(loop));
  }
  return loops;
}

// Where the scan sees the wall under an outline edge, the wall's line: points of the facade
// lie well below the roof at the edge (more than kFacadeDrop under the highest point within a
// metre along the edge) and, on one wall, on one line. The line is fitted to them (principal
// axis, refitted once without the points farther than twice its thickness: balconies, window
// recesses) and taken when there are enough of them (ten, and one per metre of the edge's
// middle), most lie on it and it is thin (within kFacadeSpread); nullopt otherwise (the wall
// unseen, as airborne scans mostly leave it). The thickness allowed is a facade's relief
// (window reveals, pilasters, ornament: AHN4's facades spread 0.2-0.35 m RMS); a lower roof
// beside the edge spreads wider and is refused. The line keeps its own direction when that
// runs within kFacadeTurn of the edge, else the edge's (a short edge of a curved facade, whose
// points give its position better than its direction). Points are
// looked for from kFacadeReach inside the edge (under eaves) to a cell outside it, over the
// edge's middle (`band`). The line is its unit direction (along the edge's) and the centre of
// its points.
constexpr double kFacadeDrop = 2.0;
constexpr double kFacadeSpread = 0.35;
constexpr double kFacadeReach = 1.5;
constexpr double kFacadeTurn = 20.0;  // degrees

struct FacadeLine {
  Vec2 dir, centre;  // a point on the line: its points' centre
};

// A point near an edge, in the outline's frame: where it lies and how far along the edge.
struct NearEdge {
  Vec2 q;
  double z = 0.0, at = 0.0;
};

std::optional<FacadeLine> facade_line(const std::vector<NearEdge>& band, const Vec2& along,
                                      double length) {
  std::map<int, double> top;  // the highest point per metre along the edge
  for (const NearEdge& p : band) {
    auto [it, fresh] = top.emplace(static_cast<int>(std::floor(p.at)), p.z);
    if (!fresh) it->second = std::max(it->second, p.z);
  }
  std::vector<Vec2> wall;
  for (const NearEdge& p : band) {
    if (p.z < top[static_cast<int>(std::floor(p.at))] - kFacadeDrop) wall.push_back(p.q);
  }
  if (wall.size() < 10 || static_cast<double>(wall.size()) < 0.7 * length) return std::nullopt;
  // The principal axis of points (centre, direction, RMS distance across).
  struct Axis {
    Vec2 centre, dir;
    double thickness = 0.0;
  };
  auto axis = [](const std::vector<Vec2>& pts) {
    Vec2 c = Vec2::Zero();
    for (const Vec2& p : pts) c += p;
    c /= static_cast<double>(pts.size());
    Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
    for (const Vec2& p : pts) cov += (p - c) * (p - c).transpose();
    cov /= static_cast<double>(pts.size());
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(cov);
    return Axis{c, eig.eigenvectors().col(1), std::sqrt(std::max(eig.eigenvalues()(0), 0.0))};
  };
  Axis a = axis(wall);
  std::vector<Vec2> kept;
  const Vec2 across(-a.dir.y(), a.dir.x());
  const double keep = std::max(2.0 * a.thickness, kFacadeSpread);
  for (const Vec2& p : wall) {
    if (std::abs((p - a.centre).dot(across)) <= keep) kept.push_back(p);
  }
  if (kept.size() < 10 || 2 * kept.size() < wall.size()) return std::nullopt;
  a = axis(kept);
  if (a.thickness > kFacadeSpread) return std::nullopt;
  Vec2 dir = a.dir.dot(along) >= 0.0 ? a.dir : Vec2(-a.dir);
  if (dir.dot(along) < std::cos(kFacadeTurn * std::numbers::pi / 180.0)) dir = along;
  return FacadeLine{dir, a.centre};
}

}  // namespace

std::optional<RoofOutline> roof_outline(const ProposalInput& in, const std::vector<Vec2>& flat,
                                        const std::function<bool(const Vec3&)>& above_roof,
                                        std::string& why, const std::vector<double>* heights) {
  const PrimitiveOptions& o = *in.options;
  const double cos_tol = std::cos(o.angle_tolerance_deg * std::numbers::pi / 180.0);
  const double spacing = in.shapes->spacing;
  if (!(spacing > 0.0)) return std::nullopt;
  // Principal frame: the smallest rectangle around the roof's hull.
  const auto frame = principal_frame(flat);
  if (!frame) return std::nullopt;
  const Vec2 u = frame->u, v = frame->v;
  const double a0 = frame->a0, a1 = frame->a1, b0 = frame->b0, b1 = frame->b1;
  if (std::min(a1 - a0, b1 - b0) < o.min_building_width) return std::nullopt;
  const double cell = 1.5 * spacing;
  const double cells = ((a1 - a0) / cell + 5.0) * ((b1 - b0) / cell + 5.0);
  if (cells > 4e6) return std::nullopt;
  const int nx = static_cast<int>((a1 - a0) / cell) + 5,
            ny = static_cast<int>((b1 - b0) / cell) + 5;
  const double ga = a0 - 2.0 * cell, gb = b0 - 2.0 * cell;  // grid origin (two empty cells)
  auto index = [&](int i, int j) {
    return static_cast<std::size_t>(j) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(i);
  };
  // Clamped in double to one cell outside the grid, so any finite point converts safely.
  auto cell_of = [&](const Vec2& p) {
    const auto to_cell = [&](double t, int n) {
      return static_cast<int>(std::clamp(std::floor(t / cell), -1.0, static_cast<double>(n)));
    };
    return std::array<int, 2>{to_cell(p.dot(u) - ga, nx), to_cell(p.dot(v) - gb, ny)};
  };
  std::vector<char> occ(static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny), 0);
  for (const auto& p : flat) {
    const auto c = cell_of(p);
    occ[index(c[0], c[1])] = 1;
  }
  const std::size_t seen_cells = static_cast<std::size_t>(std::count(occ.begin(), occ.end(), 1));
  close_cells(occ, nx, ny);  // over the gaps between scan lines
  // Empty components not reaching the border are holes: small ones (under 4 m²) and those
  // under something standing on the roof are filled.
  {
    std::vector<int> comp(occ.size(), -1);
    int next = 0;
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) {
        if (occ[index(i, j)] || comp[index(i, j)] >= 0) continue;
        std::vector<std::array<int, 2>> queue{{i, j}};
        comp[index(i, j)] = next;
        bool border = false;
        for (std::size_t h = 0; h < queue.size(); ++h) {
          const auto [ci, cj] = queue[h];
          border = border || ci == 0 || cj == 0 || ci == nx - 1 || cj == ny - 1;
          const std::array<std::array<int, 2>, 4> nb{
              {{ci + 1, cj}, {ci - 1, cj}, {ci, cj + 1}, {ci, cj - 1}}};
          for (const auto& q : nb) {
            if (q[0] < 0 || q[1] < 0 || q[0] >= nx || q[1] >= ny) continue;
            if (occ[index(q[0], q[1])] || comp[index(q[0], q[1])] >= 0) continue;
            comp[index(q[0], q[1])] = next;
            queue.push_back(q);
          }
        }
        bool fill = !border && static_cast<double>(queue.size()) * cell * cell < 4.0;
        if (!border && !fill) {
          for (std::size_t k = 0; k < in.points.size() && !fill; ++k) {
            if (!in.points[k].allFinite() || !above_roof(in.points[k])) continue;
            const auto c = cell_of(Vec2(in.points[k].x(), in.points[k].y()));
            if (c[0] >= 0 && c[1] >= 0 && c[0] < nx && c[1] < ny &&
                comp[index(c[0], c[1])] == next) {
              fill = true;
            }
          }
        }
        if (fill) {
          for (const auto& q : queue) occ[index(q[0], q[1])] = 1;
        }
        ++next;
      }
    }
  }
  const auto loops = trace(occ, nx, ny);
  // Each loop in world (a, b) coordinates, simplified, edges snapped and moved onto the
  // outermost roof points near them.
  std::vector<std::vector<Vec2>> rings;
  for (const auto& loop : loops) {
    std::vector<Vec2> ring;
    for (const auto& c : loop) ring.emplace_back(ga + c[0] * cell, gb + c[1] * cell);
    if (std::abs(ring_area(ring)) < o.min_building_width * o.min_building_width) continue;
    std::vector<char> keep(ring.size(), 0);
    std::size_t far = 0;
    for (std::size_t k = 0; k < ring.size(); ++k) {
      if ((ring[k] - ring[0]).norm() > (ring[far] - ring[0]).norm()) far = k;
    }
    keep[0] = keep[far] = 1;
    douglas_peucker(ring, 0, far, 1.0 * cell, keep);
    douglas_peucker(ring, far, 0, 1.0 * cell, keep);
    std::vector<Vec2> simple;
    for (std::size_t k = 0; k < ring.size(); ++k) {
      if (keep[k]) simple.push_back(ring[k]);
    }
    if (simple.size() < 3) continue;
    // Edge lines: direction (snapped to the frame within the angle tolerance) and offset.
    const std::size_t n = simple.size();
    std::vector<Vec2> dir(n), normal(n);
    std::vector<double> offset(n);
    const double sign = ring_area(simple) > 0.0 ? 1.0 : -1.0;  // outward = right of travel
    for (std::size_t k = 0; k < n; ++k) {
      Vec2 d = (simple[(k + 1) % n] - simple[k]).normalized();
      if (std::abs(d.x()) >= cos_tol) d = Vec2(d.x() > 0 ? 1.0 : -1.0, 0.0);
      if (std::abs(d.y()) >= cos_tol) d = Vec2(0.0, d.y() > 0 ? 1.0 : -1.0);
      dir[k] = d;
      normal[k] = sign * Vec2(d.y(), -d.x());
      const Vec2 mid = 0.5 * (simple[k] + simple[(k + 1) % n]);
      offset[k] = mid.dot(normal[k]);
      const double len = (simple[(k + 1) % n] - simple[k]).norm();
      // Roof points along the edge, within two cells inside it: the outermost (98th
      // percentile against noise) is where the roof ends.
      // With heights, the points from kFacadeReach inside it too (facade_line).
      std::vector<double> outward;
      std::vector<NearEdge> band;
      const double reach = std::max(kFacadeReach, 2.0 * cell);
      for (std::size_t i = 0; i < flat.size(); ++i) {
        const Vec2 q(flat[i].dot(u), flat[i].dot(v));
        const double along = (q - simple[k]).dot(d);
        if (along < 0.15 * len || along > 0.85 * len) continue;
        const double off = q.dot(normal[k]) - offset[k];
        if (off > cell) continue;
        if (heights != nullptr && off >= -reach && i < heights->size() &&
            std::isfinite((*heights)[i])) {
          band.push_back({q, (*heights)[i], along});
        }
        if (off >= -2.0 * cell) outward.push_back(off);
      }
      if (outward.size() >= 3) {
        std::sort(outward.begin(), outward.end());
        const double roof_end =
            outward[static_cast<std::size_t>(0.98 * static_cast<double>(outward.size() - 1))];
        const auto wall = heights != nullptr ? facade_line(band, d, len) : std::nullopt;
        // The facade where it is seen (and the roof reaches over it), else the roof's end.
        if (wall && (wall->centre - mid).dot(normal[k]) <= roof_end + 0.5 * cell) {
          Vec2 w = wall->dir;  // snapped to the frame within the angle tolerance, as edges are
          if (std::abs(w.x()) >= cos_tol) w = Vec2(w.x() > 0 ? 1.0 : -1.0, 0.0);
          if (std::abs(w.y()) >= cos_tol) w = Vec2(0.0, w.y() > 0 ? 1.0 : -1.0);
          dir[k] = w;
          normal[k] = sign * Vec2(w.y(), -w.x());
          offset[k] = wall->centre.dot(normal[k]);
        } else {
          offset[k] += roof_end;
        }
      }
    }
    // Consecutive edges along one line (a stair of the grid left by the simplification)
    // are one edge.
    for (bool merged = true; merged && dir.size() > 3;) {
      merged = false;
      for (std::size_t k = 0; k < dir.size(); ++k) {
        const std::size_t next = (k + 1) % dir.size();
        if (dir[k].dot(dir[next]) >= cos_tol && std::abs(offset[k] - offset[next]) <= cell) {
          offset[k] = 0.5 * (offset[k] + offset[next]);
          dir.erase(dir.begin() + static_cast<std::ptrdiff_t>(next));
          normal.erase(normal.begin() + static_cast<std::ptrdiff_t>(next));
          offset.erase(offset.begin() + static_cast<std::ptrdiff_t>(next));
          simple.erase(simple.begin() + static_cast<std::ptrdiff_t>(next));
          merged = true;
          break;
        }
      }
    }
    // Vertex k joins lines k - 1 and k; an edge shorter than a cell (a corner the grid cut
    // off) is dropped and its neighbours meet.
    std::vector<Vec2> refined;
    for (;;) {
      const std::size_t m = dir.size();
      refined.clear();
      for (std::size_t k = 0; k < m; ++k) {
        const std::size_t prev = (k + m - 1) % m;
        const double det = normal[prev].x() * normal[k].y() - normal[prev].y() * normal[k].x();
        if (std::abs(det) > std::sin(10.0 * std::numbers::pi / 180.0)) {
          refined.emplace_back((offset[prev] * normal[k].y() - offset[k] * normal[prev].y()) / det,
                               (normal[prev].x() * offset[k] - normal[k].x() * offset[prev]) / det);
        } else {
          const Vec2 p = simple[k];
          refined.push_back(p + (offset[k] - p.dot(normal[k])) * normal[k]);
        }
      }
      std::size_t shortest = m;
      double length = cell;
      for (std::size_t k = 0; k < m; ++k) {
        const double l = (refined[(k + 1) % m] - refined[k]).norm();
        if (l < length) {
          length = l;
          shortest = k;
        }
      }
      if (shortest == m || m <= 3) break;
      const auto at = static_cast<std::ptrdiff_t>(shortest);
      dir.erase(dir.begin() + at);
      normal.erase(normal.begin() + at);
      offset.erase(offset.begin() + at);
      simple.erase(simple.begin() + at);
    }
    // A building's outline (with heights: the partition's bounds) must not cross itself:
    // edges moved onto the outermost points or the facades can cross where the outline turns
    // back on itself (the inner corner of an L whose arms' edges meet at a grazing angle), and
    // a ring crossing itself winds around part of the building twice, which the partition
    // inside it leaves out. The corners of the edges that cross go back to the simplified
    // trace's (on the grid's lines) until none does; else the simplified trace; else no ring
    // (the partition's cells are the outline). A candidate's outline (a roof part, a flat
    // roof) stays as it is: one crossing itself is a ragged patch of points the kernel rejects.
    if (heights == nullptr) {
      rings.push_back(std::move(refined));
      continue;
    }
    const auto any = [](const std::vector<char>& flags) {
      return std::find(flags.begin(), flags.end(), 1) != flags.end();
    };
    bool crossed = false;
    for (std::size_t pass = 0;; ++pass) {
      const std::vector<char> crossing = crossing_edges(refined);
      crossed = any(crossing);
      if (!crossed || pass == refined.size()) break;
      bool moved = false;
      for (std::size_t k = 0; k < refined.size(); ++k) {
        if (!crossing[k]) continue;
        for (const std::size_t at : {k, (k + 1) % refined.size()}) {
          moved = moved || refined[at] != simple[at];
          refined[at] = simple[at];
        }
      }
      if (!moved) break;
    }
    if (!crossed) {
      rings.push_back(std::move(refined));
    } else if (!any(crossing_edges(simple))) {
      rings.push_back(std::move(simple));
    }
  }
  if (rings.empty()) {
    why = "no outline from its points";
    return std::nullopt;
  }
  std::size_t outer = 0;
  for (std::size_t r = 1; r < rings.size(); ++r) {
    if (ring_area(rings[r]) > ring_area(rings[outer])) outer = r;
  }
  std::vector<Vec2> profile = rings[outer];
  if (ring_area(profile) <= 0.0) return std::nullopt;
  std::vector<std::vector<Vec2>> holes;
  for (std::size_t r = 0; r < rings.size(); ++r) {
    if (r == outer || ring_area(rings[r]) >= 0.0) continue;
    bool inside = true;
    for (const auto& p : rings[r]) inside = inside && inside_ring(p, profile);
    if (inside) holes.push_back(rings[r]);
  }
  RoofOutline out;
  out.u = u;
  out.v = v;
  out.cell = cell;
  out.seen_cells = seen_cells;
  out.profile = std::move(profile);
  out.holes = std::move(holes);
  return out;
}

geo::FootprintPolygon outline_polygon(const RoofOutline& outline) {
  geo::FootprintPolygon out;
  auto world = [&](const Vec2& q) { return Vec2(q.x() * outline.u + q.y() * outline.v); };
  for (const auto& q : outline.profile) out.outer.push_back(world(q));
  for (const auto& hole : outline.holes) {
    auto& ring = out.holes.emplace_back();
    for (const auto& q : hole) ring.push_back(world(q));
  }
  return out;
}

OutlineGround outline_ground(const RoofOutline& outline, const GroundGrid& ground) {
  OutlineGround out;
  for (const auto& q : outline.profile) {
    out.footprint.push_back(q.x() * outline.u + q.y() * outline.v);
    out.centre += q / static_cast<double>(outline.profile.size());
  }
  out.world_centre = out.centre.x() * outline.u + out.centre.y() * outline.v;
  out.ground = lowest_ground_under(ground, out.footprint);
  if (!std::isfinite(out.ground)) {
    double radius = 0.0;
    for (const auto& q : outline.profile) radius = std::max(radius, (q - out.centre).norm());
    out.ground =
        ground.median_near(out.world_centre.x(), out.world_centre.y(), radius + 2.0 * ground.cell);
  }
  return out;
}

std::optional<kernel::PrimitiveSpec> outline_extrusion(const RoofOutline& outline,
                                                       const OutlineGround& g, double height) {
  const auto loc = place(frame_of(Vec3(outline.u.x(), outline.u.y(), 0.0), Vec3::UnitZ()),
                         Vec3(g.world_centre.x(), g.world_centre.y(), g.ground));
  if (!loc) return std::nullopt;
  kernel::PrimitiveSpec spec;
  spec.type = PrimitiveType::Extrusion;
  for (const auto& q : outline.profile) spec.profile.push_back(q - g.centre);
  for (const auto& h : outline.holes) {
    std::vector<Vec2> hole;
    for (const auto& q : h) hole.push_back(q - g.centre);
    spec.holes.push_back(std::move(hole));
  }
  spec.height = height;
  spec.placement = *loc;
  return spec;
}

std::optional<Proposal> propose_roof_extrusion(const ProposalInput& in,
                                               std::vector<Rejection>& rejected) {
  const PrimitiveOptions& o = *in.options;
  if (o.ground == nullptr) return std::nullopt;
  const auto& shapes = in.shapes->shapes;
  const double cos_tol = std::cos(o.angle_tolerance_deg * std::numbers::pi / 180.0);
  const double tight = 2.0 * in.ransac->epsilon;
  const double spacing = in.shapes->spacing;
  if (!(spacing > 0.0)) return std::nullopt;
  std::vector<int> roofs;
  for (std::size_t s = 0; s < shapes.size(); ++s) {
    if (shapes[s].surface.type == ShapeType::Plane && !(*in.absorbed)[s] &&
        std::abs(shapes[s].surface.axis.z()) >= cos_tol &&
        static_cast<long long>(shapes[s].inliers.size()) >= in.ransac->min_points) {
      roofs.push_back(static_cast<int>(s));
    }
  }
  std::stable_sort(roofs.begin(), roofs.end(), [&](int a, int b) {
    return shapes[static_cast<std::size_t>(a)].inliers.size() >
           shapes[static_cast<std::size_t>(b)].inliers.size();
  });
  long long region_points = 0;
  for (std::size_t i = 0; i < in.points.size(); ++i) {
    region_points += (!(*in.used)[i] && in.points[i].allFinite()) ? 1 : 0;
  }
  const double lambda = 0.5 * std::log2(std::max<double>(2.0, static_cast<double>(region_points)));
  const double density = 1.0 / (spacing * spacing);
  for (int roof : roofs) {
    const std::string what = "extrusion from roof plane " + std::to_string(roof);
    std::vector<std::uint32_t> pts;
    for (auto i : shapes[static_cast<std::size_t>(roof)].inliers) {
      if (!(*in.used)[i]) pts.push_back(i);
    }
    if (static_cast<long long>(pts.size()) < in.ransac->min_points) continue;
    double top = 0.0;
    std::vector<Vec2> flat;
    for (auto i : pts) {
      top += in.points[i].z();
      flat.emplace_back(in.points[i].x(), in.points[i].y());
    }
    top /= static_cast<double>(pts.size());
    std::string why;
    const auto outline = roof_outline(
        in, flat, [&](const Vec3& p) { return p.z() > top + tight; }, why);
    if (!outline) {
      if (!why.empty()) rejected.push_back({what, why, static_cast<long long>(pts.size())});
      continue;
    }
    const Vec2 u = outline->u, v = outline->v;
    const double cell = outline->cell;
    const std::size_t seen_cells = outline->seen_cells;
    const std::vector<Vec2>& profile = outline->profile;
    const std::vector<std::vector<Vec2>>& holes = outline->holes;
    if (profile.size() <= 4 && holes.empty()) continue;  // a rectangle: the box's
    // Bottom: the lowest terrain level around the footprint (the foot of a slope: walls do
    // not stop above it), else the median level near it.
    const OutlineGround under = outline_ground(*outline, *o.ground);
    const double g = under.ground;
    if (!std::isfinite(g) || top - g < o.min_building_height) continue;
    // Description lengths of the extrusion and of the box around it.
    auto dl = [&](const std::vector<Vec2>& outer_ring, const std::vector<std::vector<Vec2>>& inner,
                  std::size_t params, std::vector<std::uint32_t>* members) {
      auto distance = [&](const Vec2& q, double z) {
        const double side = boundary_distance(q, outer_ring, inner);
        const bool within = inside_polygon(q, outer_ring, inner);
        // Inside the solid (walls seen through gaps, whatever stands under the roof) or
        // beside its walls within the outline's precision (a cell) counts as explained.
        const double h = top - g;
        if (z < -tight || z > h + tight) return static_cast<double>(INFINITY);
        return within ? 0.0 : (side <= cell ? 0.0 : side);
      };
      long long explained = 0;
      for (std::uint32_t i = 0; i < in.points.size(); ++i) {
        if ((*in.used)[i] || !in.points[i].allFinite()) continue;
        const Vec3& p = in.points[i];
        const Vec2 q(Vec2(p.x(), p.y()).dot(u), Vec2(p.x(), p.y()).dot(v));
        if (distance(q, p.z() - g) <= tight) {
          ++explained;
          if (members != nullptr) members->push_back(i);
        }
      }
      // Roof the primitive claims but no roof point covers.
      const double area = polygon_area(outer_ring, inner);
      const double missing = std::max(0.0, area - static_cast<double>(seen_cells) * cell * cell);
      return static_cast<double>(region_points - explained) + missing * density +
             lambda * static_cast<double>(params);
    };
    std::vector<std::uint32_t> members;
    std::size_t vertices = profile.size();
    for (const auto& h : holes) vertices += h.size();
    const double dl_extrusion = dl(profile, holes, 2 * vertices + 7, &members);
    double ba0 = INFINITY, ba1 = -INFINITY, bb0 = INFINITY, bb1 = -INFINITY;
    for (const auto& p : profile) {
      ba0 = std::min(ba0, p.x());
      ba1 = std::max(ba1, p.x());
      bb0 = std::min(bb0, p.y());
      bb1 = std::max(bb1, p.y());
    }
    const double dl_box = dl({{ba0, bb0}, {ba1, bb0}, {ba1, bb1}, {ba0, bb1}}, {}, 9, nullptr);
    if (!(dl_extrusion < dl_box)) {
      rejected.push_back({what,
                          "the box around its outline describes the points as well (description "
                          "length " +
                              std::to_string(static_cast<long long>(dl_box)) +
                              " <= " + std::to_string(static_cast<long long>(dl_extrusion)) + ")",
                          static_cast<long long>(members.size())});
      continue;
    }
    // Placement: x along u, origin at the footprint's centre on the terrain.
    auto spec = outline_extrusion(*outline, under, top - g);
    if (!spec) continue;
    Proposal p;
    p.spec = std::move(*spec);
    // Roof and walls (the floor is never seen).
    p.area = polygon_area(profile, holes) + polygon_perimeter(profile, holes) * p.spec.height;
    p.members = std::move(members);
    // Planes whose points the extrusion explains are absorbed.
    p.shapes = planes_explained_by(in, p.members);
    p.what = what;
    return p;
  }
  return std::nullopt;
}

std::vector<int> planes_explained_by(const ProposalInput& in,
                                     const std::vector<std::uint32_t>& members) {
  const auto& shapes = in.shapes->shapes;
  std::vector<char> member(in.points.size(), 0);
  for (auto i : members) member[i] = 1;
  std::vector<int> out;
  for (std::size_t s = 0; s < shapes.size(); ++s) {
    if ((*in.absorbed)[s] || shapes[s].surface.type != ShapeType::Plane) continue;
    std::size_t n = 0;
    for (auto i : shapes[s].inliers) n += member[i] ? 1 : 0;
    if (n * 10 >= shapes[s].inliers.size() * 8) out.push_back(static_cast<int>(s));
  }
  return out;
}

}  // namespace csgtile::fit::detail
