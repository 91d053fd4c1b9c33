#include "mesh/face_mesher.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <set>
#include <string>
#include <unordered_map>

#include "mesh/polygon_triangulation.h"
#include "mesh/sampling.h"

namespace csgtile::kernel::detail {

void add_triangle(const std::vector<Vec3>& vertices, std::vector<Triangle>& triangles,
                  std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  if (a == b || b == c || a == c) return;
  const Vec3 n = (vertices[b] - vertices[a]).cross(vertices[c] - vertices[a]);
  if (!(n.squaredNorm() > 0.0)) return;
  triangles.push_back({a, b, c});
}

namespace {

// ---- row method --------------------------------------------------------------------------

// The four sides of a rectangular domain, each ordered by increasing u (bottom, top) or
// increasing v (left, right).
struct RectangularDomain {
  std::vector<BoundaryPoint> bottom, right, top, left;
};

enum class Side { Bottom = 0, Right = 1, Top = 2, Left = 3 };

// Direction of an edge use that runs parallel to an axis, monotonically; nullopt otherwise.
std::optional<Side> axis_side(const std::vector<BoundaryPoint>& use, double eps) {
  if (use.size() < 2) return std::nullopt;
  const Vec2 d = use.back().uv - use.front().uv;
  int axis;  // the coordinate that changes
  if (std::abs(d.y()) <= eps && std::abs(d.x()) > eps) {
    axis = 0;
  } else if (std::abs(d.x()) <= eps && std::abs(d.y()) > eps) {
    axis = 1;
  } else {
    return std::nullopt;
  }
  const int fixed = 1 - axis;
  const double sense = d[axis] > 0 ? 1.0 : -1.0;
  for (std::size_t i = 0; i < use.size(); ++i) {
    if (std::abs(use[i].uv[fixed] - use.front().uv[fixed]) > eps) return std::nullopt;
    if (i > 0 && !(sense * (use[i].uv[axis] - use[i - 1].uv[axis]) > 0)) return std::nullopt;
  }
  if (axis == 0) return sense > 0 ? Side::Bottom : Side::Top;
  return sense > 0 ? Side::Right : Side::Left;
}

std::optional<RectangularDomain> rectangular_domain(const FaceLoops& loops) {
  if (loops.size() != 1 || loops[0].size() < 4) return std::nullopt;
  const auto& uses = loops[0];
  const std::size_t n = uses.size();
  Vec2 lo = Vec2::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const auto& use : uses) {
    for (const BoundaryPoint& p : use) {
      lo = lo.cwiseMin(p.uv);
      hi = hi.cwiseMax(p.uv);
    }
  }
  const double eps = 1e-9 * std::max(1.0, (hi - lo).maxCoeff());
  std::vector<Side> sides;
  for (std::size_t i = 0; i < n; ++i) {
    const auto side = axis_side(uses[i], eps);
    if (!side) return std::nullopt;
    const auto& next = uses[(i + 1) % n];
    if (uses[i].back().id != next.front().id ||
        (uses[i].back().uv - next.front().uv).norm() > eps) {
      return std::nullopt;
    }
    sides.push_back(*side);
  }
  // Start at the first use of the bottom side, then collect the sides in loop order.
  std::size_t start = n;
  for (std::size_t i = 0; i < n; ++i) {
    if (sides[i] == Side::Bottom && sides[(i + n - 1) % n] != Side::Bottom) {
      start = i;
      break;
    }
  }
  if (start == n) return std::nullopt;
  std::vector<std::pair<Side, std::vector<BoundaryPoint>>> groups;
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t i = (start + k) % n;
    if (groups.empty() || groups.back().first != sides[i]) {
      groups.emplace_back(sides[i], uses[i]);
    } else {
      auto& points = groups.back().second;
      points.insert(points.end(), uses[i].begin() + 1, uses[i].end());
    }
  }
  if (groups.size() != 4) return std::nullopt;
  for (int g = 0; g < 4; ++g) {
    if (groups[static_cast<std::size_t>(g)].first != static_cast<Side>(g)) return std::nullopt;
  }
  RectangularDomain domain{std::move(groups[0].second), std::move(groups[1].second),
                           std::move(groups[2].second), std::move(groups[3].second)};
  std::reverse(domain.top.begin(), domain.top.end());
  std::reverse(domain.left.begin(), domain.left.end());
  // Rows join left and right points at the same v: both sides must be sampled alike.
  if (domain.left.size() != domain.right.size()) return std::nullopt;
  for (std::size_t j = 0; j < domain.left.size(); ++j) {
    if (std::abs(domain.left[j].uv.y() - domain.right[j].uv.y()) > eps) return std::nullopt;
  }
  return domain;
}

