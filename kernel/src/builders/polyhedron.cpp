// Box and polygon extrusion: solids bounded by planar faces with straight edges.

#include <cmath>
#include <map>
#include <string>

#include "csgtile/kernel/polygon2d.h"
#include "csgtile/kernel/primitives.h"

namespace csgtile::kernel {

namespace {

// Accumulates vertices and planar faces; each edge is made once and shared by the two faces
// that use it (in opposite directions).
class PolyhedronBuilder {
 public:
  explicit PolyhedronBuilder(double tolerance) : tolerance_(tolerance) {}

  // Room for the vertices and faces to come (one allocation each instead of regrowth).
  void reserve(std::size_t vertices, std::size_t faces) {
    points_.reserve(vertices);
    vertices_.reserve(vertices);
    faces_.reserve(faces);
  }

  Result<std::size_t> add_vertex(const Vec3& p) {
    auto v = ShapeFactory::vertex(p, tolerance_);
    if (!v.ok()) return v.error();
    points_.push_back(p);
    vertices_.push_back(std::move(v).value());
    return points_.size() - 1;
  }

  // rings[0] is the outer boundary, the rest holes; each ring's orientation is fixed here
  // from `outward` (outer counter-clockwise around it, holes clockwise).
  Status add_face(std::vector<std::vector<std::size_t>> rings, const Vec3& outward) {
    const Vec3 n = outward.normalized();
    for (std::size_t r = 0; r < rings.size(); ++r) {
      const bool want_ccw = r == 0;
      if ((newell(rings[r]).dot(n) > 0) != want_ccw) std::reverse(rings[r].begin(), rings[r].end());
    }
    const Vec3 origin = points_[rings[0][0]];
    const Frame frame = Frame::from_z(origin, n, points_[rings[0][1]] - origin);
    auto surface = std::make_shared<PlaneSurface>(frame);
    auto uv = [&](const Vec3& p) {
      return Vec2((p - origin).dot(frame.x), (p - origin).dot(frame.y));
    };

    std::vector<Shape> wires;
    std::vector<std::vector<Curve2dPtr>> pcurves;
    wires.reserve(rings.size());
    pcurves.reserve(rings.size());
    for (const auto& ring : rings) {
      std::vector<Shape> edges;
      std::vector<Curve2dPtr> curves;
      edges.reserve(ring.size());
      curves.reserve(ring.size());
      for (std::size_t i = 0; i < ring.size(); ++i) {
        const std::size_t a = ring[i], b = ring[(i + 1) % ring.size()];
        auto edge = edge_between(a, b);
        if (!edge.ok()) return edge.error();
        const std::size_t lo = std::min(a, b), hi = std::max(a, b);
        const double length = (points_[hi] - points_[lo]).norm();
        edges.push_back(a == lo ? edge.value() : edge.value().reversed());
        curves.push_back(std::make_shared<Line2d>(uv(points_[lo]),
                                                  (uv(points_[hi]) - uv(points_[lo])) / length));
      }
      auto wire = ShapeFactory::wire(std::move(edges));
      if (!wire.ok()) return wire.error();
      wires.push_back(std::move(wire).value());
      pcurves.push_back(std::move(curves));
    }
    auto face = ShapeFactory::face(surface, std::move(wires), std::move(pcurves), tolerance_);
    if (!face.ok()) return face.error();
    faces_.push_back(std::move(face).value());
    return {};
  }

  Result<Shape> solid() {
    auto shell = ShapeFactory::shell(std::move(faces_));
    if (!shell.ok()) return shell;
    return ShapeFactory::solid({std::move(shell).value()});
  }

 private:
  Vec3 newell(const std::vector<std::size_t>& ring) const {
    Vec3 n = Vec3::Zero();
    for (std::size_t i = 0; i < ring.size(); ++i) {
      n += points_[ring[i]].cross(points_[ring[(i + 1) % ring.size()]]);
    }
    return n;
  }

  // The edge runs from the lower to the higher vertex index, its curve parametrised by
  // arc length.
  Result<Shape> edge_between(std::size_t a, std::size_t b) {
    const auto key = std::make_pair(std::min(a, b), std::max(a, b));
    if (auto it = edges_.find(key); it != edges_.end()) return it->second;
    const Vec3& p = points_[key.first];
    const Vec3& q = points_[key.second];
    const double length = (q - p).norm();
    if (!(length > tolerance_)) {
      return Error{ErrorCode::DegenerateGeometry, "an edge is shorter than the tolerance"};
    }
    auto edge = ShapeFactory::edge(std::make_shared<LineCurve>(p, q - p), 0.0, length,
                                   vertices_[key.first], vertices_[key.second], tolerance_);
    if (!edge.ok()) return edge;
    edges_.emplace(key, edge.value());
    return edge;
  }

