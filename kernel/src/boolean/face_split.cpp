#include "boolean/face_split.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "boolean/tolerance.h"
#include "boolean/uv_geometry.h"
#include "csgtile/kernel/polygon2d.h"
#include "predicates/predicates.h"

namespace csgtile::kernel::detail {

namespace {

struct HalfEdge {
  BUse use;
  int from = -1, to = -1;       // nodes
  Vec2 out_dir = Vec2::Zero();  // direction leaving `from`
  Vec2 in_dir = Vec2::Zero();   // direction of the reverse leaving `to`
  bool alive = true;
  bool boundary = false;
};

double param_at(const BEdge& e, bool forward, bool at_start) {
  return (forward == at_start) ? e.t0 : e.t1;
}

// Direction in (u, v) of the use leaving its start, or of its reverse leaving its end: a
// short chord, so that tangent curves are told apart by their curvature. Directions are
// compared by angle with the exact predicates (predicates::clockwise_before).
Vec2 chord_direction(const BModel& m, const BUse& use, bool at_start) {
  const BEdge& e = m.edges[static_cast<std::size_t>(use.edge)];
  const double span = e.t1 - e.t0;
  const double t = param_at(e, use.forward, at_start);
  const double step = kLeavingChordStep * span * (((use.forward == at_start)) ? 1.0 : -1.0);
  Vec2 d = use.pcurve->point(t + step) - use.pcurve->point(t);
  if (d.norm() == 0) d = use.pcurve->derivative(t) * (step > 0 ? 1.0 : -1.0);
  return d;
}

// The points of a loop's sampled pcurves (the polygon its area and orientation are taken on).
std::vector<Vec2> loop_points(const BModel& m, const BLoop& loop) {
  std::vector<Vec2> pts;
  for (const BUse& u : loop) {
    auto s = sample_use(m, u, 64);
    pts.insert(pts.end(), s.begin(), s.end() - 1);
  }
  return pts;
}

}  // namespace

double loop_area(const BModel& m, const BLoop& loop) { return ring_area(loop_points(m, loop)); }

Result<std::vector<Region>> split_face(const BModel& m, const BFace& face) {
  std::vector<HalfEdge> half;
  for (const BLoop& loop : face.loops) {
    for (const BUse& u : loop) half.push_back({u, -1, -1, Vec2::Zero(), Vec2::Zero(), true, true});
  }
  for (const BUse& u : face.extra) {
    half.push_back({u, -1, -1, Vec2::Zero(), Vec2::Zero(), true, false});
    BUse r = u;
    r.forward = !u.forward;
    half.push_back({r, -1, -1, Vec2::Zero(), Vec2::Zero(), true, false});
  }
  // Nodes: one per (vertex, place in the (u, v) plane): a seam vertex is two nodes.
  const FacePolygon polygon = face_polygon(m, face);
  const Vec2 extent = (polygon.max - polygon.min).cwiseAbs();
  const double node_tol = kNodeUvRelative * std::max({1.0, extent.x(), extent.y()});
  struct Node {
    int vertex;
    Vec2 uv;
  };
  std::vector<Node> nodes;
  auto node_of = [&](int vertex, const Vec2& uv) {
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      if (nodes[i].vertex == vertex && (nodes[i].uv - uv).norm() <= node_tol)
        return static_cast<int>(i);
    }
    nodes.push_back({vertex, uv});
    return static_cast<int>(nodes.size()) - 1;
  };
  for (HalfEdge& h : half) {
    h.from = node_of(use_start(m, h.use), use_start_uv(m, h.use));
    h.to = node_of(use_end(m, h.use), use_end_uv(m, h.use));
    h.out_dir = chord_direction(m, h.use, true);
    h.in_dir = chord_direction(m, h.use, false);
  }
  // Section edges with a free end bound nothing: drop them (repeat: removal may free others).
  bool changed = true;
  while (changed) {
    changed = false;
    std::vector<int> degree(nodes.size(), 0);
    for (const HalfEdge& h : half) {
      if (!h.alive) continue;
      ++degree[static_cast<std::size_t>(h.from)];
      ++degree[static_cast<std::size_t>(h.to)];
    }
    for (HalfEdge& h : half) {
      if (!h.alive || h.boundary) continue;
      // A section edge contributes 2 to each end (both directions); a free end has exactly that.
      if (h.from != h.to && (degree[static_cast<std::size_t>(h.from)] <= 2 ||
                             degree[static_cast<std::size_t>(h.to)] <= 2)) {
        h.alive = false;
        changed = true;
      }
    }
  }
  std::vector<std::vector<int>> outgoing(nodes.size());
  for (std::size_t i = 0; i < half.size(); ++i) {
    if (half[i].alive)
      outgoing[static_cast<std::size_t>(half[i].from)].push_back(static_cast<int>(i));
  }
  std::vector<bool> used(half.size(), false);
  std::vector<BLoop> outers, holes;
  std::vector<double> outer_areas;
  for (std::size_t start = 0; start < half.size(); ++start) {
    if (!half[start].alive || used[start]) continue;
    BLoop cycle;
    int h = static_cast<int>(start);
    std::size_t guard = 0;
    while (!used[static_cast<std::size_t>(h)]) {
      used[static_cast<std::size_t>(h)] = true;
      const HalfEdge& cur = half[static_cast<std::size_t>(h)];
      cycle.push_back(cur.use);
      // Next: the first outgoing half-edge clockwise from the reverse of `cur` (one leaving
      // in the reverse's own direction comes last).
      int best = -1;
      for (int o : outgoing[static_cast<std::size_t>(cur.to)]) {
        const Vec2& d = half[static_cast<std::size_t>(o)].out_dir;
        if (best < 0 || predicates::clockwise_before(
                            cur.in_dir, d, half[static_cast<std::size_t>(best)].out_dir)) {
          best = o;
        }
      }
      if (best < 0 || ++guard > half.size() + 1) {
        return Error{ErrorCode::InvalidShape, "a face piece's boundary cannot be closed"};
      }
      h = best;
    }
    if (h != static_cast<int>(start)) {
      return Error{ErrorCode::InvalidShape, "face pieces' boundaries cross (open cycle)"};
    }
    // Outer or hole: the exact orientation of the sampled loop (its area for ordering).
    const std::vector<Vec2> points = loop_points(m, cycle);
    const double area = ring_area(points);
    if (predicates::polygon_orientation(points) > 0) {
      outers.push_back(std::move(cycle));
      outer_areas.push_back(area);
    } else {
      holes.push_back(std::move(cycle));
    }
  }
  std::vector<Region> regions(outers.size());
  for (std::size_t i = 0; i < outers.size(); ++i) regions[i].loops.push_back(outers[i]);
  for (BLoop& hole : holes) {
    // The smallest piece around the hole (a point of the hole, nudged inside it by nothing:
    // holes do not touch their outer loop in valid faces). A piece whose outer loop uses an
    // edge of the hole lies on the other side of that edge: the hole is the reverse of part
    // of its boundary (a lens cut off by two section edges), the probe on its outline.
    const std::vector<Vec2> pts = sample_use(m, hole.front(), 8);
    const Vec2& probe = pts[pts.size() / 2];
    int best = -1;
    for (std::size_t i = 0; i < outers.size(); ++i) {
      const bool shares_edge = std::any_of(hole.begin(), hole.end(), [&](const BUse& h) {
        return std::any_of(outers[i].begin(), outers[i].end(),
                           [&](const BUse& o) { return o.edge == h.edge; });
      });
      if (shares_edge) continue;
      // Against the piece's curved sides, not their chords: a hole can come closer to a
      // circle than its sampled polygon does (a box's corner 4 mm inside an 8 m disc).
      const FacePolygon poly = face_polygon(m, face, {outers[i]});
      auto in = poly.inside(probe, 0.0);
      if (in && *in && (best < 0 || outer_areas[i] < outer_areas[static_cast<std::size_t>(best)])) {
        best = static_cast<int>(i);
      }
    }
    if (best < 0) return Error{ErrorCode::InvalidShape, "a hole of a face piece lies outside it"};
    regions[static_cast<std::size_t>(best)].loops.push_back(std::move(hole));
  }
  return regions;
}

}  // namespace csgtile::kernel::detail