// Joins two rows (lower at smaller v, both ordered by u over the same range) into a strip of
// counter-clockwise triangles, advancing on whichever row's next point comes first in u.
void zip_rows(const std::vector<BoundaryPoint>& lower, const std::vector<BoundaryPoint>& upper,
              const std::vector<Vec3>& vertices, std::vector<Triangle>& triangles) {
  std::size_t i = 0, j = 0;
  while (i + 1 < lower.size() || j + 1 < upper.size()) {
    bool advance_lower;
    if (i + 1 == lower.size()) {
      advance_lower = false;
    } else if (j + 1 == upper.size()) {
      advance_lower = true;
    } else {
      const double next_lower = lower[i + 1].uv.x(), next_upper = upper[j + 1].uv.x();
      advance_lower = next_lower < next_upper ||
                      (next_lower == next_upper && lower[i].uv.x() <= upper[j].uv.x());
    }
    if (advance_lower) {
      add_triangle(vertices, triangles, lower[i].id, lower[i + 1].id, upper[j].id);
      ++i;
    } else {
      add_triangle(vertices, triangles, lower[i].id, upper[j + 1].id, upper[j].id);
      ++j;
    }
  }
}

// ---- general method ----------------------------------------------------------------------

constexpr int kMaxRefinementPasses = 32;
constexpr double kStraightColumnShrink = 0.05;
constexpr std::size_t kMaxLocalPoints = std::size_t{1} << 21;
constexpr std::uint32_t kNoId = std::numeric_limits<std::uint32_t>::max();

