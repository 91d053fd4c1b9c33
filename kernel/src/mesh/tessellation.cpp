// Tessellation of shapes: shared edge discretisation, then each face meshed against it.

#include "csgtile/kernel/tessellation.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iterator>
#include <limits>
#include <numbers>
#include <string>

#include "csgtile/kernel/explorer.h"
#include "mesh/face_mesher.h"
#include "mesh/sampling.h"

namespace csgtile::kernel {

namespace {

// A closed curve needs at least three segments to bound any area.
constexpr double kMaxTurn = 2.0 * std::numbers::pi / 3.0;

bool doubly_curved(const Surface& surface) {
  switch (surface.kind()) {
    case SurfaceKind::Sphere:
    case SurfaceKind::Torus:
      return true;
    case SurfaceKind::Revolution:
      return static_cast<const RevolutionSurface&>(surface).meridian()->kind() != CurveKind::Line;
    default:
      return false;
  }
}

// A face whose single loop is made of axis-parallel straight pcurves: the row method applies
// (it re-checks the sampled boundary and falls back to the general method otherwise).
bool axis_aligned_domain(const Shape& face) {
  const FaceData& data = *face.body().face();
  if (data.pcurves.size() != 1 || data.pcurves[0].size() < 4) return false;
  for (const Curve2dPtr& pcurve : data.pcurves[0]) {
    if (pcurve->kind() != Curve2dKind::Line) return false;
    const Vec2 d = static_cast<const Line2d&>(*pcurve).direction();
    if (d.x() != 0.0 && d.y() != 0.0) return false;
  }
  return true;
}

enum class FaceMethod { Planar, Rows, General };

// How a face is meshed, and how the chordal tolerance is split between its edges and its
// interior (fractions of the tolerance).
struct FacePlan {
  FaceMethod method;
  double edge_share;
  double interior_share;
};

// Planes need no interior points. On rows, a face curved in both directions (sphere, torus,
// a revolution of a curved meridian) errs by about the sum of its errors along u and along
// v, and its row spacing in v is its side edges' sampling: edges and interior rows get half
// the budget each; ruled faces (cylinder, cone, extrusion, revolution of a line) are exact
// across their rows and give all of it to their edges. The general method measures its
// real error inside (the whole budget), but its triangles join boundary points that are not
// aligned as rows are, so it needs the margin of edges sampled at half the budget.
FacePlan plan_face(const Shape& face, const TessellationOptions& options) {
  const Surface& surface = *face.body().face()->surface;
  if (surface.kind() == SurfaceKind::Plane) return {FaceMethod::Planar, 1.0, 1.0};
  if (!options.general_method_only && axis_aligned_domain(face)) {
    return doubly_curved(surface) ? FacePlan{FaceMethod::Rows, 0.5, 0.5}
                                  : FacePlan{FaceMethod::Rows, 1.0, 1.0};
  }
  return {FaceMethod::General, 0.5, 1.0};
}

// Smallest row step (in u) over the face's v range, sampled at 17 values of v (exact for
// cones and cylinders, whose row radius is linear in v, and at the torus's outer equator).
double widest_row_step(const Shape& face, double chordal_body, double angular) {
  const FaceData& data = *face.body().face();
  const Shape body_face = face.oriented(Orientation::Forward);
  Vec2 lo = Vec2::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (std::size_t w = 0; w < body_face.child_count(); ++w) {
    const Shape wire = body_face.child(w);
    for (std::size_t u = 0; u < wire.child_count(); ++u) {
      const EdgeData& edge = *wire.child(u).body().edge();
      const Curve2d& pcurve = *data.pcurves[w][u];
      const int samples = pcurve.kind() == Curve2dKind::Line ? 1 : 32;
      for (int k = 0; k <= samples; ++k) {
        const Vec2 p = pcurve.point(edge.first + (edge.last - edge.first) * k / samples);
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
      }
    }
  }
  double step = std::numeric_limits<double>::infinity();
  if (!(lo.x() <= hi.x())) return step;
  constexpr int kRows = 16;
  for (int k = 0; k <= kRows; ++k) {
    const double v = lo.y() + (hi.y() - lo.y()) * k / kRows;
    step =
        std::min(step, detail::row_step(*data.surface, v, lo.x(), hi.x(), chordal_body, angular));
  }
  return step;
}

// The sample parameters of one edge and the mesh vertex at each.
struct EdgeSamples {
  std::vector<double> parameters;
  std::vector<std::uint32_t> ids;
};

std::string face_name(std::size_t index, const Shape& face) {
  constexpr const char* kSurfaceNames[] = {"plane", "cylinder",  "cone",      "sphere",
                                           "torus", "extrusion", "revolution"};
  const auto kind = static_cast<std::size_t>(face.body().face()->surface->kind());
  return "face " + std::to_string(index) + " (" +
         (kind < std::size(kSurfaceNames) ? kSurfaceNames[kind] : "surface") + ")";
}

void put_u32(std::string& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xFFu));
}
void put_f32(std::string& out, double value) {
  const auto f = static_cast<float>(value);
  std::uint32_t bits;
  std::memcpy(&bits, &f, sizeof bits);
  put_u32(out, bits);
}

}  // namespace