  double tolerance_;
  std::vector<Vec3> points_;
  std::vector<Shape> vertices_;
  std::map<std::pair<std::size_t, std::size_t>, Shape> edges_;
  std::vector<Shape> faces_;
};

bool positive_finite(double v) { return std::isfinite(v) && v > 0.0; }

}  // namespace

Result<Shape> make_box(double dx, double dy, double dz, double tolerance) {
  if (!positive_finite(dx) || !positive_finite(dy) || !positive_finite(dz)) {
    return Error{ErrorCode::InvalidArgument, "box sizes must be finite and > 0"};
  }
  // Polygon extrusion of the rectangle gives exactly the box's 6 faces, 12 edges, 8 vertices.
  return make_extrusion({{0, 0}, {dx, 0}, {dx, dy}, {0, dy}}, {}, dz, tolerance);
}

Result<Shape> make_extrusion(const std::vector<Vec2>& outer,
                             const std::vector<std::vector<Vec2>>& holes, double h,
                             double tolerance) {
  if (!positive_finite(h)) return Error{ErrorCode::InvalidArgument, "extrusion height must be > 0"};
  std::vector<std::vector<Vec2>> rings;
  rings.push_back(clean_ring(outer, tolerance));
  for (const auto& hole : holes) rings.push_back(clean_ring(hole, tolerance));
  for (std::size_t r = 0; r < rings.size(); ++r) {
    const std::string name = r == 0 ? "outer ring" : "hole " + std::to_string(r - 1);
    for (const Vec2& p : rings[r]) {
      if (!p.allFinite())
        return Error{ErrorCode::InvalidArgument, name + " has a non-finite point"};
    }
    if (rings[r].size() < 3 || std::abs(ring_area(rings[r])) <= 0.5 * tolerance * tolerance) {
      return Error{ErrorCode::DegenerateGeometry, name + " has no area"};
    }
    if (ring_self_intersects(rings[r])) {
      return Error{ErrorCode::DegenerateGeometry, name + " intersects itself"};
    }
    // Outer counter-clockwise, holes clockwise: the material is on the left of every ring.
    const bool ccw = ring_area(rings[r]) > 0;
    if (ccw != (r == 0)) std::reverse(rings[r].begin(), rings[r].end());
    if (r > 0) {
      if (rings_intersect(rings[0], rings[r]) || !inside_ring(rings[r][0], rings[0])) {
        return Error{ErrorCode::DegenerateGeometry,
                     name + " is not strictly inside the outer ring"};
      }
      for (std::size_t s = 1; s < r; ++s) {
        if (rings_intersect(rings[s], rings[r]) || inside_ring(rings[r][0], rings[s]) ||
            inside_ring(rings[s][0], rings[r])) {
          return Error{ErrorCode::DegenerateGeometry,
                       name + " overlaps hole " + std::to_string(s - 1)};
        }
      }
    }
  }

  PolyhedronBuilder builder(tolerance);
  std::size_t corners = 0;
  for (const auto& ring : rings) corners += ring.size();
  builder.reserve(2 * corners, 2 + corners);
  std::vector<std::vector<std::size_t>> bottom, top;
  bottom.reserve(rings.size());
  top.reserve(rings.size());
  for (const auto& ring : rings) {
    std::vector<std::size_t> b, t;
    b.reserve(ring.size());
    t.reserve(ring.size());
    for (const Vec2& p : ring) {
      auto vb = builder.add_vertex(Vec3(p.x(), p.y(), 0.0));
      auto vt = builder.add_vertex(Vec3(p.x(), p.y(), h));
      if (!vb.ok()) return vb.error();
      if (!vt.ok()) return vt.error();
      b.push_back(vb.value());
      t.push_back(vt.value());
    }
    bottom.push_back(std::move(b));
    top.push_back(std::move(t));
  }
  if (auto s = builder.add_face(bottom, -Vec3::UnitZ()); !s.ok()) return s.error();
  if (auto s = builder.add_face(top, Vec3::UnitZ()); !s.ok()) return s.error();
  for (std::size_t r = 0; r < rings.size(); ++r) {
    const auto& ring = rings[r];
    for (std::size_t i = 0; i < ring.size(); ++i) {
      const std::size_t j = (i + 1) % ring.size();
      const Vec2 d = ring[j] - ring[i];
      // Material on the left of the ring, so the side's outward normal is on its right.
      const Vec3 outward(d.y(), -d.x(), 0.0);
      auto s = builder.add_face({{bottom[r][i], bottom[r][j], top[r][j], top[r][i]}}, outward);
      if (!s.ok()) return s.error();
    }
  }
  return builder.solid();
}

}  // namespace csgtile::kernel