double orient(const Vec2& a, const Vec2& b, const Vec2& c) {
  return (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
}

// A triangulation of the face domain being refined. Points are local; boundary points carry
// their mesh vertex, interior ones get theirs when the face is emitted.
class DomainRefiner {
 public:
  explicit DomainRefiner(const FaceGeometry& geometry) : geometry_(geometry) {}

  Status run(const FaceLoops& loops, std::vector<Vec3>& vertices, std::vector<Triangle>& out) {
    std::vector<std::vector<Vec2>> polygon;
    for (const auto& wire : loops) {
      std::vector<Vec2> ring;
      boundary_.emplace_back();
      for (const auto& use : wire) {
        for (std::size_t i = 0; i + 1 < use.size(); ++i) {
          boundary_.back().push_back(static_cast<int>(uv_.size()));
          ring.push_back(use[i].uv);
          uv_.push_back(use[i].uv);
          xyz_.push_back(vertices[use[i].id]);
          id_.push_back(use[i].id);
        }
      }
      polygon.push_back(std::move(ring));
    }
    const PolygonTriangulation triangulation = triangulate_polygon(polygon);
    if (!triangulation.complete) {
      return Error{ErrorCode::DegenerateGeometry,
                   "the face boundary has no area or overlaps itself in its parameter plane"};
    }
    for (const auto& t : triangulation.triangles) {
      add({static_cast<int>(t[0]), static_cast<int>(t[1]), static_cast<int>(t[2])});
    }
    if (geometry_.surface->kind() != SurfaceKind::Plane) {
      refine();
      repair_flat_triangles();
    }
    for (std::size_t t = 0; t < triangles_.size(); ++t) {
      if (!alive_[t]) continue;
      std::array<std::uint32_t, 3> ids{};
      for (int k = 0; k < 3; ++k) {
        const auto p = static_cast<std::size_t>(triangles_[t][static_cast<std::size_t>(k)]);
        if (id_[p] == kNoId) {
          id_[p] = static_cast<std::uint32_t>(vertices.size());
          vertices.push_back(xyz_[p]);
        }
        ids[static_cast<std::size_t>(k)] = id_[p];
      }
      add_triangle(vertices, out, ids[0], ids[1], ids[2]);
    }
    return {};
  }

 private:
  using Tri = std::array<int, 3>;

  static std::uint64_t key(int a, int b) {
    return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) |
           static_cast<std::uint32_t>(b);
  }
  bool has_edge(int a, int b) const { return edges_.count(key(a, b)) > 0; }

  void add(const Tri& t) {
    const int index = static_cast<int>(triangles_.size());
    triangles_.push_back(t);
    alive_.push_back(1);
    for (int k = 0; k < 3; ++k)
      edges_[key(t[static_cast<std::size_t>(k)], t[static_cast<std::size_t>((k + 1) % 3)])] = index;
  }
  void remove(int index) {
    const Tri& t = triangles_[static_cast<std::size_t>(index)];
    alive_[static_cast<std::size_t>(index)] = 0;
    for (int k = 0; k < 3; ++k)
      edges_.erase(key(t[static_cast<std::size_t>(k)], t[static_cast<std::size_t>((k + 1) % 3)]));
  }
  // The vertex of triangle `index` opposite its directed edge (a, b).
  int third(int index, int a, int b) const {
    const Tri& t = triangles_[static_cast<std::size_t>(index)];
    for (int v : t) {
      if (v != a && v != b) return v;
    }
    return -1;
  }
  int add_point(const Vec2& uv) {
    uv_.push_back(uv);
    xyz_.push_back(geometry_.point(uv));
    id_.push_back(kNoId);
    return static_cast<int>(uv_.size() - 1);
  }
  // Two local points that are one mesh point (a seam's two sides, a pole).
  bool coincide(int a, int b) const {
    const auto i = static_cast<std::size_t>(a), j = static_cast<std::size_t>(b);
    return (id_[i] != kNoId && id_[i] == id_[j]) || xyz_[i] == xyz_[j];
  }

  void refine() {
    Vec2 lo = Vec2::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (const Vec2& p : uv_) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    const Vec2 centre = 0.5 * (lo + hi);
    const double su = geometry_.surface->du(centre.x(), centre.y()).norm();
    const double sv = geometry_.surface->dv(centre.x(), centre.y()).norm();
    if (su > 0 && sv > 0 && std::isfinite(su) && std::isfinite(sv)) metric_ = Vec2(su, sv);
    // On a surface straight along v (cylinder, cone, extrusion) the error of a triangle only
    // depends on its extent in u: shrinking v in the flip metric makes Delaunay join points
    // nearest in u, as the row method's strips do, instead of splitting across.
    const double v_step = column_step(lo, hi);
    if (!(v_step < hi.y() - lo.y())) metric_.y() *= kStraightColumnShrink;
    make_delaunay();
    seed_interior(lo, hi, v_step);
    for (int pass = 0; pass < kMaxRefinementPasses; ++pass) {
      const std::vector<std::pair<int, int>> marked = marked_edges();
      if (marked.empty()) break;
      // Splits only disturb the Delaunay property next to them: re-check the outer edges of
      // each split quadrilateral.
      std::vector<std::pair<int, int>> around;
      for (const auto& [a, b] : marked) {
        if (uv_.size() >= kMaxLocalPoints) return;
        split(a, b, around);
      }
      flip_until_delaunay(std::move(around));
    }
  }

  // A triangle valid in (u, v) can be flat in space when a corner is a singular point (a
  // cone apex or a pole: one point for a whole side of the domain) and the other two lie on
  // one generatrix through it. Dropping it would leave a crack, so it is flipped with its
  // neighbour across its longest side (which holds the third corner): the two triangles
  // that replace them are not flat, and the boundary of the pair is unchanged. The (u, v)
  // triangulation may stop being valid; only the spatial mesh is used from here on.
  void repair_flat_triangles() {
    for (int pass = 0; pass < 4; ++pass) {
      bool changed = false;
      for (std::size_t t = 0; t < triangles_.size(); ++t) {
        if (!alive_[t]) continue;
        const Tri tri = triangles_[t];
        if (coincide(tri[0], tri[1]) || coincide(tri[1], tri[2]) || coincide(tri[2], tri[0]))
          continue;
        const Vec3& p0 = xyz_[static_cast<std::size_t>(tri[0])];
        const Vec3& p1 = xyz_[static_cast<std::size_t>(tri[1])];
        const Vec3& p2 = xyz_[static_cast<std::size_t>(tri[2])];
        if ((p1 - p0).cross(p2 - p0).squaredNorm() > 0.0) continue;
        std::size_t longest = 0;
        double length = -1.0;
        for (std::size_t k = 0; k < 3; ++k) {
          const double l = (xyz_[static_cast<std::size_t>(tri[k])] -
                            xyz_[static_cast<std::size_t>(tri[(k + 1) % 3])])
                               .squaredNorm();
          if (l > length) {
            length = l;
            longest = k;
          }
        }
        const int x = tri[longest], y = tri[(longest + 1) % 3], z = tri[(longest + 2) % 3];
        const auto twin = edges_.find(key(y, x));
        if (twin == edges_.end()) continue;
        const int w = third(twin->second, y, x);
        if (w == z || has_edge(w, z) || has_edge(z, w)) continue;
        remove(twin->second);
        remove(static_cast<int>(t));
        add({x, w, z});
        add({w, y, z});
        changed = true;
      }
      if (!changed) return;
    }
  }

  double midpoint_error(int a, int b) const {
    const auto i = static_cast<std::size_t>(a), j = static_cast<std::size_t>(b);
    return (geometry_.point(0.5 * (uv_[i] + uv_[j])) - 0.5 * (xyz_[i] + xyz_[j])).norm();
  }

  // Interior edges to split: those whose midpoint is off the surface by more than the
  // budget, and for a triangle whose centre is off, its interior edge whose midpoint is
  // farthest off (the longest among equals). Edges already shorter than the budget are
  // left alone: splitting them cannot help (slivers along the boundary). Sorted and
  // unique, so passes are deterministic.
  std::vector<std::pair<int, int>> marked_edges() const {
    std::set<std::pair<int, int>> marked;
    for (std::size_t t = 0; t < triangles_.size(); ++t) {
      if (!alive_[t]) continue;
      const Tri& tri = triangles_[t];
      if (coincide(tri[0], tri[1]) || coincide(tri[1], tri[2]) || coincide(tri[2], tri[0]))
        continue;
      bool any = false;
      int pick = -1;
      double pick_error = -1.0, pick_length = -1.0;
      for (std::size_t k = 0; k < 3; ++k) {
        const int a = tri[k], b = tri[(k + 1) % 3];
        if (!has_edge(b, a)) continue;  // boundary edges stay as the edges made them
        const double length =
            (xyz_[static_cast<std::size_t>(a)] - xyz_[static_cast<std::size_t>(b)]).norm();
        if (!(length > geometry_.chordal)) continue;
        const double error = midpoint_error(a, b);
        if (error > geometry_.chordal) {
          marked.emplace(std::min(a, b), std::max(a, b));
          any = true;
        }
        if (error > pick_error || (error == pick_error && length > pick_length)) {
          pick_error = error;
          pick_length = length;
          pick = static_cast<int>(k);
        }
      }
      if (any || pick < 0) continue;
      const auto p0 = static_cast<std::size_t>(tri[0]), p1 = static_cast<std::size_t>(tri[1]),
                 p2 = static_cast<std::size_t>(tri[2]);
      const Vec2 centre_uv = (uv_[p0] + uv_[p1] + uv_[p2]) / 3.0;
      const Vec3 centre = (xyz_[p0] + xyz_[p1] + xyz_[p2]) / 3.0;
      const bool bad = (geometry_.point(centre_uv) - centre).norm() > geometry_.chordal;
      if (bad) {
        const int a = tri[static_cast<std::size_t>(pick)];
        const int b = tri[static_cast<std::size_t>((pick + 1) % 3)];
        marked.emplace(std::min(a, b), std::max(a, b));
      }
    }
    return {marked.begin(), marked.end()};
  }

  // Splits interior edge (a, b) at its midpoint and appends the outer edges of its two
  // triangles to `around`.
  void split(int a, int b, std::vector<std::pair<int, int>>& around) {
    const auto first = edges_.find(key(a, b));
    const auto second = edges_.find(key(b, a));
    if (first == edges_.end() || second == edges_.end()) return;
    const int c = third(first->second, a, b), d = third(second->second, b, a);
    split_at(a, b, 0.5 * (uv_[static_cast<std::size_t>(a)] + uv_[static_cast<std::size_t>(b)]));
    around.insert(around.end(), {{b, c}, {c, a}, {a, d}, {d, b}});
  }

  // Splits interior edge (a, b) at a point of it; returns the new point or -1 (a boundary
  // edge).
  int split_at(int a, int b, const Vec2& uv) {
    const auto first = edges_.find(key(a, b));
    const auto second = edges_.find(key(b, a));
    if (first == edges_.end() || second == edges_.end()) return -1;
    const int t1 = first->second, t2 = second->second;
    const int c = third(t1, a, b), d = third(t2, b, a);
    const int m = add_point(uv);
    remove(t1);
    remove(t2);
    add({a, m, c});
    add({m, b, c});
    add({b, m, d});
    add({m, a, d});
    return m;
  }

  // Triangle containing p, found by walking from `hint` towards p, else by a scan (a
  // concave boundary can block the walk); -1 when p is outside the domain.
  int locate(const Vec2& p, int hint) const {
    int t = hint;
    if (t < 0 || !alive_[static_cast<std::size_t>(t)]) {
      t = static_cast<int>(std::find(alive_.begin(), alive_.end(), 1) - alive_.begin());
    }
    const std::size_t max_steps = triangles_.size();
    for (std::size_t step = 0; step < max_steps && t < static_cast<int>(triangles_.size());
         ++step) {
      const Tri& tri = triangles_[static_cast<std::size_t>(t)];
      int next = -1;
      for (std::size_t i = 0; i < 3; ++i) {
        const std::size_t k = (i + step) % 3;  // rotating the first edge avoids walk cycles
        const int a = tri[k], b = tri[(k + 1) % 3];
        if (orient(uv_[static_cast<std::size_t>(a)], uv_[static_cast<std::size_t>(b)], p) < 0) {
          const auto twin = edges_.find(key(b, a));
          next = twin == edges_.end() ? -2 : twin->second;
          break;
        }
      }
      if (next == -1) return t;
      if (next == -2) break;
      t = next;
    }
    for (std::size_t u = 0; u < triangles_.size(); ++u) {
      if (!alive_[u]) continue;
      const Tri& tri = triangles_[u];
      bool inside = true;
      for (std::size_t k = 0; k < 3 && inside; ++k) {
        inside = orient(uv_[static_cast<std::size_t>(tri[k])],
                        uv_[static_cast<std::size_t>(tri[(k + 1) % 3])], p) >= 0;
      }
      if (inside) return static_cast<int>(u);
    }
    return -1;
  }

  // Inserts a point into the triangulation and restores the Delaunay property around it.
  // Returns false when p is outside the domain or on a boundary edge.
  bool insert(const Vec2& p, int& hint) {
    const int t = locate(p, hint);
    if (t < 0) return false;
    const Tri tri = triangles_[static_cast<std::size_t>(t)];
    std::array<double, 3> side{};
    for (std::size_t k = 0; k < 3; ++k) {
      side[k] = orient(uv_[static_cast<std::size_t>(tri[k])],
                       uv_[static_cast<std::size_t>(tri[(k + 1) % 3])], p);
    }
    const double area = side[0] + side[1] + side[2];
    const auto k =
        static_cast<std::size_t>(std::min_element(side.begin(), side.end()) - side.begin());
    std::vector<std::pair<int, int>> stack;
    if (side[k] <= 1e-9 * area) {
      // On an edge: split it so that no triangle has zero area.
      const int a = tri[k], b = tri[(k + 1) % 3];
      const int c = tri[(k + 2) % 3];
      const auto twin = edges_.find(key(b, a));
      if (twin == edges_.end()) return false;
      const int d = third(twin->second, b, a);
      if (split_at(a, b, p) < 0) return false;
      stack = {{b, c}, {c, a}, {a, d}, {d, b}};
    } else {
      const int m = add_point(p);
      remove(t);
      add({tri[0], tri[1], m});
      add({tri[1], tri[2], m});
      add({tri[2], tri[0], m});
      stack = {{tri[0], tri[1]}, {tri[1], tri[2]}, {tri[2], tri[0]}};
    }
    flip_until_delaunay(std::move(stack));
    // The newest live triangle is next to the new point, and so to the next one in a row.
    hint = static_cast<int>(triangles_.size()) - 1;
    while (hint > 0 && !alive_[static_cast<std::size_t>(hint)]) --hint;
    return true;
  }

  // Distance from p to the domain boundary, with (u, v) scaled by the surface's speeds at p.
  double boundary_distance(const Vec2& p, const Vec2& speeds) const {
    double best = std::numeric_limits<double>::infinity();
    const Vec2 q = p.cwiseProduct(speeds);
    for (const auto& loop : boundary_) {
      for (std::size_t i = 0; i < loop.size(); ++i) {
        const Vec2 a = uv_[static_cast<std::size_t>(loop[i])].cwiseProduct(speeds);
        const Vec2 b =
            uv_[static_cast<std::size_t>(loop[(i + 1) % loop.size()])].cwiseProduct(speeds);
        const Vec2 d = b - a;
        const double len2 = d.squaredNorm();
        const double s = len2 > 0 ? std::clamp((q - a).dot(d) / len2, 0.0, 1.0) : 0.0;
        best = std::min(best, (a + s * d - q).norm());
      }
    }
    return best;
  }

  bool inside_domain(const Vec2& p) const {
    bool inside = false;
    for (const auto& loop : boundary_) {
      for (std::size_t i = 0, j = loop.size() - 1; i < loop.size(); j = i++) {
        const Vec2& a = uv_[static_cast<std::size_t>(loop[i])];
        const Vec2& b = uv_[static_cast<std::size_t>(loop[j])];
        if ((a.y() > p.y()) != (b.y() > p.y()) &&
            p.x() < (b.x() - a.x()) * (p.y() - a.y()) / (b.y() - a.y()) + a.x()) {
          inside = !inside;
        }
      }
    }
    return inside;
  }

  // Interior points on rows of constant v, each direction spaced for half the budget (their
  // errors add on doubly curved surfaces), each row sampled for its own curvature as in the
  // row method. Inserted before refinement, they give triangles close to the size they need
  // and well shaped; points closer to the boundary than half a spacing are left out.
  // Largest v step over the domain's columns u = const, for half the budget.
  double column_step(const Vec2& lo, const Vec2& hi) const {
    const Surface& surface = *geometry_.surface;
    const double half = 0.5 * geometry_.chordal / geometry_.location.scale();  // body units
    const double span_u = hi.x() - lo.x(), span_v = hi.y() - lo.y();
    const double h = 1e-5 * std::max(1.0, span_v);
    double step = span_v;
    for (int k = 0; k <= 16; ++k) {
      const double u = lo.x() + span_u * k / 16;
      step = std::min(step, uniform_step(
                                [&](double v) {
                                  const Vec3 d2 =
                                      (surface.dv(u, v + h) - surface.dv(u, v - h)) / (2.0 * h);
                                  return std::make_pair(surface.dv(u, v), d2);
                                },
                                lo.y(), hi.y(), half, geometry_.angular));
    }
    return step;
  }

  void seed_interior(const Vec2& lo, const Vec2& hi, double v_step) {
    const Surface& surface = *geometry_.surface;
    const double half = 0.5 * geometry_.chordal / geometry_.location.scale();  // body units
    const double span_u = hi.x() - lo.x(), span_v = hi.y() - lo.y();
    if (!(span_u > 0) || !(span_v > 0)) return;
    const std::size_t rows = segments_for(span_v, v_step);
    // Rows coarse to fine (every 2^k-th row, then the ones halfway between, …): each row
    // then splits triangles no taller than a few rows, which keeps flip cascades short.
    std::vector<std::size_t> order;
    std::size_t stride = 1;
    while (stride * 2 < rows) stride *= 2;
    for (; stride > 0; stride /= 2) {
      for (std::size_t j = stride; j < rows; j += stride) {
        if (j % (2 * stride) != 0 || 2 * stride >= rows) order.push_back(j);
      }
    }
    int hint = -1;
    for (const std::size_t j : order) {
      const double v = lo.y() + span_v * static_cast<double>(j) / static_cast<double>(rows);
      const std::size_t columns =
          segments_for(span_u, row_step(surface, v, lo.x(), hi.x(), half, geometry_.angular));
      if (columns == 0) return;
      for (std::size_t i = 1; i < columns; ++i) {
        if (uv_.size() >= kMaxLocalPoints / 2) return;
        const Vec2 p(lo.x() + span_u * static_cast<double>(i) / static_cast<double>(columns), v);
        if (!inside_domain(p)) continue;
        const Vec2 speeds(surface.du(p.x(), p.y()).norm(), surface.dv(p.x(), p.y()).norm());
        const double spacing = std::min(speeds.x() * span_u / static_cast<double>(columns),
                                        speeds.y() * span_v / static_cast<double>(rows));
        if (boundary_distance(p, speeds) < 0.5 * spacing) continue;
        insert(p, hint);
      }
    }
  }

  Vec2 metric(int p) const { return uv_[static_cast<std::size_t>(p)].cwiseProduct(metric_); }

  // Flips interior edge (a, b) of triangles (a, b, c) and (b, a, d) to (c, d) when d lies
  // inside the circumcircle of (a, b, c) and the quadrilateral is convex, both in (u, v)
  // scaled by the surface's speeds at the domain centre (so that Delaunay there is close
  // to Delaunay on the surface, and flips terminate: it is a planar triangulation).
  bool try_flip(int a, int b) {
    const auto first = edges_.find(key(a, b));
    const auto second = edges_.find(key(b, a));
    if (first == edges_.end() || second == edges_.end()) return false;
    const int t1 = first->second, t2 = second->second;
    const int c = third(t1, a, b), d = third(t2, b, a);
    if (c == d || coincide(c, d) || has_edge(c, d) || has_edge(d, c)) return false;
    const Vec2 pa = metric(a), pb = metric(b), pc = metric(c), pd = metric(d);
    if (!(orient(pa, pd, pc) > 0) || !(orient(pd, pb, pc) > 0)) return false;
    const Vec2 da = pa - pd, db = pb - pd, dc = pc - pd;
    const double la = da.squaredNorm(), lb = db.squaredNorm(), lc = dc.squaredNorm();
    const double det = da.x() * (db.y() * lc - lb * dc.y()) - da.y() * (db.x() * lc - lb * dc.x()) +
                       la * (db.x() * dc.y() - db.y() * dc.x());
    const double scale = std::abs(da.x()) * (std::abs(db.y()) * lc + lb * std::abs(dc.y())) +
                         std::abs(da.y()) * (std::abs(db.x()) * lc + lb * std::abs(dc.x())) +
                         la * (std::abs(db.x() * dc.y()) + std::abs(db.y() * dc.x()));
    if (!(det > 1e-12 * scale)) return false;
    remove(t1);
    remove(t2);
    add({a, d, c});
    add({d, b, c});
    return true;
  }

  // Lawson's algorithm: flip non-Delaunay edges until none is left, re-examining the four
  // outer edges of each flipped quadrilateral. Terminates (each flip raises the sorted
  // angle vector); the cap only guards against rounding cycles.
  void make_delaunay() {
    std::vector<std::pair<int, int>> stack;
    for (std::size_t t = 0; t < triangles_.size(); ++t) {
      if (!alive_[t]) continue;
      const Tri& tri = triangles_[t];
      for (std::size_t k = 0; k < 3; ++k) {
        if (tri[k] < tri[(k + 1) % 3]) stack.emplace_back(tri[k], tri[(k + 1) % 3]);
      }
    }
    flip_until_delaunay(std::move(stack));
  }

  void flip_until_delaunay(std::vector<std::pair<int, int>> stack) {
    std::size_t budget = 64 * triangles_.size() + 1024;
    while (!stack.empty() && budget > 0) {
      const auto [a, b] = stack.back();
      stack.pop_back();
      const auto first = edges_.find(key(a, b));
      const auto second = edges_.find(key(b, a));
      if (first == edges_.end() || second == edges_.end()) continue;
      const int c = third(first->second, a, b), d = third(second->second, b, a);
      if (!try_flip(a, b)) continue;
      --budget;
      stack.emplace_back(a, d);
      stack.emplace_back(d, b);
      stack.emplace_back(b, c);
      stack.emplace_back(c, a);
    }
  }

  const FaceGeometry& geometry_;
  std::vector<Vec2> uv_;
  std::vector<Vec3> xyz_;
  std::vector<std::uint32_t> id_;
  std::vector<std::vector<int>> boundary_;  // local points of each boundary loop
  std::vector<Tri> triangles_;
  std::vector<char> alive_;
  std::unordered_map<std::uint64_t, int> edges_;  // directed edge -> triangle; lookups only
  Vec2 metric_ = Vec2(1.0, 1.0);
};

}  // namespace

