// The efficient RANSAC on one-surface clouds with known answers: each shape type is found
// once with its parameters, degenerate input gives no shape and a reason, and the same seed
// gives the same shapes.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <stop_token>

#include "csgtile/fit/fit.h"
#include "csgtile/fit/segment.h"
#include "fit_clouds.h"

namespace csgtile::fit {
namespace {

using kernel::Vec3;
using testing::Cloud;
using testing::line_angle_deg;
using testing::line_distance;

RansacOptions options_for(double epsilon) {
  RansacOptions o;
  o.epsilon = epsilon;
  o.min_points = 50;
  o.seed = 7;
  return o;
}

// The shape with the most inliers.
const DetectedShape& largest(const RansacResult& r) {
  std::size_t best = 0;
  for (std::size_t k = 1; k < r.shapes.size(); ++k) {
    if (r.shapes[k].inliers.size() > r.shapes[best].inliers.size()) best = k;
  }
  return r.shapes[best];
}

TEST(FitRansac, CylinderSeenFromOneSideIsFoundWithItsAxisAndRadius) {
  const Vec3 axis = Vec3(0.2, 0.1, 1.0).normalized();
  const Vec3 base(1.0, 2.0, 3.0);
  const Cloud c =
      testing::cylinder_cloud(base, axis, 0.3, 2.0, 0.0, 1.5 * std::numbers::pi, 6000, 0.003, 1);
  const auto r = detect_shapes(c.points, estimate_normals(c.points, {}), options_for(0.01));
  ASSERT_TRUE(r.ok()) << r.error().message;
  ASSERT_FALSE(r->shapes.empty()) << r->reason;
  const DetectedShape& s = largest(r.value());
  EXPECT_EQ(s.surface.type, ShapeType::Cylinder);
  EXPECT_NEAR(s.surface.radius, 0.3, 0.005);
  EXPECT_LT(line_angle_deg(s.surface.axis, axis), 1.0);
  EXPECT_LT(line_distance(s.surface.point, base, axis), 0.005);
  EXPECT_GT(s.inliers.size(), 5400U);
  EXPECT_LT(s.rms, 0.005);
}

// A stop request reaches inside one region's search: the detection returns Cancelled after
// its first batch of samples, not after the whole search; an interrupt that never fires
// changes nothing.
TEST(FitRansac, AStopRequestEndsTheSearchWithCancelled) {
  const Cloud c = testing::cylinder_cloud(Vec3(0, 0, 0), Vec3::UnitZ(), 0.5, 2.0, 0.0,
                                          2.0 * std::numbers::pi, 4000, 0.002, 3);
  const auto normals = estimate_normals(c.points, {});
  RansacOptions o = options_for(0.01);
  std::stop_source source;
  o.interrupt.stop = source.get_token();
  const auto free = detect_shapes(c.points, normals, o);
  ASSERT_TRUE(free.ok()) << free.error().message;
  const auto plain = detect_shapes(c.points, normals, options_for(0.01));
  ASSERT_TRUE(plain.ok());
  EXPECT_EQ(free->assignment, plain->assignment);
  EXPECT_EQ(free->candidates, plain->candidates);
  source.request_stop();
  const auto stopped = detect_shapes(c.points, normals, o);
  ASSERT_FALSE(stopped.ok());
  EXPECT_EQ(stopped.error().code, kernel::ErrorCode::Cancelled);
  EXPECT_NE(stopped.error().message.find("while detecting shapes"), std::string::npos)
      << stopped.error().message;
}

TEST(FitRansac, ConeIsFoundWithApexAxisAndAngle) {
  const Vec3 apex(0.0, 0.0, 2.0);
  const Vec3 axis(0.0, 0.0, -1.0);
  const double angle = 30.0 * std::numbers::pi / 180.0;
  const Cloud c = testing::cone_cloud(apex, axis, angle, 0.5, 2.0, 6000, 0.002, 2);
  const auto r = detect_shapes(c.points, estimate_normals(c.points, {}), options_for(0.01));
  ASSERT_TRUE(r.ok());
  ASSERT_FALSE(r->shapes.empty()) << r->reason;
  const DetectedShape& s = largest(r.value());
  ASSERT_EQ(s.surface.type, ShapeType::Cone);
  EXPECT_LT((s.surface.point - apex).norm(), 0.02);
  EXPECT_GT(s.surface.axis.dot(axis), std::cos(1.0 * std::numbers::pi / 180.0));
  EXPECT_NEAR(s.surface.angle, angle, 0.01);
  EXPECT_GT(s.inliers.size(), 5400U);
}

TEST(FitRansac, SphereCapIsFoundWithCentreAndRadius) {
  const Vec3 centre(1.0, 1.0, 1.0);
  const Cloud c = testing::sphere_cloud(centre, 0.8, -0.2, 6000, 0.003, 3);
  const auto r = detect_shapes(c.points, estimate_normals(c.points, {}), options_for(0.01));
  ASSERT_TRUE(r.ok());
  ASSERT_FALSE(r->shapes.empty()) << r->reason;
  const DetectedShape& s = largest(r.value());
  ASSERT_EQ(s.surface.type, ShapeType::Sphere);
  EXPECT_LT((s.surface.point - centre).norm(), 0.005);
  EXPECT_NEAR(s.surface.radius, 0.8, 0.005);
}

TEST(FitRansac, TorusIsFoundWithBothRadii) {
  const Vec3 centre(-4.0, 4.0, 3.45);
  const Vec3 axis(0.0, 1.0, 0.0);
  const Cloud c = testing::torus_cloud(centre, axis, 2.5, 0.35, 20000, 0.003, 4);
  auto o = options_for(0.01);
  const auto r = detect_shapes(c.points, estimate_normals(c.points, {}), o);
  ASSERT_TRUE(r.ok());
  ASSERT_FALSE(r->shapes.empty()) << r->reason;
  const DetectedShape& s = largest(r.value());
  ASSERT_EQ(s.surface.type, ShapeType::Torus);
  EXPECT_LT((s.surface.point - centre).norm(), 0.01);
  EXPECT_LT(line_angle_deg(s.surface.axis, axis), 1.0);
  EXPECT_NEAR(s.surface.radius, 2.5, 0.01);
  EXPECT_NEAR(s.surface.radius2, 0.35, 0.005);
  EXPECT_GT(s.inliers.size(), 18000U);
}

TEST(FitRansac, PlaneRectangleIsOnePlaneNotACurvedShape) {
  const Cloud c =
      testing::rectangle_cloud(Vec3(0, 0, 0), Vec3(3, 0, 0), Vec3(0, 0.3, 0.2), 0.01, 0.002, 5);
  const auto r = detect_shapes(c.points, estimate_normals(c.points, {}), options_for(0.01));
  ASSERT_TRUE(r.ok());
  ASSERT_EQ(r->shapes.size(), 1U) << r->reason;
  EXPECT_EQ(r->shapes[0].surface.type, ShapeType::Plane);
  EXPECT_LT(line_angle_deg(r->shapes[0].surface.axis, Vec3(0, -0.2, 0.3)), 0.5);
}

TEST(FitRansac, EmptyInputGivesNoShapeAndAReason) {
  const std::vector<Vec3> none;
  const auto r = detect_shapes(none, none, options_for(0.01));
  ASSERT_TRUE(r.ok());
  EXPECT_TRUE(r->shapes.empty());
  EXPECT_NE(r->reason.find("no finite points"), std::string::npos) << r->reason;
}

TEST(FitRansac, CollinearPointsGiveNoShapeAndAReason) {
  std::vector<Vec3> line;
  for (int i = 0; i < 500; ++i) line.emplace_back(0.01 * i, 0.02 * i, 0.0);
  const auto normals = estimate_normals(line, {});
  for (const auto& n : normals) EXPECT_EQ(n.norm(), 0.0);  // no normal on a line
  const auto r = detect_shapes(line, normals, options_for(0.01));
  ASSERT_TRUE(r.ok());
  EXPECT_TRUE(r->shapes.empty());
  EXPECT_FALSE(r->reason.empty());
}

TEST(FitRansac, DuplicatedPointsGiveNoShapeAndAReason) {
  std::vector<Vec3> copies;
  for (int i = 0; i < 300; ++i) {
    copies.emplace_back(1, 2, 3);
    copies.emplace_back(1, 2.5, 3);
    copies.emplace_back(1.5, 2, 3.2);
  }
  const auto r = detect_shapes(copies, estimate_normals(copies, {}), options_for(0.01));
  ASSERT_TRUE(r.ok());
  EXPECT_TRUE(r->shapes.empty());
  EXPECT_FALSE(r->reason.empty());
}

TEST(FitRansac, NaNPointsAreIgnored) {
  Cloud c =
      testing::cylinder_cloud(Vec3::Zero(), Vec3::UnitZ(), 0.2, 1.0, 0.0, 2.0, 3000, 0.002, 6);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int i = 0; i < 100; ++i) c.points.insert(c.points.begin() + 7 * i, Vec3(nan, 0, nan));
  const auto r = detect_shapes(c.points, estimate_normals(c.points, {}), options_for(0.01));
  ASSERT_TRUE(r.ok());
  ASSERT_FALSE(r->shapes.empty()) << r->reason;
  EXPECT_EQ(largest(r.value()).surface.type, ShapeType::Cylinder);