std::vector<double> discretize_edge(const Shape& edge, double chordal_tolerance,
                                    double angular_tolerance) {
  if (edge.is_null() || edge.kind() != ShapeKind::Edge) return {};
  const EdgeData& data = *edge.body().edge();
  if (data.degenerate()) return {data.first, data.last};
  return detail::curve_parameters(*data.curve, data.first, data.last,
                                  chordal_tolerance / edge.location().scale(),
                                  std::min(angular_tolerance, kMaxTurn));
}

Result<Mesh> tessellate(const Shape& shape, const TessellationOptions& options) {
  if (shape.is_null()) return Error{ErrorCode::InvalidArgument, "cannot tessellate a null shape"};
  if (!(options.chordal_tolerance > 0.0) || !std::isfinite(options.chordal_tolerance)) {
    return Error{ErrorCode::InvalidArgument, "chordal_tolerance must be finite and > 0"};
  }
  if (!(options.angular_tolerance > 0.0) || !(options.angular_tolerance <= std::numbers::pi)) {
    return Error{ErrorCode::InvalidArgument, "angular_tolerance must be in (0, pi]"};
  }
  const double angular = std::min(options.angular_tolerance, kMaxTurn);
  Mesh mesh;

  // Topological vertices are the first mesh vertices, one each.
  const ShapeIndex vertices = map_child_shapes(shape, ShapeKind::Vertex);
  for (const Shape& v : vertices.shapes()) mesh.vertices.push_back(vertex_point(v));

  const ShapeIndex edges = map_child_shapes(shape, ShapeKind::Edge);
  const ShapeIndex faces = map_child_shapes(shape, ShapeKind::Face);

  // An edge is sampled once, for the most demanding face it bounds.
  std::vector<FacePlan> plans;
  std::vector<double> share(edges.size(), 1.0);
  for (const Shape& face : faces.shapes()) {
    plans.push_back(plan_face(face, options));
    for (const Shape& edge : Explorer(face, ShapeKind::Edge)) {
      const std::size_t e = edges.find(edge);
      if (e != ShapeIndex::npos) share[e] = std::min(share[e], plans.back().edge_share);
    }
  }

  // Rows of a face of revolution are circles whose radius varies with v (a cone's two
  // circles differ); strips between rows join points up to one step apart in u, so the
  // circles bounding such a face take the step that its widest row needs.
  std::vector<double> max_step(edges.size(), std::numeric_limits<double>::infinity());
  for (std::size_t f = 0; f < faces.size(); ++f) {
    const Shape& face = faces[f];
    const FaceData& data = *face.body().face();
    if (plans[f].method != FaceMethod::Rows || !detail::revolution_like(*data.surface)) continue;
    const double chordal =
        options.chordal_tolerance * plans[f].interior_share / face.location().scale();
    const double step = widest_row_step(face, chordal, angular);
    const Shape body_face = face.oriented(Orientation::Forward);
    for (std::size_t w = 0; w < body_face.child_count(); ++w) {
      const Shape wire = body_face.child(w);
      for (std::size_t u = 0; u < wire.child_count(); ++u) {
        const Curve2d& pcurve = *data.pcurves[w][u];
        if (pcurve.kind() != Curve2dKind::Line) continue;
        const Vec2 d = static_cast<const Line2d&>(pcurve).direction();
        const std::size_t e = edges.find(wire.child(u));
        if (e == ShapeIndex::npos || d.y() != 0.0 || d.x() == 0.0) continue;
        max_step[e] = std::min(max_step[e], step / std::abs(d.x()));
      }
    }
  }

  std::vector<EdgeSamples> samples(edges.size());
  mesh.edge_vertices.resize(edges.size());
  for (std::size_t e = 0; e < edges.size(); ++e) {
    const Shape& edge = edges[e];
    const EdgeData& data = *edge.body().edge();
    // Children of an edge body: its start vertex Forward, its end vertex Reversed.
    std::uint32_t start = 0, end = 0;
    for (std::size_t c = 0; c < edge.child_count(); ++c) {
      const std::size_t v = vertices.find(edge.child(c));
      const bool is_start = edge.body().children()[c].orientation() == Orientation::Forward;
      (is_start ? start : end) = static_cast<std::uint32_t>(v);
    }
    EdgeSamples& s = samples[e];
    if (data.degenerate()) {
      s.parameters = {data.first, data.last};
      s.ids = {start, start};
      mesh.edge_vertices[e] = {start};
      continue;
    }
    s.parameters = detail::curve_parameters(
        *data.curve, data.first, data.last,
        options.chordal_tolerance * share[e] / edge.location().scale(), angular, max_step[e]);
    if (s.parameters.empty()) {
      return Error{ErrorCode::InvalidArgument,
                   "chordal_tolerance is too small for edge " + std::to_string(e) +
                       ": it would need more than " + std::to_string(detail::kMaxSegments) +
                       " segments"};
    }
    s.ids.push_back(start);
    for (std::size_t i = 1; i + 1 < s.parameters.size(); ++i) {
      s.ids.push_back(static_cast<std::uint32_t>(mesh.vertices.size()));
      mesh.vertices.push_back(edge.location().apply_point(data.curve->point(s.parameters[i])));
    }
    s.ids.push_back(end);
    mesh.edge_vertices[e] = s.ids;
  }

  for (std::size_t f = 0; f < faces.size(); ++f) {
    const Shape& face = faces[f];
    const Orientation orientation = face.orientation();
    if (orientation != Orientation::Forward && orientation != Orientation::Reversed) continue;
    const FaceData& data = *face.body().face();
    // Walk the face body's own loops (outer counter-clockwise in (u, v)); the face's
    // orientation only decides which side is outward, applied to the triangles below.
    const Shape body_face = face.oriented(Orientation::Forward);
    detail::FaceLoops loops;
    for (std::size_t w = 0; w < body_face.child_count(); ++w) {
      const Shape wire = body_face.child(w);
      std::vector<std::vector<detail::BoundaryPoint>> uses;
      for (std::size_t u = 0; u < wire.child_count(); ++u) {
        const Shape use = wire.child(u);
        const Orientation o = use.orientation();
        if (o != Orientation::Forward && o != Orientation::Reversed) continue;  // embedded
        const std::size_t e = edges.find(use);
        if (e == ShapeIndex::npos) {
          return Error{ErrorCode::InvalidShape, face_name(f, face) + " uses an unknown edge"};
        }
        const EdgeSamples& s = samples[e];
        const Curve2d& pcurve = *data.pcurves[w][u];
        std::vector<detail::BoundaryPoint> points;
        for (std::size_t k = 0; k < s.parameters.size(); ++k) {
          const std::size_t i = o == Orientation::Forward ? k : s.parameters.size() - 1 - k;
          points.push_back({pcurve.point(s.parameters[i]), s.ids[i]});
        }
        uses.push_back(std::move(points));
      }
      if (!uses.empty()) loops.push_back(std::move(uses));
    }
    if (loops.empty()) continue;

    detail::FaceGeometry geometry;
    geometry.surface = data.surface.get();
    geometry.location = face.location();
    geometry.chordal = options.chordal_tolerance * plans[f].interior_share;
    geometry.angular = angular;
    std::vector<detail::Triangle> triangles;
    bool done = false;
    if (plans[f].method == FaceMethod::Rows) {
      Result<bool> rows = detail::mesh_rectangular_face(geometry, loops, mesh.vertices, triangles);
      if (!rows.ok()) {
        return Error{rows.error().code, face_name(f, face) + ": " + rows.error().message};
      }
      done = rows.value();
    }
    if (!done) {
      Status status = detail::mesh_general_face(geometry, loops, mesh.vertices, triangles);
      if (!status.ok()) {
        return Error{status.error().code, face_name(f, face) + ": " + status.error().message};
      }
    }
    // Triangles are counter-clockwise in (u, v), i.e. around the surface normal; a face used
    // Reversed has its outside opposite the normal.
    for (detail::Triangle& t : triangles) {
      if (orientation == Orientation::Reversed) std::swap(t[1], t[2]);
      mesh.triangles.push_back(t);
      mesh.triangle_face.push_back(static_cast<std::uint32_t>(f));
    }
    if (mesh.vertices.size() >= std::numeric_limits<std::uint32_t>::max()) {
      return Error{ErrorCode::InvalidArgument,
                   "chordal_tolerance is too small: the mesh would exceed 2^32 vertices"};
    }
  }
  return mesh;
}