Result<bool> mesh_rectangular_face(const FaceGeometry& geometry, const FaceLoops& loops,
                                   std::vector<Vec3>& vertices, std::vector<Triangle>& triangles) {
  const std::optional<RectangularDomain> domain = rectangular_domain(loops);
  if (!domain) return false;
  const double u0 = domain->left.front().uv.x(), u1 = domain->right.front().uv.x();
  const double chordal_body = geometry.chordal / geometry.location.scale();
  const std::size_t last = domain->left.size() - 1;
  std::vector<BoundaryPoint> lower = domain->bottom;
  for (std::size_t j = 1; j <= last; ++j) {
    std::vector<BoundaryPoint> upper;
    if (j == last) {
      upper = domain->top;
    } else {
      const double v = domain->left[j].uv.y();
      const std::size_t n =
          row_segment_count(*geometry.surface, v, u0, u1, chordal_body, geometry.angular);
      if (n == 0) {
        return Error{ErrorCode::InvalidArgument,
                     "the chordal tolerance needs too many points on a row of a face"};
      }
      upper.push_back(domain->left[j]);
      for (std::size_t i = 1; i < n; ++i) {
        const double u = u0 + (u1 - u0) * static_cast<double>(i) / static_cast<double>(n);
        upper.push_back({Vec2(u, v), static_cast<std::uint32_t>(vertices.size())});
        vertices.push_back(geometry.point(Vec2(u, v)));
      }
      upper.push_back(domain->right[j]);
    }
    zip_rows(lower, upper, vertices, triangles);
    lower = std::move(upper);
  }
  return true;
}

Status mesh_general_face(const FaceGeometry& geometry, const FaceLoops& loops,
                         std::vector<Vec3>& vertices, std::vector<Triangle>& triangles) {
  return DomainRefiner(geometry).run(loops, vertices, triangles);
}

}  // namespace csgtile::kernel::detail
