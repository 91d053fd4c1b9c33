// LoD1.2 block models and the heights of a building's solid (block_model.h).

#include "csgtile/assembly/block_model.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "csgtile/kernel/check.h"
#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/face_rings.h"
#include "csgtile/kernel/tessellation.h"

namespace csgtile::assembly {

namespace {

using kernel::ErrorCode;
using kernel::Vec2;
using kernel::Vec3;
using Triangle = std::array<Vec3, 3>;

// The exporters' rules (CityJSON semantics): a face turned up by more than this is roof, one
// turned down by more than this (in size) is seen from below.
constexpr double kRoofNz = 0.2;
constexpr double kDownNz = -0.9;
// A face is part of the footprint when it faces down at all (not vertical): the downward
// faces' projections together are the solid's.
constexpr double kSeenFromBelow = 1e-6;

// The area seen from above of the part of `t` at or below height z: the triangle clipped by
// the plane (at most four corners), its shoelace area.
double area_below(const Triangle& t, double z) {
  std::array<Vec3, 4> poly;
  int n = 0;
  for (int i = 0; i < 3; ++i) {
    const Vec3& a = t[static_cast<std::size_t>(i)];
    const Vec3& b = t[static_cast<std::size_t>((i + 1) % 3)];
    const bool a_in = a.z() <= z, b_in = b.z() <= z;
    if (a_in) poly[static_cast<std::size_t>(n++)] = a;
    if (a_in != b_in)
      poly[static_cast<std::size_t>(n++)] = a + (z - a.z()) / (b.z() - a.z()) * (b - a);
  }
  double twice = 0.0;
  for (int i = 0; i < n; ++i) {
    const Vec3& a = poly[static_cast<std::size_t>(i)];
    const Vec3& b = poly[static_cast<std::size_t>((i + 1) % n)];
    twice += a.x() * b.y() - a.y() * b.x();
  }
  return 0.5 * std::abs(twice);
}

// The height below which a share q of the roof's area lies: the area function is continuous
// and increasing from roof_min to roof_max; bisection to the resolution of doubles.
double roof_percentile(const std::vector<Triangle>& roof, double total, double low, double high,
                       double q) {
  const double target = q * total;
  for (int i = 0; i < 200 && high - low > 1e-12 * std::max(1.0, std::abs(high)); ++i) {
    const double mid = 0.5 * (low + high);
    double below = 0.0;
    for (const Triangle& t : roof) below += area_below(t, mid);
    (below < target ? low : high) = mid;
  }
  return high;
}

struct Measured {
  kernel::Mesh mesh;
  BuildingHeights heights;
};

kernel::Result<Measured> measure(const kernel::Shape& shape, double chordal_tolerance) {
  kernel::TessellationOptions tessellation;
  tessellation.chordal_tolerance = chordal_tolerance;
  auto meshed = kernel::tessellate(shape, tessellation);
  if (!meshed.ok()) return meshed.error();
  Measured out;
  out.mesh = std::move(meshed).value();
  const kernel::Mesh& m = out.mesh;
  BuildingHeights& h = out.heights;
  double ground = std::numeric_limits<double>::infinity();
  double lowest = ground;
  h.roof_min = ground;
  h.roof_max = -ground;
  std::vector<Triangle> roof;
  std::vector<bool> roof_face;
  for (std::size_t i = 0; i < m.triangles.size(); ++i) {
    const auto& k = m.triangles[i];
    const Triangle t = {m.vertices[k[0]], m.vertices[k[1]], m.vertices[k[2]]};
    const Vec3 n = (t[1] - t[0]).cross(t[2] - t[0]);
    const double length = n.norm();
    if (!(length > 0.0)) continue;
    const double low = std::min({t[0].z(), t[1].z(), t[2].z()});
    const double high = std::max({t[0].z(), t[1].z(), t[2].z()});
    lowest = std::min(lowest, low);
    const double nz = n.z() / length;
    if (nz < kDownNz) ground = std::min(ground, low);
    if (nz <= kRoofNz) continue;
    roof.push_back(t);
    h.roof_area += 0.5 * n.z();
    h.roof_min = std::min(h.roof_min, low);
    h.roof_max = std::max(h.roof_max, high);
    const std::size_t f = m.triangle_face[i];
    if (f >= roof_face.size()) roof_face.resize(f + 1, false);
    roof_face[f] = true;
  }
  if (roof.empty() || !(h.roof_area > 0.0)) {
    return kernel::Error{ErrorCode::DegenerateGeometry, "the solid has no roof seen from above"};
  }
  h.ground = std::isfinite(ground) ? ground : lowest;
  h.roof_faces = static_cast<std::size_t>(std::count(roof_face.begin(), roof_face.end(), true));
  h.roof_50p = roof_percentile(roof, h.roof_area, h.roof_min, h.roof_max, 0.5);
  h.roof_70p = roof_percentile(roof, h.roof_area, h.roof_min, h.roof_max, 0.7);
  return out;
}

Vec3 ring_normal(const std::vector<Vec3>& ring) {
  Vec3 n = Vec3::Zero();
  for (std::size_t i = 0; i < ring.size(); ++i) n += ring[i].cross(ring[(i + 1) % ring.size()]);
  return n;
}

}  // namespace

kernel::Result<BuildingHeights> building_heights(const kernel::Shape& shape,
                                                 double chordal_tolerance) {
  auto measured = measure(shape, chordal_tolerance);
  if (!measured.ok()) return measured.error();
  return measured.value().heights;
}

kernel::Result<BlockModel> block_model(const kernel::CsgModel& model,
                                       const BlockModelOptions& options) {
  if (model.shape.is_null() || model.nodes.empty()) {
    return kernel::Error{ErrorCode::InvalidArgument,
                         "the model has no CSG history: its leaves cannot tell a building"};
  }
  for (std::size_t k = 0; k < model.nodes.size(); ++k) {
    const kernel::CsgNode& node = model.nodes[k];
    if (node.kind != kernel::CsgNodeKind::Primitive) continue;
    const kernel::PrimitiveSpec& s = node.primitive;
    if (s.type != kernel::PrimitiveType::Extrusion && s.type != kernel::PrimitiveType::Box) {
      return kernel::Error{ErrorCode::InvalidArgument, "leaf " + std::to_string(k) + " is a " +
                                                           kernel::primitive_type_name(s.type) +
                                                           ", not an extrusion or a box"};
    }
  }
  auto measured = measure(model.shape, options.chordal_tolerance);
  if (!measured.ok()) return measured.error();
  const kernel::Mesh& mesh = measured.value().mesh;
  BlockModel out;
  out.heights = measured.value().heights;
  const double ground = out.heights.ground, top = out.heights.roof_70p;
  if (!(top - ground > 100.0 * options.tolerance)) {
    return kernel::Error{ErrorCode::DegenerateGeometry,
                         "the roof's 70th percentile is not above the ground"};
  }

  // The footprint: every face seen from below, as an extrusion from the ground to the top.
  const kernel::EdgePoints edge_points = kernel::mesh_edge_points(model.shape, mesh);
  const kernel::ShapeIndex faces = kernel::map_child_shapes(model.shape, kernel::ShapeKind::Face);
  std::vector<kernel::CsgModel> pieces;
  for (std::size_t f = 0; f < faces.size(); ++f) {
    const kernel::Shape& face = faces[f];
    if (face.orientation() != kernel::Orientation::Forward &&
        face.orientation() != kernel::Orientation::Reversed) {
      continue;  // Internal and External faces bound nothing
    }
    const bool planar = face.body().face()->surface->kind() == kernel::SurfaceKind::Plane;
    auto rings = planar ? kernel::planar_face_rings(face, edge_points) : std::nullopt;
    if (!rings) continue;  // curved faces do not occur on extrusions and boxes cut by planes
    const Vec3 n = ring_normal(rings->front());
    if (!(n.norm() > 0.0) || n.z() / n.norm() >= -kSeenFromBelow) continue;
    kernel::PrimitiveSpec spec;
    spec.type = kernel::PrimitiveType::Extrusion;
    spec.height = top - ground;
    spec.placement = kernel::Location::translation(Vec3(0.0, 0.0, ground));
    for (std::size_t r = 0; r < rings->size(); ++r) {
      std::vector<Vec2> ring;
      for (const Vec3& p : (*rings)[r]) ring.emplace_back(p.x(), p.y());
      if (r == 0) {
        spec.profile = std::move(ring);
      } else {
        spec.holes.push_back(std::move(ring));
      }
    }
    auto piece =
        kernel::csg_primitive(spec, "footprint face " + std::to_string(f), options.tolerance);
    if (!piece.ok()) {
      return kernel::Error{piece.error().code,
                           "footprint face " + std::to_string(f) + ": " + piece.error().message};
    }
    pieces.push_back(std::move(piece).value());
  }
  if (pieces.empty()) {
    return kernel::Error{ErrorCode::DegenerateGeometry, "the solid has no face seen from below"};
  }
  if (pieces.size() == 1) {
    out.model = std::move(pieces.front());
  } else {
    kernel::BooleanOptions b;
    b.tolerance = options.tolerance;
    auto fused = kernel::csg_combine(pieces, kernel::BooleanOp::Fuse, b);
    if (!fused.ok()) return fused.error();
    out.model = std::move(fused).value();
  }
  const std::size_t solids =
      kernel::map_child_shapes(out.model.shape, kernel::ShapeKind::Solid).size();
  if (solids != 1) {
    return kernel::Error{ErrorCode::DegenerateGeometry,
                         "the footprint is in " + std::to_string(solids) + " pieces"};
  }
  if (!kernel::check_shape(out.model.shape).valid()) {
    return kernel::Error{ErrorCode::InvalidShape, "the block fails the validity checker"};
  }
  return out;
}

}  // namespace csgtile::assembly