double mesh_volume(const Mesh& mesh) {
  if (mesh.vertices.empty()) return 0.0;
  Vec3 lo = mesh.vertices.front(), hi = lo;
  for (const Vec3& p : mesh.vertices) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const Vec3 origin = 0.5 * (lo + hi);
  double six_volume = 0.0;
  for (const auto& t : mesh.triangles) {
    const Vec3 a = mesh.vertices[t[0]] - origin;
    const Vec3 b = mesh.vertices[t[1]] - origin;
    const Vec3 c = mesh.vertices[t[2]] - origin;
    six_volume += a.dot(b.cross(c));
  }
  return six_volume / 6.0;
}

double mesh_area(const Mesh& mesh) {
  double twice = 0.0;
  for (const auto& t : mesh.triangles) {
    const Vec3& a = mesh.vertices[t[0]];
    twice += (mesh.vertices[t[1]] - a).cross(mesh.vertices[t[2]] - a).norm();
  }
  return 0.5 * twice;
}

bool mesh_is_closed(const Mesh& mesh) {
  std::vector<std::uint64_t> directed;
  directed.reserve(3 * mesh.triangles.size());
  for (const auto& t : mesh.triangles) {
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) return false;
    for (std::size_t k = 0; k < 3; ++k) {
      directed.push_back((std::uint64_t{t[k]} << 32) | t[(k + 1) % 3]);
    }
  }
  std::sort(directed.begin(), directed.end());
  if (std::adjacent_find(directed.begin(), directed.end()) != directed.end()) return false;
  for (std::uint64_t e : directed) {
    const std::uint64_t twin = (e << 32) | (e >> 32);
    if (!std::binary_search(directed.begin(), directed.end(), twin)) return false;
  }
  return true;
}