  const std::vector<Vec3> all_nan(50, Vec3(nan, nan, nan));
  const auto none = detect_shapes(all_nan, estimate_normals(all_nan, {}), options_for(0.01));
  ASSERT_TRUE(none.ok());
  EXPECT_TRUE(none->shapes.empty());
  EXPECT_NE(none->reason.find("no finite points"), std::string::npos);
}

TEST(FitRansac, MismatchedNormalsAreAnError) {
  const std::vector<Vec3> p(10, Vec3::Zero()), n(9, Vec3::UnitZ());
  const auto r = detect_shapes(p, n, options_for(0.01));
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("normals"), std::string::npos);
  auto bad = options_for(-1.0);
  EXPECT_FALSE(detect_shapes(p, std::vector<Vec3>(10, Vec3::UnitZ()), bad).ok());
}

TEST(FitRansac, SameSeedSameShapes) {
  Cloud c =
      testing::cylinder_cloud(Vec3::Zero(), Vec3::UnitZ(), 0.25, 2.0, 0.0, 4.0, 4000, 0.003, 8);
  c.append(testing::sphere_cloud(Vec3(3, 0, 1), 0.6, -0.3, 3000, 0.003, 9));
  const auto normals = estimate_normals(c.points, {});
  const auto a = detect_shapes(c.points, normals, options_for(0.01));
  const auto b = detect_shapes(c.points, normals, options_for(0.01));
  ASSERT_TRUE(a.ok() && b.ok());
  ASSERT_EQ(a->shapes.size(), b->shapes.size());
  EXPECT_EQ(a->assignment, b->assignment);
  for (std::size_t k = 0; k < a->shapes.size(); ++k) {
    EXPECT_EQ(a->shapes[k].surface.radius, b->shapes[k].surface.radius);
    EXPECT_EQ(a->shapes[k].surface.point, b->shapes[k].surface.point);
  }
}

