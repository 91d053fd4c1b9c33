#pragma once
/// \file
/// Exact classification of points against a closed region bounded by faces (paper §4.2's
/// "classify each piece as in / out / on the other solid"). Private to the Boolean unit.

#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include "csgtile/kernel/bounding_box.h"
#include "csgtile/kernel/shape.h"

namespace csgtile::kernel::detail {

/// Where a point lies with respect to a region (or a face's parameter domain).
enum class Containment { Inside, Outside, OnBoundary };

/// "inside", "outside", "on_boundary".
const char* containment_name(Containment c);

/// One face prepared for queries: its surface, its (u, v) boundary loops, its outward side.
///
/// The surface and the parameters stay those of the face body (the location is applied to
/// points instead): transforming the surface would rescale its length parameters and no
/// longer match the pcurves. The boundary loops come from the pcurves walked with the edge
/// orientations of the face body (outer loop counter-clockwise, holes clockwise). A loop is
/// kept as chords of its pcurves with a rigorous bound on how far each arc bulges from its
/// chord; a query refines only the arcs whose bulge could hide the answer, so point-in-face is
/// exact up to rounding whatever the number of initial samples. Consecutive pcurves that do
/// not quite meet are blended linearly into each other (a correction as small as the gap,
/// with no effect on the bulge bound); pcurves written in another period are shifted back; a
/// loop that closes only up to a period (a band around a cylinder) is closed far outside the
/// domain on the same side for every loop, which keeps the even–odd rule right.
/// Immutable after create(); const queries are thread-safe.
class FaceQuery {
 public:
  /// Prepares `face` as seen through the shape it was explored from (composed location and
  /// orientation). Errors: InvalidArgument (null or not a face), InvalidShape (no surface,
  /// pcurve counts that do not match the wires).
  static Result<FaceQuery> create(const Shape& face);

  /// Whether the parameter point (u, v) lies in the face's domain or on its boundary. Periodic
  /// parameters are tried in every period that overlaps the domain (u, u ± period, …).
  bool contains_uv(const Vec2& uv) const { return locate_uv(uv) != Containment::Outside; }
  /// Inside / Outside, or OnBoundary when within kFaceQueryUvRelative (boolean/tolerance.h;
  /// relative to the domain's size) of a boundary loop in the parameter plane. Outside that
  /// band the side of every chord is decided by the exact predicates.
  Containment locate_uv(const Vec2& uv) const;

  const Shape& face() const { return face_; }
  /// The face body's surface (body frame).
  const Surface& surface() const { return *surface_; }
  /// The face's composed location (body frame → world).
  const Location& location() const { return location_; }
  /// +1 when the outward side of the region is the surface normal (Forward), −1 when it is
  /// the opposite (Reversed).
  double outward_sign() const { return outward_sign_; }
  /// Bounding rectangle of the boundary loops in the parameter plane.
  const ParamBox& parameter_box() const { return parameter_box_; }
  /// Box of the face patch in the body frame.
  const BoundingBox& local_bounds() const { return local_bounds_; }
  /// Box of the face patch in the world frame (a box around the moved local box).
  const BoundingBox& world_bounds() const { return world_bounds_; }

  /// World point → body frame.
  Vec3 to_local(const Vec3& p) const { return inverse_.apply_point(p); }
  /// Parameters of the surface point closest to the world point p, and its world distance.
  std::pair<Vec2, double> project(const Vec3& p) const;
  /// Outward unit normal (world frame) at the parameters uv.
  Vec3 outward_normal(const Vec2& uv) const;

 private:
  // A pcurve as walked in its loop: c̃(t) = c(t) + offset + blend of the gaps at its ends.
  struct EdgeUse {
    Curve2dPtr curve;
    double t_start = 0, t_end = 0;  // walking direction: t_start → t_end (either order)
    Vec2 offset = Vec2::Zero();     // period shift
    Vec2 gap_start = Vec2::Zero(), gap_end = Vec2::Zero();
    double second = 0;  // bound on |c''| (0 for straight pieces)
    Vec2 point(double t) const;
  };
  // A chord of an edge use over [t0, t1] (use == kStraight: an exact straight segment).
  struct Piece {
    std::uint32_t use;
    double t0, t1;
    Vec2 a, b;
  };
  static constexpr std::uint32_t kStraight = 0xffffffffu;