std::string to_binary_stl(const Mesh& mesh) {
  std::string out = "csgtile binary STL";
  out.resize(80, ' ');
  out.reserve(84 + 50 * mesh.triangles.size());
  put_u32(out, static_cast<std::uint32_t>(mesh.triangles.size()));
  for (const auto& t : mesh.triangles) {
    const Vec3& a = mesh.vertices[t[0]];
    const Vec3& b = mesh.vertices[t[1]];
    const Vec3& c = mesh.vertices[t[2]];
    const Vec3 n = (b - a).cross(c - a).normalized();
    for (int i = 0; i < 3; ++i) put_f32(out, n[i]);
    for (const Vec3* p : {&a, &b, &c}) {
      for (int i = 0; i < 3; ++i) put_f32(out, (*p)[i]);
    }
    out.push_back('\0');
    out.push_back('\0');
  }
  return out;
}

Result<std::shared_ptr<const Mesh>> shared_tessellation(const Shape& shape,
                                                        double chordal_tolerance,
                                                        std::shared_ptr<const Mesh> given) {
  if (given) return given;
  TessellationOptions options;
  options.chordal_tolerance = chordal_tolerance;
  auto mesh = tessellate(shape, options);
  if (!mesh.ok()) return mesh.error();
  return std::make_shared<const Mesh>(std::move(mesh).value());
}

}  // namespace csgtile::kernel