// Relabelling (issue #24 item 2): after detection no point stays with a shape when another
// shape near it explains it better (closer, and facing like it), every point that lies on a
// shape near it is taken, and each shape's inliers are exactly the points labelled with it.
// With edges_to_smaller, a point on two neighbouring shapes belongs to the smaller when that
// has at most half the other's points (and only then may stay with the farther one).
TEST(FitRansac, RelabelGivesEachPointTheShapeItFitsBest) {
  Cloud c = testing::rectangle_cloud(Vec3::Zero(), Vec3(2, 0, 0), Vec3(0, 1.5, 0), 0.03, 0.003, 41);
  c.append(testing::rectangle_cloud(Vec3::Zero(), Vec3(2, 0, 0), Vec3(0, 0, 1), 0.03, 0.003, 42));
  c.append(testing::cylinder_cloud(Vec3(1, 0.8, 0), Vec3::UnitZ(), 0.25, 0.7, 0.0,
                                   2.0 * std::numbers::pi, 1500, 0.003, 43));
  const auto normals = estimate_normals(c.points, {});
  RansacOptions o = options_for(0.01);
  o.min_points = 20;
  const auto plain = detect_shapes(c.points, normals, o);
  ASSERT_TRUE(plain.ok());
  long long assigned_plain = 0;
  for (int a : plain->assignment) assigned_plain += a >= 0 ? 1 : 0;
  const double cos_alpha = std::cos(o.normal_deviation_deg * std::numbers::pi / 180.0);
  long long edge_points = 0;
  RansacResult before_edges;  // relabel alone: the shapes whose neighbourhoods give up edges
  for (const bool edges : {false, true}) {
    SCOPED_TRACE(edges ? "relabel and edges_to_smaller" : "relabel");
    o.relabel = true;
    o.edges_to_smaller = edges;
    const auto relabelled = detect_shapes(c.points, normals, o);
    ASSERT_TRUE(relabelled.ok());
    const RansacResult& r = relabelled.value();
    ASSERT_GE(r.shapes.size(), 3U);
    long long assigned = 0;
    for (int a : r.assignment) assigned += a >= 0 ? 1 : 0;
    EXPECT_GE(assigned, assigned_plain);
    if (!edges) before_edges = r;
    ASSERT_EQ(before_edges.shapes.size(), r.shapes.size());
    auto size_of = [&](std::size_t s) { return r.shapes[s].inliers.size(); };
    std::vector<long long> count(r.shapes.size(), 0);
    for (std::size_t i = 0; i < c.points.size(); ++i) {
      const int own = r.assignment[i];
      if (own >= 0) ++count[static_cast<std::size_t>(own)];
      const auto o_own = static_cast<std::size_t>(std::max(own, 0));
      const double d_own =
          own >= 0 ? std::abs(surface_distance(r.shapes[o_own].surface, c.points[i])) : INFINITY;
      for (std::size_t t = 0; t < r.shapes.size(); ++t) {
        if (static_cast<int>(t) == own) continue;
        const Surface& other = r.shapes[t].surface;
        const double d = std::abs(surface_distance(other, c.points[i]));
        if (d > o.epsilon) continue;
        // Only shapes near the point compete: within the connectivity size of an inlier (the
        // surfaces are unbounded; a cylinder's far side is not the plane's business).
        double nearest = INFINITY;
        for (auto j : r.shapes[t].inliers) {
          nearest = std::min(nearest, (c.points[j] - c.points[i]).norm());
        }
        if (nearest > r.cluster_epsilon) continue;
        const bool faces =
            std::abs(surface_normal(other, c.points[i]).dot(normals[i])) >= cos_alpha;
        if (edges && own >= 0) {
          // On both: the smaller by half wins, whatever the distances and normals.
          if (2 * size_of(o_own) <= size_of(t)) {
            ++edge_points;
            continue;
          }
          // (Only points next to the smaller shape's inliers before the edges moved.)
          double next_to = INFINITY;
          for (auto j : before_edges.shapes[t].inliers) {
            next_to = std::min(next_to, (c.points[j] - c.points[i]).norm());
          }
          if (2 * size_of(t) <= size_of(o_own) && next_to <= r.cluster_epsilon) {
            ADD_FAILURE() << "edge point " << i << " of shape " << own << " (" << size_of(o_own)
                          << " points) lies on the smaller shape " << t << " (" << size_of(t)
                          << ")";
            continue;
          }
        }
        if (own >= 0 && (!faces || d_own <= d)) continue;
        // A point on a shape near it, nearer and facing like it, must not stay where it is; a
        // free point on a shape near it must have been taken.
        ADD_FAILURE() << (own >= 0 ? "point " : "free point ") << i << " of shape " << own
                      << " (distance " << d_own << ") lies on shape " << t << " (distance " << d
                      << ")";
      }
    }
    for (std::size_t s = 0; s < r.shapes.size(); ++s) {
      EXPECT_EQ(count[s], static_cast<long long>(r.shapes[s].inliers.size()));
      EXPECT_GE(count[s], o.min_points);
    }
  }
  EXPECT_GT(edge_points, 0);  // the cylinder's foot rim lies on the floor too
}

}  // namespace
}  // namespace csgtile::fit
