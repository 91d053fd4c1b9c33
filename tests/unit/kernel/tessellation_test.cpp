// Tessellation: every primitive meshes to a closed, outward, vertex-sharing mesh within the
// chordal tolerance, whose volume converges to the exact one as the tolerance shrinks; edges
// are discretised once; placement, compounds, orientation, the general (non-row) face
// method, STL output and errors. Random draws use fixed seeds.

#include "csgtile/kernel/tessellation.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <map>
#include <numbers>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/mass_properties.h"
#include "csgtile/kernel/primitives.h"

namespace csgtile::kernel {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

// ---- helpers -------------------------------------------------------------------------------

Shape built(const Result<Shape>& shape) {
  EXPECT_TRUE(shape.ok()) << (shape.ok() ? "" : shape.error().message);
  return shape.ok() ? shape.value() : Shape();
}

Mesh mesh_of(const Shape& shape, double tolerance, bool general = false, double angular = 0.5) {
  TessellationOptions options;
  options.chordal_tolerance = tolerance;
  options.angular_tolerance = angular;
  options.general_method_only = general;
  Result<Mesh> mesh = tessellate(shape, options);
  EXPECT_TRUE(mesh.ok()) << (mesh.ok() ? "" : mesh.error().message);
  return mesh.ok() ? std::move(mesh).value() : Mesh();
}

// Distance from (rho, z) to the boundary of a profile polygon, leaving out segments on the
// axis (they bound nothing in a full revolution).
double profile_distance(const std::vector<Vec2>& profile, const Vec2& q) {
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < profile.size(); ++i) {
    const Vec2 a = profile[i], b = profile[(i + 1) % profile.size()];
    if (a.x() == 0.0 && b.x() == 0.0) continue;
    const Vec2 d = b - a;
    const double t = std::clamp((q - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
    best = std::min(best, (a + t * d - q).norm());
  }
  return best;
}

// Unsigned distance from a point to the exact boundary surface of the primitive.
using SurfaceDistance = std::function<double(const Vec3&)>;

SurfaceDistance revolution_distance(std::vector<Vec2> profile) {
  return [profile](const Vec3& p) {
    return profile_distance(profile, Vec2(p.head<2>().norm(), p.z()));
  };
}

bool inside_polygon(const std::vector<Vec2>& polygon, const Vec2& q) {
  bool inside = false;
  for (std::size_t i = 0, j = polygon.size() - 1; i < polygon.size(); j = i++) {
    const Vec2 a = polygon[i], b = polygon[j];
    if ((a.y() > q.y()) != (b.y() > q.y()) &&
        q.x() < (b.x() - a.x()) * (q.y() - a.y()) / (b.y() - a.y()) + a.x()) {
      inside = !inside;
    }
  }
  return inside;
}

// Revolution by `angle` < 2π: the revolved profile plus the two planar end caps.
SurfaceDistance partial_revolution_distance(std::vector<Vec2> profile, double angle) {
  return [profile, angle](const Vec3& p) {
    double best = std::numeric_limits<double>::infinity();
    double phi = std::atan2(p.y(), p.x());
    if (phi < -1e-9) phi += kTwoPi;
    if (phi <= angle + 1e-9) best = profile_distance(profile, Vec2(p.head<2>().norm(), p.z()));
    for (double cap : {0.0, angle}) {
      const Vec3 radial(std::cos(cap), std::sin(cap), 0.0),
          normal(-std::sin(cap), std::cos(cap), 0.0);
      const Vec2 q(p.dot(radial), p.z());
      double in_plane = 0.0;
      if (!inside_polygon(profile, q)) {
        in_plane = std::numeric_limits<double>::infinity();
        for (std::size_t i = 0; i < profile.size(); ++i) {
          const Vec2 a = profile[i], d = profile[(i + 1) % profile.size()] - a;
          const double t = std::clamp((q - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
          in_plane = std::min(in_plane, (a + t * d - q).norm());
        }
      }
      best = std::min(best, std::hypot(p.dot(normal), in_plane));
    }
    return best;
  };
}

// One primitive to mesh: its shape, its exact volume, the distance to its exact boundary
// (null when not easily written), its smallest radius of curvature (for error bounds).
struct PrimitiveCase {
  std::string name;
  std::function<Result<Shape>()> make;
  double exact_volume;
  SurfaceDistance distance;
  double min_radius;
};

std::vector<PrimitiveCase> primitive_cases() {
  const std::vector<Vec2> vase{{0, 0}, {2, 0}, {2, 1}, {1, 2}, {1, 3}, {0, 3}};
  // Volume of revolution of a polygon: 2π · (area · centroid rho) (Pappus).
  auto pappus = [](const std::vector<Vec2>& profile, double angle) {
    double moment = 0.0;  // ∬ rho d(rho) dz
    for (std::size_t i = 0; i < profile.size(); ++i) {
      const Vec2 a = profile[i], b = profile[(i + 1) % profile.size()];
      const double cross = a.x() * b.y() - b.x() * a.y();
      moment += cross * (a.x() + b.x()) / 6.0;
    }
    return angle * std::abs(moment);
  };
  const std::vector<Vec2> wedge{{0, 0}, {2, 0}, {1, 2}, {0, 2}};
  const std::vector<Vec2> ring{{1, 0}, {2, 0}, {2, 1}, {1, 1}};
  return {
      {"box", [] { return make_box(2, 3, 4); }, 24.0,
       [](const Vec3& p) {
         const Vec3 q = (p - Vec3(1, 1.5, 2)).cwiseAbs() - Vec3(1, 1.5, 2);
         return std::abs(std::min(q.maxCoeff(), 0.0) + q.cwiseMax(0.0).norm());
       },
       std::numeric_limits<double>::infinity()},
      {"cylinder", [] { return make_cylinder(1.0, 2.0); }, kPi * 2.0,
       revolution_distance({{0, 0}, {1, 0}, {1, 2}, {0, 2}}), 1.0},
      {"frustum", [] { return make_cone(1.5, 0.5, 2.0); }, kPi * 2.0 / 3.0 * (2.25 + 0.75 + 0.25),
       revolution_distance({{0, 0}, {1.5, 0}, {0.5, 2}, {0, 2}}), 0.5},
      {"cone_apex_top", [] { return make_cone(1.0, 0.0, 2.0); }, kPi * 2.0 / 3.0,
       revolution_distance({{0, 0}, {1, 0}, {0, 2}}), 1.0},
      {"cone_apex_bottom", [] { return make_cone(0.0, 1.0, 1.5); }, kPi * 1.5 / 3.0,
       revolution_distance({{0, 0}, {1, 1.5}, {0, 1.5}}), 1.0},
      {"sphere", [] { return make_sphere(1.0); }, 4.0 / 3.0 * kPi,
       [](const Vec3& p) { return std::abs(p.norm() - 1.0); }, 1.0},
      {"torus", [] { return make_torus(2.0, 0.5); }, 2.0 * kPi * kPi * 2.0 * 0.25,
       [](const Vec3& p) { return std::abs(std::hypot(p.head<2>().norm() - 2.0, p.z()) - 0.5); },
       0.5},
      {"extrusion_with_hole",
       [] {
         return make_extrusion({{0, 0}, {4, 0}, {4, 3}, {2, 4}, {0, 3}},
                               {{{1, 1}, {2, 1}, {2, 2}, {1, 2}}}, 2.0);
       },
       (12.0 + 2.0 - 1.0) * 2.0, nullptr, std::numeric_limits<double>::infinity()},
      {"full_revolution_touching_axis", [vase] { return make_revolution(vase, kTwoPi); },
       pappus(vase, kTwoPi), revolution_distance(vase), 1.0},
      {"partial_revolution_touching_axis", [wedge] { return make_revolution(wedge, 1.5 * kPi); },
       pappus(wedge, 1.5 * kPi), partial_revolution_distance(wedge, 1.5 * kPi), 1.0},
      {"partial_revolution_ring", [ring] { return make_revolution(ring, 0.5 * kPi); },
       pappus(ring, 0.5 * kPi), partial_revolution_distance(ring, 0.5 * kPi), 1.0},
  };
}

// Sample points of a triangle: corners, edge midpoints, centre.
std::vector<Vec3> triangle_samples(const Mesh& mesh, const std::array<std::uint32_t, 3>& t) {
  const Vec3& a = mesh.vertices[t[0]];
  const Vec3& b = mesh.vertices[t[1]];
  const Vec3& c = mesh.vertices[t[2]];
  return {a, b, c, 0.5 * (a + b), 0.5 * (b + c), 0.5 * (c + a), (a + b + c) / 3.0};
}

// Largest distance from an edge's arc to the chords between its consecutive mesh vertices.
double max_edge_chord_error(const Shape& edge, const std::vector<std::uint32_t>& ids,
                            const Mesh& mesh) {
  const EdgeData& data = *edge.body().edge();
  if (data.degenerate()) return 0.0;
  const CurvePtr curve = data.curve;
  const Location& loc = edge.location();
  double worst = 0.0;
  double previous_t = data.first;
  for (std::size_t i = 0; i + 1 < ids.size(); ++i) {
    const Vec3 a = mesh.vertices[ids[i]], b = mesh.vertices[ids[i + 1]];
    const double t1 = i + 2 == ids.size() ? data.last
                                          : curve->closest_parameter(loc.inverse().apply_point(b),
                                                                     data.first, data.last);
    for (int k = 1; k < 16; ++k) {
      const Vec3 p = loc.apply_point(curve->point(previous_t + (t1 - previous_t) * k / 16.0));
      const Vec3 d = b - a;
      const double s = std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
      worst = std::max(worst, (a + s * d - p).norm());
    }
    previous_t = t1;
  }
  return worst;
}

// Number of pairs of mesh vertices closer than `eps`.
std::size_t coincident_vertices(const Mesh& mesh, double eps) {
  std::vector<std::size_t> order(mesh.vertices.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return mesh.vertices[a].x() < mesh.vertices[b].x();
  });
  std::size_t count = 0;
  for (std::size_t i = 0; i < order.size(); ++i) {
    for (std::size_t j = i + 1; j < order.size(); ++j) {
      const Vec3& p = mesh.vertices[order[i]];
      const Vec3& q = mesh.vertices[order[j]];
      if (q.x() - p.x() > eps) break;
      if ((p - q).norm() <= eps) ++count;
    }
  }
  return count;
}

// Connected components of triangles sharing a vertex; returns each component's triangles.
std::vector<Mesh> components(const Mesh& mesh) {
  std::vector<std::size_t> parent(mesh.vertices.size());
  std::iota(parent.begin(), parent.end(), 0);
  std::function<std::size_t(std::size_t)> root = [&](std::size_t v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  for (const auto& t : mesh.triangles) {
    parent[root(t[1])] = root(t[0]);
    parent[root(t[2])] = root(t[0]);
  }
  std::map<std::size_t, Mesh> parts;
  for (const auto& t : mesh.triangles) {
    Mesh& part = parts[root(t[0])];
    part.vertices = mesh.vertices;
    part.triangles.push_back(t);
  }
  std::vector<Mesh> out;
  for (auto& [r, part] : parts) out.push_back(std::move(part));
  return out;
}

Location random_similarity(std::mt19937& rng, double* scale_out) {
  std::normal_distribution<double> n(0.0, 1.0);
  const Eigen::Quaterniond q = Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized();
  std::uniform_real_distribution<double> scale(0.3, 3.0), offset(-50.0, 50.0);
  const double s = scale(rng);
  Matrix34 m;
  m.leftCols<3>() = s * q.toRotationMatrix();
  m.col(3) = Vec3(offset(rng), offset(rng), offset(rng));
  const Result<Location> loc = Location::from_matrix(m);
  EXPECT_TRUE(loc.ok());
  *scale_out = loc.ok() ? loc.value().scale() : 1.0;
  return loc.ok() ? loc.value() : Location();
}

// ---- every primitive ------------------------------------------------------------------------

void PrintTo(const PrimitiveCase& c, std::ostream* os) { *os << c.name; }

class TessellationPrimitive : public ::testing::TestWithParam<PrimitiveCase> {};

TEST_P(TessellationPrimitive, ClosedOutwardWithinToleranceAndConverging) {
  const PrimitiveCase& c = GetParam();
  const Shape shape = built(c.make());
  ASSERT_FALSE(shape.is_null());
  ASSERT_NEAR(mass_properties(shape).volume, c.exact_volume, 1e-9 * c.exact_volume);
  const ShapeIndex edges = map_child_shapes(shape, ShapeKind::Edge);
  const ShapeIndex faces = map_child_shapes(shape, ShapeKind::Face);
  double previous_error = std::numeric_limits<double>::infinity();
  for (double tolerance : {1e-1, 3e-2, 1e-2, 3e-3, 1e-3}) {
    SCOPED_TRACE("tolerance " + std::to_string(tolerance));
    const Mesh mesh = mesh_of(shape, tolerance);
    EXPECT_TRUE(mesh_is_closed(mesh));
    ASSERT_EQ(mesh.triangle_face.size(), mesh.triangles.size());
    ASSERT_EQ(mesh.edge_vertices.size(), edges.size());
    std::vector<int> per_face(faces.size(), 0);
    for (std::uint32_t f : mesh.triangle_face) {
      ASSERT_LT(f, faces.size());
      ++per_face[f];
    }
    for (std::size_t f = 0; f < faces.size(); ++f) EXPECT_GT(per_face[f], 0) << "face " << f;

    const double volume = mesh_volume(mesh);
    EXPECT_GT(volume, 0.0);
    const double error = std::abs(volume - c.exact_volume);
    EXPECT_LE(error, previous_error);
    previous_error = error;
    // An inscribed mesh loses about (4/3)·sagitta/radius of volume along one curved
    // direction and 2·sagitta/radius on doubly curved faces.
    if (std::isfinite(c.min_radius)) {
      EXPECT_LE(error / c.exact_volume, 3.0 * tolerance / std::min(c.min_radius, 1.0));
    } else {
      EXPECT_NEAR(volume, c.exact_volume, 1e-12 * c.exact_volume);
    }

    for (const auto& t : mesh.triangles) {
      const Vec3 n = (mesh.vertices[t[1]] - mesh.vertices[t[0]])
                         .cross(mesh.vertices[t[2]] - mesh.vertices[t[0]]);
      EXPECT_GT(n.norm(), 0.0);
    }
    EXPECT_EQ(coincident_vertices(mesh, 1e-9), 0u);

    if (c.distance) {
      double worst_vertex = 0.0, worst_sample = 0.0;
      for (const Vec3& p : mesh.vertices) worst_vertex = std::max(worst_vertex, c.distance(p));
      for (const auto& t : mesh.triangles) {
        for (const Vec3& p : triangle_samples(mesh, t)) {
          worst_sample = std::max(worst_sample, c.distance(p));
        }
      }
      EXPECT_LE(worst_vertex, 1e-9);
      EXPECT_LE(worst_sample, tolerance * (1.0 + 1e-6));
    }
    for (std::size_t e = 0; e < edges.size(); ++e) {
      EXPECT_LE(max_edge_chord_error(edges[e], mesh.edge_vertices[e], mesh), tolerance * (1 + 1e-9))
          << "edge " << e;
    }
  }
}

TEST_P(TessellationPrimitive, VolumeErrorBelowOnePerMilleAtQuarterPerMilleTolerance) {
  // The mesh is inscribed, so at tolerance t the relative volume error is about
  // (4/3)·t/r (one curved direction) to 2·t/r (sphere): 1e-3 needs t ≈ r/4000.
  const PrimitiveCase& c = GetParam();
  const Shape shape = built(c.make());
  const double tolerance = 2.5e-4 * std::min(1.0, c.min_radius);
  const Mesh mesh = mesh_of(shape, tolerance);
  EXPECT_TRUE(mesh_is_closed(mesh));
  EXPECT_LT(std::abs(mesh_volume(mesh) - c.exact_volume) / c.exact_volume, 1e-3);
}

INSTANTIATE_TEST_SUITE_P(AllPrimitives, TessellationPrimitive,
                         ::testing::ValuesIn(primitive_cases()),
                         [](const auto& test) { return test.param.name; });

// ---- shared edges ---------------------------------------------------------------------------

TEST(TessellationEdges, CylinderCircleIsSampledOnceAndSharedByItsFaces) {
  const double r = 1.5, h = 1.0, tolerance = 1e-3, angular = 0.5;
  const Shape cylinder = built(make_cylinder(r, h));
  const Mesh mesh = mesh_of(cylinder, tolerance, false, angular);
  // A circle of radius r needs n equal steps of at most min(angular, 2·acos(1 - t/r)).
  const auto expected = static_cast<std::size_t>(
      std::ceil(kTwoPi / std::min(angular, 2.0 * std::acos(1.0 - tolerance / r)) - 1e-9));
  const ShapeIndex edges = map_child_shapes(cylinder, ShapeKind::Edge);
  std::size_t circles = 0;
  for (std::size_t e = 0; e < edges.size(); ++e) {
    const EdgeData& data = *edges[e].body().edge();
    if (data.curve->kind() != CurveKind::Circle) {
      EXPECT_EQ(mesh.edge_vertices[e].size(), 2u) << "a line keeps its two vertices only";
      continue;
    }
    ++circles;
    // Closed edge: n + 1 entries, the first and last its single vertex.
    ASSERT_EQ(mesh.edge_vertices[e].size(), expected + 1);
    EXPECT_EQ(mesh.edge_vertices[e].front(), mesh.edge_vertices[e].back());
    EXPECT_EQ(discretize_edge(edges[e], tolerance, angular).size(), expected + 1);
    const double z = mesh.vertices[mesh.edge_vertices[e].front()].z();
    std::size_t on_circle = 0;
    for (const Vec3& p : mesh.vertices) {
      if (std::abs(p.z() - z) < 1e-9 && std::abs(p.head<2>().norm() - r) < 1e-9) ++on_circle;
    }
    EXPECT_EQ(on_circle, expected);
  }
  EXPECT_EQ(circles, 2u);
  // 2 circles of n points, no interior points: the lateral face is one strip, the discs fans.
  EXPECT_EQ(mesh.vertices.size(), 2 * expected);
  EXPECT_EQ(mesh.triangles.size(), 2 * expected + 2 * (expected - 2));
  EXPECT_EQ(coincident_vertices(mesh, 1e-12), 0u);
}

TEST(TessellationEdges, LinesKeepTheirEndsAndPolylinesTheirBreakpoints) {
  const Shape a = built(ShapeFactory::vertex(Vec3(0, 0, 0), 1e-7));
  const Shape b = built(ShapeFactory::vertex(Vec3(3, 0, 0), 1e-7));
  const Shape line = built(ShapeFactory::edge(
      std::make_shared<LineCurve>(Vec3::Zero(), Vec3::UnitX()), 0.0, 3.0, a, b, 1e-7));
  EXPECT_EQ(discretize_edge(line, 1e-6, 0.1), (std::vector<double>{0.0, 3.0}));
  auto polyline = std::make_shared<PolylineCurve>(
      std::vector<Vec3>{{0, 0, 0}, {1, 1, 0}, {2, 0, 0}, {3, 0, 0}}, 0.0);
  const Shape poly = built(ShapeFactory::edge(polyline, 0.0, 3.0, a, b, 1e-7));
  EXPECT_EQ(discretize_edge(poly, 1.0, 3.0), (std::vector<double>{0.0, 1.0, 2.0, 3.0}));
}

TEST(TessellationEdges, EllipseChordsStayWithinTolerance) {
  auto ellipse = std::make_shared<EllipseCurve>(Frame(), 3.0, 1.0);
  const Shape v = built(ShapeFactory::vertex(Vec3(3, 0, 0), 1e-7));
  const Shape edge = built(ShapeFactory::edge(ellipse, 0.0, kTwoPi, v, v, 1e-7));
  for (double tolerance : {1e-1, 1e-2, 1e-3}) {
    const std::vector<double> t = discretize_edge(edge, tolerance, 0.5);
    ASSERT_GE(t.size(), 4u);
    double worst = 0.0;
    for (std::size_t i = 0; i + 1 < t.size(); ++i) {
      const Vec3 a = ellipse->point(t[i]), b = ellipse->point(t[i + 1]);
      for (int k = 1; k < 32; ++k) {
        const Vec3 p = ellipse->point(t[i] + (t[i + 1] - t[i]) * k / 32.0);
        const Vec3 d = b - a;
        worst = std::max(worst, (a + (p - a).dot(d) / d.squaredNorm() * d - p).norm());
      }
    }
    EXPECT_LE(worst, tolerance);
  }
}

// ---- placement, compounds, orientation -------------------------------------------------------

TEST(TessellationPlacement, RandomSimilarityScalesVolumeByCube) {
  std::mt19937 rng(20240611);
  const std::vector<Shape> shapes{built(make_box(1, 2, 3)), built(make_cylinder(1, 2)),
                                  built(make_sphere(1.5)), built(make_torus(2, 0.5)),
                                  built(make_cone(1, 0, 2))};
  for (int trial = 0; trial < 10; ++trial) {
    double s = 1.0;
    const Location loc = random_similarity(rng, &s);
    const Shape& shape = shapes[static_cast<std::size_t>(trial) % shapes.size()];
    const Mesh local = mesh_of(shape, 1e-2);
    // The same tolerance relative to the size gives the same sampling, so the volumes match.
    const Mesh placed = mesh_of(shape.moved(loc), 1e-2 * s);
    EXPECT_TRUE(mesh_is_closed(placed));
    EXPECT_EQ(placed.triangles.size(), local.triangles.size());
    EXPECT_EQ(placed.vertices.size(), local.vertices.size());
    EXPECT_NEAR(mesh_volume(placed), s * s * s * mesh_volume(local),
                1e-9 * s * s * s * mesh_volume(local));
    EXPECT_NEAR(mesh_area(placed), s * s * mesh_area(local), 1e-9 * s * s * mesh_area(local));
    for (std::size_t i = 0; i < local.vertices.size(); ++i) {
      EXPECT_LE((placed.vertices[i] - loc.apply_point(local.vertices[i])).norm(),
                1e-9 * (1 + s) * 60);
    }
  }
}

TEST(TessellationCompound, TwoSolidsGiveTwoClosedComponents) {
  const Shape sphere = built(make_sphere(1.0));
  const Shape box = built(make_box(1, 1, 1)).moved(Location::translation(Vec3(5, 0, 0)));
  const Shape compound = built(ShapeFactory::compound({sphere, box}));
  const Mesh mesh = mesh_of(compound, 1e-2);
  EXPECT_TRUE(mesh_is_closed(mesh));
  const std::vector<Mesh> parts = components(mesh);
  ASSERT_EQ(parts.size(), 2u);
  for (const Mesh& part : parts) EXPECT_TRUE(mesh_is_closed(part));
  EXPECT_NEAR(mesh_volume(mesh), mesh_volume(mesh_of(sphere, 1e-2)) + 1.0, 1e-9);
}

TEST(TessellationCompound, SameSolidPlacedTwiceSharesNothing) {
  const Shape cylinder = built(make_cylinder(1, 1));
  const Shape compound = built(
      ShapeFactory::compound({cylinder, cylinder.moved(Location::translation(Vec3(0, 0, 3)))}));
  const Mesh mesh = mesh_of(compound, 1e-2);
  const Mesh single = mesh_of(cylinder, 1e-2);
  EXPECT_TRUE(mesh_is_closed(mesh));
  EXPECT_EQ(components(mesh).size(), 2u);
  EXPECT_EQ(mesh.vertices.size(), 2 * single.vertices.size());
  EXPECT_NEAR(mesh_volume(mesh), 2.0 * mesh_volume(single), 1e-9);
}

TEST(TessellationOrientation, ReversedSolidTurnsInsideOut) {
  const Shape sphere = built(make_sphere(1.0));
  const Mesh forward = mesh_of(sphere, 1e-2);
  const Mesh reversed = mesh_of(sphere.reversed(), 1e-2);
  EXPECT_TRUE(mesh_is_closed(reversed));
  EXPECT_NEAR(mesh_volume(reversed), -mesh_volume(forward), 1e-12);
}

TEST(TessellationOrientation, TrianglesFaceAlongTheOutwardNormal) {
  // Every triangle's normal points away from the centre of these star-shaped solids.
  for (const Shape& shape :
       {built(make_sphere(1.0)),
        built(make_cylinder(1, 2).value().moved(Location::translation(Vec3(0, 0, -1)))),
        built(make_box(2, 2, 2).value().moved(Location::translation(Vec3(-1, -1, -1))))}) {
    const Mesh mesh = mesh_of(shape, 1e-2);
    for (const auto& t : mesh.triangles) {
      const Vec3& a = mesh.vertices[t[0]];
      const Vec3 n = (mesh.vertices[t[1]] - a).cross(mesh.vertices[t[2]] - a);
      EXPECT_GT(n.dot((a + mesh.vertices[t[1]] + mesh.vertices[t[2]]) / 3.0), 0.0);
    }
  }
}

// ---- general method -------------------------------------------------------------------------

TEST(TessellationGeneralMethod, PlanarFacesMatchTheirBoundaryExactly) {
  const Shape extrusion = built(make_extrusion(
      {{0, 0}, {6, 0}, {6, 4}, {3, 2}, {0, 4}},
      {{{1, 0.5}, {2, 0.5}, {2, 1.5}, {1, 1.5}}, {{4, 0.5}, {5, 0.5}, {4.5, 1.5}}}, 1.0));
  const double exact = mass_properties(extrusion).volume;
  for (bool general : {false, true}) {
    const Mesh mesh = mesh_of(extrusion, 1e-3, general);
    EXPECT_TRUE(mesh_is_closed(mesh));
    EXPECT_NEAR(mesh_volume(mesh), exact, 1e-12 * exact);
    EXPECT_NEAR(mesh_area(mesh), mass_properties(extrusion).area, 1e-12 * exact);
    // Planar faces add no points: only the polygon's vertices.
    EXPECT_EQ(mesh.vertices.size(), 2u * 12u);
  }
}

// A roof part of a real Delft building (regressions: its LoD1.3 block failed): three of its
// corners lie on one line in the profile, which the footprint's rotated parameter plane puts
// a few ulps apart. The ear clipper must still see the middle one on the diagonal.
TEST(TessellationGeneralMethod, CollinearCornersInARotatedFaceStayOnTheirDiagonal) {
  const std::vector<Vec2> profile{
      {-2.0733454009053389, 2.5175826344429879},  {-0.15699992849843625, -1.3151083103708174},
      {-2.1073227092042117, -3.9155386846451705}, {0.49310766507015558, -6.5159690589195378},
      {0.49310766507015558, -7.8161842460567215}, {1.0038710461229527, -7.8161842460567215},
      {1.0038710461229527, 1.2853220639035499},   {-0.15699992849843625, 1.2853220639035499},
      {-0.15699992849843625, 3.2356448446093395}, {1.0038710461229527, 3.2356448446093395},
      {1.0038710461229527, 6.4861828124522845},   {0.73475427618062383, 6.4861828124522845},
      {-1.0847858952077871, 2.8471024696755052}};
  const Shape part = built(make_extrusion(profile, {}, 15.567196758674289));
  Matrix34 m = Matrix34::Zero();
  m.block<2, 2>(0, 0) << 0.70802126353892014, -0.70619111462602746, 0.70619111462602746,
      0.70802126353892014;
  m(2, 2) = 1.0;
  m.col(3) = Vec3(253.35012167920115, 46.876210053146423, -0.13185714285714278);
  const auto loc = Location::from_matrix(m);
  ASSERT_TRUE(loc.ok());
  const Shape placed = part.moved(loc.value());
  const Mesh mesh = mesh_of(placed, 1e-2);
  EXPECT_TRUE(mesh_is_closed(mesh));
  const double exact = mass_properties(placed).volume;
  EXPECT_NEAR(mesh_volume(mesh), exact, 1e-9 * exact);
}

TEST(TessellationGeneralMethod, CurvedPrimitivesConvergeWithoutRows) {
  for (const PrimitiveCase& c : primitive_cases()) {
    if (c.name != "cylinder" && c.name != "sphere" && c.name != "torus" &&
        c.name != "cone_apex_top" && c.name != "partial_revolution_touching_axis") {
      continue;
    }
    SCOPED_TRACE(c.name);
    const Shape shape = built(c.make());
    double previous = std::numeric_limits<double>::infinity();
    for (double tolerance : {3e-2, 1e-2, 3e-3}) {
      const Mesh mesh = mesh_of(shape, tolerance, /*general=*/true);
      EXPECT_TRUE(mesh_is_closed(mesh));
      const double error = std::abs(mesh_volume(mesh) - c.exact_volume) / c.exact_volume;
      EXPECT_LE(error, 3.0 * tolerance / std::min(c.min_radius, 1.0));
      EXPECT_LE(error, previous * 1.05);
      previous = error;
      if (c.distance) {
        for (const auto& t : mesh.triangles) {
          for (const Vec3& p : triangle_samples(mesh, t)) {
            ASSERT_LE(c.distance(p), tolerance * (1.0 + 1e-6));
          }
        }
      }
    }
  }
}

// ---- mesh utilities -------------------------------------------------------------------------

TEST(MeshUtilities, ClosednessNeedsEveryEdgeTwiceInOppositeDirections) {
  const Mesh cube = mesh_of(built(make_box(1, 1, 1)), 0.1);
  ASSERT_TRUE(mesh_is_closed(cube));
  EXPECT_EQ(cube.triangles.size(), 12u);
  Mesh open = cube;
  open.triangles.pop_back();
  EXPECT_FALSE(mesh_is_closed(open));
  Mesh flipped = cube;
  std::swap(flipped.triangles[0][1], flipped.triangles[0][2]);
  EXPECT_FALSE(mesh_is_closed(flipped));
  EXPECT_TRUE(mesh_is_closed(Mesh{}));
  EXPECT_NEAR(mesh_volume(cube), 1.0, 1e-15);
  EXPECT_NEAR(mesh_area(cube), 6.0, 1e-15);
}

TEST(MeshUtilities, BinaryStlLayout) {
  const Mesh cube = mesh_of(built(make_box(1, 2, 3)), 0.1);
  const std::string stl = to_binary_stl(cube);
  ASSERT_EQ(stl.size(), 84u + 50u * cube.triangles.size());
  EXPECT_NE(stl.substr(0, 5), "solid");  // readers take "solid" for ASCII STL
  std::uint32_t count = 0;
  for (int i = 0; i < 4; ++i)
    count |= static_cast<std::uint32_t>(static_cast<unsigned char>(stl[80 + i])) << (8 * i);
  EXPECT_EQ(count, cube.triangles.size());
  auto read_float = [&](std::size_t offset) {
    std::uint32_t bits = 0;
    for (int i = 0; i < 4; ++i) {
      bits |= static_cast<std::uint32_t>(static_cast<unsigned char>(stl[offset + i])) << (8 * i);
    }
    float f;
    std::memcpy(&f, &bits, sizeof f);
    return f;
  };
  for (std::size_t t = 0; t < cube.triangles.size(); ++t) {
    const std::size_t base = 84 + 50 * t;
    const Vec3& a = cube.vertices[cube.triangles[t][0]];
    const Vec3 n = (cube.vertices[cube.triangles[t][1]] - a)
                       .cross(cube.vertices[cube.triangles[t][2]] - a)
                       .normalized();
    for (int i = 0; i < 3; ++i) {
      EXPECT_FLOAT_EQ(read_float(base + 4 * i), static_cast<float>(n[i]));
      EXPECT_FLOAT_EQ(read_float(base + 12 + 4 * i), static_cast<float>(a[i]));
    }
    EXPECT_EQ(stl[base + 48], '\0');
    EXPECT_EQ(stl[base + 49], '\0');
  }
}

TEST(MeshUtilities, TessellationIsDeterministic) {
  const Shape shape =
      built(make_revolution({{0, 0}, {2, 0}, {2, 1}, {1, 2}, {1, 3}, {0, 3}}, kTwoPi));
  EXPECT_EQ(to_binary_stl(mesh_of(shape, 1e-3)), to_binary_stl(mesh_of(shape, 1e-3)));
  EXPECT_EQ(to_binary_stl(mesh_of(shape, 1e-2, true)), to_binary_stl(mesh_of(shape, 1e-2, true)));
}

TEST(TessellationErrors, RejectsNullShapesAndBadTolerances) {
  EXPECT_EQ(tessellate(Shape()).error().code, ErrorCode::InvalidArgument);
  const Shape box = built(make_box(1, 1, 1));
  for (double bad : {0.0, -1.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
    TessellationOptions options;
    options.chordal_tolerance = bad;
    EXPECT_FALSE(tessellate(box, options).ok()) << bad;
    options = {};
    options.angular_tolerance = bad;
    EXPECT_FALSE(tessellate(box, options).ok()) << bad;
  }
  TessellationOptions tiny;
  tiny.chordal_tolerance = 1e-15;
  const Result<Mesh> too_fine = tessellate(built(make_cylinder(1e3, 1)), tiny);
  ASSERT_FALSE(too_fine.ok());
  EXPECT_EQ(too_fine.error().code, ErrorCode::InvalidArgument);
}

TEST(TessellationAngular, CoarseChordalToleranceStillBoundsTheTurn) {
  // With a huge chordal tolerance the angular one decides: a circle gets ceil(2π / 0.5)
  // points, and angular tolerances above 2π/3 still leave three.
  const Shape cylinder = built(make_cylinder(1, 1));
  EXPECT_EQ(mesh_of(cylinder, 10.0, false, 0.5).vertices.size(), 2u * 13u);
  const Mesh coarse = mesh_of(cylinder, 10.0, false, kPi);
  EXPECT_EQ(coarse.vertices.size(), 2u * 3u);
  EXPECT_TRUE(mesh_is_closed(coarse));
  const Mesh sphere = mesh_of(built(make_sphere(1)), 10.0, false, kPi);
  EXPECT_TRUE(mesh_is_closed(sphere));
  EXPECT_GT(mesh_volume(sphere), 0.0);
}

}  // namespace
}  // namespace csgtile::kernel