  FaceQuery() = default;
  Containment locate_once(const Vec2& q) const;
  /// Adds the piece's crossings with the ray from q towards +u to `inside`; false when q is
  /// on the boundary.
  bool cross(const Piece& piece, const Vec2& q, bool& inside) const;

  Shape face_;
  SurfacePtr surface_;
  Location location_, inverse_;
  double outward_sign_ = 1.0;
  std::vector<EdgeUse> uses_;
  std::vector<std::vector<Piece>> loops_;
  ParamBox parameter_box_{0, 0, 0, 0};
  double uv_epsilon_ = 0.0;
  BoundingBox local_bounds_, world_bounds_;
};

/// A bounding-volume hierarchy over boxes: the items whose box contains a point, or meets a
/// ray. Built by median splits along the longest axis of the box centres (ties broken by
/// index: deterministic); leaves hold at most four items. Immutable after build().
class BoxTree {
 public:
  void build(const std::vector<BoundingBox>& boxes);
  /// Calls f(item) for every item whose box, grown by `margin`, contains p (any order).
  template <class F>
  void visit_point(const Vec3& p, double margin, F&& f) const;
  /// Calls f(item) for every item whose box the ray origin + t·direction, 0 ≤ t ≤ t_max,
  /// meets.
  template <class F>
  void visit_ray(const Vec3& origin, const Vec3& direction, double t_max, F&& f) const;

 private:
  struct Node {
    BoundingBox box;
    std::uint32_t first = 0, count = 0;  // items [first, first + count) of a leaf
    std::uint32_t left = 0, right = 0;   // children of an inner node (count == 0)
  };
  std::uint32_t build_node(std::vector<std::uint32_t>& order, const std::vector<BoundingBox>& boxes,
                           std::uint32_t first, std::uint32_t count);
  std::vector<Node> nodes_;
  std::vector<std::uint32_t> items_;
};

template <class F>
void BoxTree::visit_point(const Vec3& p, double margin, F&& f) const {
  if (nodes_.empty()) return;
  std::uint32_t stack[64];
  int size = 0;
  stack[size++] = 0;
  while (size > 0) {
    const Node& node = nodes_[stack[--size]];
    if (!((node.box.min.array() - margin <= p.array()).all() &&
          (p.array() <= node.box.max.array() + margin).all())) {
      continue;
    }
    if (node.count > 0) {
      for (std::uint32_t i = node.first; i < node.first + node.count; ++i) f(items_[i]);
    } else {
      stack[size++] = node.left;
      stack[size++] = node.right;
    }
  }
}

template <class F>
void BoxTree::visit_ray(const Vec3& origin, const Vec3& direction, double t_max, F&& f) const {
  if (nodes_.empty()) return;
  const BoxRay ray(origin, direction);
  std::uint32_t stack[64];
  int size = 0;
  stack[size++] = 0;
  while (size > 0) {
    const Node& node = nodes_[stack[--size]];
    double t0 = 0.0, t1 = t_max;
    if (!ray.clip(node.box, t0, t1)) continue;
    if (node.count > 0) {
      for (std::uint32_t i = node.first; i < node.first + node.count; ++i) f(items_[i]);
    } else {
      stack[size++] = node.left;
      stack[size++] = node.right;
    }
  }
}

/// Knobs of a SolidClassifier.
struct ClassifierOptions {
  /// Seed of the ray directions (a fixed sequence derived from it: deterministic).
  std::uint64_t seed = 0x9e3779b97f4a7c15ull;
  /// Rays tried (each after an ambiguous one) before the majority vote over all of them.
  int max_rays = 9;
};

/// What one classification cost (for tests and benchmarks).
struct ClassifyStats {
  int rays = 0;        ///< rays cast (more than one: the earlier ones were ambiguous)
  bool voted = false;  ///< every ray was ambiguous and the majority decided
};

/// Exact classification of points against a closed region bounded by faces: a solid (any
/// number of shells: cavities are outside), or a compound / compsolid of solids (the union
/// of their interiors).
///
/// A point within `tolerance` of a face (surface projection whose parameters the face
/// contains) or of an edge is OnBoundary of its solid. Otherwise a ray from it is intersected
/// with every face surface (closed forms, see boolean/line_surface.h) and the hits that lie
/// inside their faces are counted per solid; odd means inside. A ray that passes within
/// max(tolerance, edge tolerance) of a face boundary, runs along a surface or touches one
/// inside a face (or within kTouchingRelative of the face's size from its boundary, see
/// boolean/tolerance.h) is ambiguous and another direction is cast; after
/// ClassifierOptions::max_rays ambiguous rays the majority of their parities decides. Faces
/// with Internal or External orientation bound nothing and are skipped; faces not inside any
/// solid form one extra region. Trees of face and edge boxes (slab tests) skip what a ray or
/// a point cannot meet, so a query costs O(log n) plus the faces actually near it.
/// Immutable after create(); const queries are thread-safe and deterministic.
class SolidClassifier {
 public:
  /// Errors: InvalidArgument (null shape, tolerance not finite and > 0, max_rays < 1),
  /// InvalidShape (a face FaceQuery::create rejects). A shape without faces is accepted:
  /// everything is outside it.
  static Result<SolidClassifier> create(const Shape& shape, double tolerance,
                                        const ClassifierOptions& options = {});

