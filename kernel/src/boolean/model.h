#pragma once
// The Boolean engine's working model: an operand's faces in world coordinates, with edges
// and vertices shared by index, so that splitting an edge splits it for every face using it.

#include <map>
#include <optional>
#include <unordered_map>
#include <vector>

#include "boolean/cell_hash.h"
#include "csgtile/kernel/bounding_box.h"
#include "csgtile/kernel/shape.h"

namespace csgtile::kernel::detail {

struct BVertex {
  Vec3 point;
  double tolerance;
};

struct BEdge {
  CurvePtr curve;  // null for a degenerate edge
  double t0 = 0.0, t1 = 0.0;
  int v0 = -1, v1 = -1;
  double tolerance = 0.0;
  bool degenerate() const { return curve == nullptr; }
  // Where other geometry ends on this edge: (parameter, vertex), applied by split_edges().
  std::vector<std::pair<double, int>> splits;
  bool seam = false;  // used twice by one face (a periodic surface's seam)
};

struct BUse {
  int edge;
  bool forward;
  Curve2dPtr pcurve;  // parametrised like the edge's curve
};

using BLoop = std::vector<BUse>;

struct BFace {
  SurfacePtr surface;
  bool reversed = false;  // outward side is −normal
  std::vector<BLoop> loops;
  int operand = 0;  // 0 = first argument, 1 = second
  int source = 0;   // index of the face in its operand (child-map order)
  BoundingBox box;
  std::vector<BUse> extra;  // section edges inside the face (used in both directions)
};

class BModel {
 public:
  explicit BModel(double tolerance) : tolerance_(tolerance) {}
  double tolerance() const { return tolerance_; }

  /// Index of the vertex at `p` (an existing one within tolerance, else a new one).
  int vertex_at(const Vec3& p);
  int add_edge(BEdge edge) {
    edges.push_back(std::move(edge));
    return static_cast<int>(edges.size()) - 1;
  }

  std::vector<BVertex> vertices;
  std::vector<BEdge> edges;
  std::vector<BFace> faces;

 private:
  double tolerance_;
  std::unordered_map<long long, std::vector<int>> grid_;
  long long cell_key(long long x, long long y, long long z) const { return cell_hash(x, y, z); }
};

/// Start / end vertex of a use, following its direction.
inline int use_start(const BModel& m, const BUse& u) {
  return u.forward ? m.edges[u.edge].v0 : m.edges[u.edge].v1;
}
inline int use_end(const BModel& m, const BUse& u) {
  return u.forward ? m.edges[u.edge].v1 : m.edges[u.edge].v0;
}
/// (u, v) at the start / end of a use.
inline Vec2 use_start_uv(const BModel& m, const BUse& u) {
  const BEdge& e = m.edges[u.edge];
  return u.pcurve->point(u.forward ? e.t0 : e.t1);
}
inline Vec2 use_end_uv(const BModel& m, const BUse& u) {
  const BEdge& e = m.edges[u.edge];
  return u.pcurve->point(u.forward ? e.t1 : e.t0);
}

/// Adds the faces of `shape` (solids, compsolids or compounds of them) as operand
/// `operand`, with world geometry and refitted pcurves. Errors: InvalidArgument (no solids),
/// Unsupported (a pcurve that cannot be expressed exactly in the world frame).
Status import_operand(BModel& model, const Shape& shape, int operand);

}  // namespace csgtile::kernel::detail
