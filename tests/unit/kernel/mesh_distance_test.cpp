// Point-to-mesh distances (csgtile/kernel/mesh_distance.h): known answers on a box, and the
// grid search against a scan of every triangle on curved and many-triangle meshes.

#include "csgtile/kernel/mesh_distance.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "csgtile/kernel/primitives.h"

namespace csgtile::kernel {
namespace {

Mesh mesh_of(const Result<Shape>& shape, double chordal) {
  EXPECT_TRUE(shape.ok());
  TessellationOptions t;
  t.chordal_tolerance = chordal;
  auto mesh = tessellate(shape.value(), t);
  EXPECT_TRUE(mesh.ok());
  return mesh.value();
}

double scan_distance2(const Mesh& m, const Vec3& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& k : m.triangles) {
    best =
        std::min(best, triangle_distance2(p, m.vertices[k[0]], m.vertices[k[1]], m.vertices[k[2]]));
  }
  return best;
}

TEST(MeshDistance, KnownDistancesToABox) {
  // A 4 × 2 × 3 box at the origin.
  const MeshDistance box(mesh_of(make_box(4, 2, 3), 0.01));
  EXPECT_DOUBLE_EQ(box.distance(Vec3(2, 1, 1.5)), 1.0);             // centre: the nearest side y
  EXPECT_DOUBLE_EQ(box.distance(Vec3(2, 1, 3.25)), 0.25);           // above the top
  EXPECT_NEAR(box.distance(Vec3(2, 1, 2.9)), 0.1, 1e-12);           // under the top
  EXPECT_NEAR(box.distance(Vec3(5, 3, 4)), std::sqrt(3.0), 1e-12);  // off a corner
  EXPECT_NEAR(box.distance(Vec3(-3, 1, 1.5)), 3.0, 1e-12);          // beside, far off the grid
  EXPECT_NEAR(box.distance(Vec3(2, 1, -100)), 100.0, 1e-12);        // far below
  EXPECT_EQ(box.distance(Vec3(2, 1, 0)), 0.0);                      // on the bottom
  EXPECT_TRUE(box.covers(2, 1));
  EXPECT_TRUE(box.covers(0, 0));  // a corner counts
  EXPECT_TRUE(box.covers(4, 2));
  EXPECT_FALSE(box.covers(4.001, 1));
  EXPECT_FALSE(box.covers(-0.001, 1));
  EXPECT_FALSE(box.covers(std::nan(""), 1));
}

TEST(MeshDistance, TheGridFindsWhatAScanOfEveryTriangleFinds) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-6.0, 6.0);
  PrimitiveSpec torus;
  torus.type = PrimitiveType::Torus;
  torus.radius = 3.0;
  torus.radius2 = 0.7;
  for (const auto& [what, shape] :
       {std::pair{"sphere", make_sphere(2.5)}, std::pair{"cone", make_cone(2, 0.5, 3)},
        std::pair{"torus", build_primitive(torus)}}) {
    const Mesh m = mesh_of(shape, 0.005);
    ASSERT_GT(m.triangles.size(), 100u) << what;
    const MeshDistance grid(m);
    for (int i = 0; i < 500; ++i) {
      const Vec3 p(u(rng), u(rng), u(rng));
      // The same formula, the minimum over the same triangles: the same bits.
      EXPECT_EQ(grid.distance2(p), scan_distance2(m, p)) << what << " " << p.transpose();
    }
  }
}

TEST(MeshDistance, AnEmptyMeshIsInfinitelyFarAndCoversNothing) {
  const MeshDistance none{Mesh{}};
  EXPECT_TRUE(std::isinf(none.distance(Vec3(0, 0, 0))));
  EXPECT_FALSE(none.covers(0, 0));
  EXPECT_TRUE(none.bounds().empty());
}

}  // namespace
}  // namespace csgtile::kernel