  /// Inside / Outside / OnBoundary of the union of the solids. A point on one solid's
  /// boundary but strictly inside another is Inside.
  /// `stats`, when given, receives what the call cost.
  Containment classify(const Vec3& p, ClassifyStats* stats = nullptr) const;

  /// For a boundary point: the outward unit normal of the first face (explorer order) it
  /// lies on; nullopt when it lies on none.
  std::optional<Vec3> boundary_normal(const Vec3& p) const;

  std::size_t face_count() const { return faces_.size(); }
  const FaceQuery& face(std::size_t i) const { return faces_[i]; }
  double tolerance() const { return tolerance_; }
  /// The ray directions, in the order they are tried.
  const std::vector<Vec3>& ray_directions() const { return directions_; }

 private:
  struct EdgeRecord {
    CurvePtr curve;  // null for a degenerate edge
    double first = 0, last = 0;
    Location location, inverse;
    Vec3 point = Vec3::Zero();  // degenerate edge: its vertex (world)
    BoundingBox bounds;         // world, enlarged by `band`
    double band = 0;            // max(classifier tolerance, edge tolerance)
    std::vector<std::uint32_t> groups;
  };
  // The solids (groups) a query involves: those whose box holds the point, ascending, and
  // per candidate whether rays must decide it (it is not on its boundary).
  struct Candidates {
    std::vector<std::uint32_t> groups;
    std::vector<std::uint8_t> open;
    /// Position of group g in `groups`, or -1.
    int find(std::uint32_t g) const;
  };
  struct RayOutcome {
    std::vector<std::uint8_t> parity;  // per candidate
    bool ambiguous = false;
  };

  SolidClassifier() = default;
  /// Distance from p to the edge; infinity when p is outside its box grown by `margin`.
  double edge_distance(const EdgeRecord& edge, const Vec3& p, double margin) const;
  Candidates candidates(const Vec3& p) const;
  /// Per candidate: whether p is within tolerance of its boundary.
  std::vector<std::uint8_t> on_boundary(const Vec3& p, const Candidates& c) const;
  RayOutcome cast(const Vec3& p, const Vec3& direction, const Candidates& c) const;
  /// Per candidate (open ones): whether p is inside, by rays.
  std::vector<std::uint8_t> inside(const Vec3& p, const Candidates& c, ClassifyStats& stats) const;

  std::vector<FaceQuery> faces_;
  std::vector<std::uint32_t> face_group_;
  std::vector<std::vector<std::uint32_t>> face_edges_;
  std::vector<EdgeRecord> edges_;
  std::size_t group_count_ = 0;
  double tolerance_ = 0.0;
  ClassifierOptions options_;
  std::vector<Vec3> directions_;
  BoundingBox bounds_;                     // everything, enlarged by the largest band
  std::vector<BoundingBox> group_bounds_;  // per group, enlarged by the largest band
  BoxTree group_tree_;                     // over group_bounds_
  BoxTree face_tree_;                      // over the faces' world boxes
  BoxTree edge_tree_;                      // over the edges' world boxes (enlarged by their bands)
};

}  // namespace csgtile::kernel::detail
