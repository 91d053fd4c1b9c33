// Exact geometric predicates (kernel/src/predicates): signs checked against an exact rational
// reference (GMP) on seeded near-degenerate inputs where the naive double evaluation goes
// wrong, exact zeros for inputs that are collinear / coplanar in double, antisymmetry under
// swaps, the classic "points near a line on an ulp grid" example, and the helpers built on
// them (segments, point in polygon, angular order).

#include "predicates/predicates.h"

#include <gmpxx.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "boolean/uv_geometry.h"

namespace csgtile::kernel::predicates {
namespace {

constexpr int kRandomCases = 100000;

int sgn_of(const mpq_class& x) { return sgn(x); }
mpq_class q(double x) { return mpq_class(x); }  // exact: a double is a dyadic rational

int reference_orient2d(const Vec2& a, const Vec2& b, const Vec2& c) {
  return sgn_of((q(b.x()) - q(a.x())) * (q(c.y()) - q(a.y())) -
                (q(b.y()) - q(a.y())) * (q(c.x()) - q(a.x())));
}

int reference_orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const mpq_class ux = q(b.x()) - q(a.x()), uy = q(b.y()) - q(a.y()), uz = q(b.z()) - q(a.z());
  const mpq_class vx = q(c.x()) - q(a.x()), vy = q(c.y()) - q(a.y()), vz = q(c.z()) - q(a.z());
  const mpq_class wx = q(d.x()) - q(a.x()), wy = q(d.y()) - q(a.y()), wz = q(d.z()) - q(a.z());
  return sgn_of(ux * (vy * wz - vz * wy) + uy * (vz * wx - vx * wz) + uz * (vx * wy - vy * wx));
}

int reference_orient_plane(const Vec3& p, const Vec3& o, const Vec3& n) {
  mpq_class s = 0;
  for (int i = 0; i < 3; ++i) s += (q(p[i]) - q(o[i])) * q(n[i]);
  return sgn_of(s);
}

int reference_polygon(const std::vector<Vec2>& ring) {
  mpq_class s = 0;
  for (std::size_t i = 0; i < ring.size(); ++i) {
    const Vec2& p = ring[i];
    const Vec2& r = ring[(i + 1) % ring.size()];
    s += q(p.x()) * q(r.y()) - q(p.y()) * q(r.x());
  }
  return sgn_of(s);
}

// The textbook double evaluation, for contrast.
int naive_orient2d(const Vec2& a, const Vec2& b, const Vec2& c) {
  const double d = (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
  return (d > 0) - (d < 0);
}
int naive_orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const Vec3 u = b - a, v = c - a, w = d - a;
  const double x = u.dot(v.cross(w));
  return (x > 0) - (x < 0);
}

// x moved by k ulps (k may be negative).
double ulps(double x, int k) {
  const double towards =
      k > 0 ? std::numeric_limits<double>::infinity() : -std::numeric_limits<double>::infinity();
  for (int i = 0; i < std::abs(k); ++i) x = std::nextafter(x, towards);
  return x;
}

// Random inputs of varied magnitude and offset: the near-degenerate cases are points
// computed on a line / plane (rounded) and then nudged by a few ulps.
class Generator {
 public:
  explicit Generator(std::uint64_t seed) : rng_(seed) {}
  double uniform(double lo, double hi) {
    return std::uniform_real_distribution<double>(lo, hi)(rng_);
  }
  int integer(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng_); }
  double scale() { return std::ldexp(1.0, integer(-30, 40)); }
  Vec2 point2(double scale, const Vec2& offset) {
    return offset + scale * Vec2(uniform(-1, 1), uniform(-1, 1));
  }
  Vec3 point3(double scale, const Vec3& offset) {
    return offset + scale * Vec3(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1));
  }
  Vec2 nudge2(Vec2 p) {
    for (int i = 0; i < 2; ++i) p[i] = ulps(p[i], integer(-2, 2));
    return p;
  }
  Vec3 nudge3(Vec3 p) {
    for (int i = 0; i < 3; ++i) p[i] = ulps(p[i], integer(-2, 2));
    return p;
  }

 private:
  std::mt19937_64 rng_;
};

// ---- orient2d -------------------------------------------------------------------------------

TEST(Predicates, Orient2dMatchesExactRationalsOnNearCollinearPoints) {
  Generator g(20240604);
  int naive_wrong = 0, zeros = 0;
  for (int i = 0; i < kRandomCases; ++i) {
    const double s = g.scale();
    const Vec2 offset = g.integer(0, 1) ? g.point2(s * 1e3, Vec2::Zero()) : Vec2::Zero();
    const Vec2 a = g.point2(s, offset), b = g.point2(s, offset);
    const double t = g.integer(0, 3) == 0 ? g.uniform(-3, 3) : g.uniform(0, 1);
    Vec2 c = g.nudge2(a + t * (b - a));
    if (i % 16 == 0) c = i % 32 == 0 ? a : b;  // exactly degenerate
    if (i % 16 == 8) c = Vec2(a.x(), b.y());   // axis-parallel right angle
    const int expected = reference_orient2d(a, b, c);
    ASSERT_EQ(orient2d(a, b, c), expected) << i;
    naive_wrong += naive_orient2d(a, b, c) != expected;
    zeros += expected == 0;
  }
  // The set is hard enough that the naive evaluation fails on part of it.
  EXPECT_GT(naive_wrong, kRandomCases / 100);
  EXPECT_GT(zeros, 0);
}

// Kettner et al.'s classroom example: p on a 256 × 256 grid of ulp steps around (0.5, 0.5),
// q = (12, 12), r = (24, 24). The exact sign is that of p.y - p.x (the line is y = x); the
// naive evaluation gives a scattered, non-convex pattern of wrong signs.
TEST(Predicates, Orient2dOnTheUlpGridNearALineIsExact) {
  const double u = std::ldexp(1.0, -53);
  const Vec2 q2(12, 12), r2(24, 24);
  int naive_wrong = 0;
  for (int x = 0; x < 256; ++x) {
    for (int y = 0; y < 256; ++y) {
      const Vec2 p(0.5 + x * u, 0.5 + y * u);
      const int expected = (y > x) - (y < x);
      ASSERT_EQ(orient2d(p, q2, r2), expected) << x << " " << y;
      ASSERT_EQ(reference_orient2d(p, q2, r2), expected);
      naive_wrong += naive_orient2d(p, q2, r2) != expected;
    }
  }
  EXPECT_GT(naive_wrong, 1000);
}

TEST(Predicates, Orient2dIsExactlyZeroForCollinearDyadicPoints) {
  Generator g(7);
  for (int i = 0; i < 10000; ++i) {
    // y = m·x + k with small dyadic m, k and x: every coordinate is exact in double.
    const double m = g.integer(-64, 64) / 8.0, k = g.integer(-1000, 1000) / 4.0;
    const int e = g.integer(-40, 40);
    auto on_line = [&] {
      const double x = g.integer(-1 << 20, 1 << 20) / 16.0;
      return Vec2(std::ldexp(x, e), std::ldexp(m * x + k, e));
    };
    const Vec2 a = on_line(), b = on_line(), c = on_line();
    ASSERT_EQ(orient2d(a, b, c), 0);
    ASSERT_EQ(cross_sign(a, b, c, a), 0);
  }
  EXPECT_EQ(orient2d(Vec2(1, 2), Vec2(1, 2), Vec2(1, 2)), 0);
  EXPECT_EQ(orient2d(Vec2(0.1, 0.2), Vec2(0.1, 0.2), Vec2(5, 7)), 0);
}

TEST(Predicates, Orient2dIsAntisymmetric) {
  Generator g(11);
  for (int i = 0; i < 20000; ++i) {
    const double s = g.scale();
    const Vec2 a = g.point2(s, Vec2::Zero()), b = g.point2(s, Vec2::Zero());
    const Vec2 c = g.nudge2(a + g.uniform(0, 1) * (b - a));
    const int o = orient2d(a, b, c);
    ASSERT_EQ(orient2d(b, c, a), o);
    ASSERT_EQ(orient2d(c, a, b), o);
    ASSERT_EQ(orient2d(b, a, c), -o);
    ASSERT_EQ(orient2d(a, c, b), -o);
    ASSERT_EQ(orient2d(c, b, a), -o);
  }
}

TEST(Predicates, Orient2dAtExtremeScales) {
  Generator g(13);
  for (int i = 0; i < 5000; ++i) {
    const Vec2 a = g.point2(1, Vec2::Zero()), b = g.point2(1, Vec2::Zero());
    const Vec2 c = g.nudge2(a + g.uniform(0, 1) * (b - a));
    const int o = orient2d(a, b, c);
    ASSERT_EQ(o, reference_orient2d(a, b, c));
    for (int e : {-200, 200}) {
      const double f = std::ldexp(1.0, e);  // scaling by 2^e is exact and keeps the sign
      ASSERT_EQ(orient2d(f * a, f * b, f * c), o) << e;
    }
  }
}

// ---- orient3d -------------------------------------------------------------------------------

TEST(Predicates, Orient3dMatchesExactRationalsOnNearCoplanarPoints) {
  Generator g(31337);
  int naive_wrong = 0, zeros = 0;
  for (int i = 0; i < kRandomCases; ++i) {
    const double s = g.scale();
    const Vec3 offset = g.integer(0, 1) ? g.point3(s * 1e3, Vec3::Zero()) : Vec3::Zero();
    const Vec3 a = g.point3(s, offset), b = g.point3(s, offset), c = g.point3(s, offset);
    Vec3 d = g.nudge3(a + g.uniform(-1, 2) * (b - a) + g.uniform(-1, 2) * (c - a));
    if (i % 16 == 0) d = i % 32 == 0 ? a : c;  // exactly degenerate
    const int expected = reference_orient3d(a, b, c, d);
    ASSERT_EQ(orient3d(a, b, c, d), expected) << i;
    naive_wrong += naive_orient3d(a, b, c, d) != expected;
    zeros += expected == 0;
  }
  EXPECT_GT(naive_wrong, kRandomCases / 100);
  EXPECT_GT(zeros, 0);
}

TEST(Predicates, Orient3dIsExactlyZeroForCoplanarDyadicPoints) {
  Generator g(17);
  for (int i = 0; i < 10000; ++i) {
    // z = m·x + n·y + k with small dyadic coefficients.
    const double m = g.integer(-32, 32) / 4.0, n = g.integer(-32, 32) / 8.0;
    const double k = g.integer(-100, 100) / 2.0;
    const int e = g.integer(-30, 30);
    auto on_plane = [&] {
      const double x = g.integer(-1 << 16, 1 << 16) / 8.0, y = g.integer(-1 << 16, 1 << 16) / 8.0;
      return Vec3(std::ldexp(x, e), std::ldexp(y, e), std::ldexp(m * x + n * y + k, e));
    };
    const Vec3 a = on_plane(), b = on_plane(), c = on_plane(), d = on_plane();
    ASSERT_EQ(orient3d(a, b, c, d), 0);
  }
}

TEST(Predicates, Orient3dIsAntisymmetricAndFollowsTheNormal) {
  // d above the counter-clockwise triangle (seen from +z): positive.
  EXPECT_EQ(orient3d(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0.2, 0.2, 1)), 1);
  EXPECT_EQ(orient3d(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0.2, 0.2, -1)), -1);
  Generator g(19);
  for (int i = 0; i < 20000; ++i) {
    const double s = g.scale();
    const Vec3 a = g.point3(s, Vec3::Zero()), b = g.point3(s, Vec3::Zero()),
               c = g.point3(s, Vec3::Zero());
    const Vec3 d = g.nudge3(a + g.uniform(0, 1) * (b - a) + g.uniform(0, 1) * (c - a));
    const int o = orient3d(a, b, c, d);
    // Odd permutations flip the sign, even ones keep it.
    ASSERT_EQ(orient3d(b, a, c, d), -o);
    ASSERT_EQ(orient3d(a, c, b, d), -o);
    ASSERT_EQ(orient3d(a, b, d, c), -o);
    ASSERT_EQ(orient3d(d, b, c, a), -o);
    ASSERT_EQ(orient3d(b, c, a, d), o);
    ASSERT_EQ(orient3d(b, a, d, c), o);
    ASSERT_EQ(orient3d(c, d, a, b), o);
  }
}

TEST(Predicates, Orient3dAtExtremeScales) {
  Generator g(23);
  for (int i = 0; i < 3000; ++i) {
    const Vec3 a = g.point3(1, Vec3::Zero()), b = g.point3(1, Vec3::Zero()),
               c = g.point3(1, Vec3::Zero());
    const Vec3 d = g.nudge3(a + g.uniform(0, 1) * (b - a) + g.uniform(0, 1) * (c - a));
    const int o = orient3d(a, b, c, d);
    ASSERT_EQ(o, reference_orient3d(a, b, c, d));
    for (int e : {-200, 200}) {
      const double f = std::ldexp(1.0, e);
      ASSERT_EQ(orient3d(f * a, f * b, f * c, f * d), o) << e;
    }
  }
}

// ---- Plane side, cross and dot signs ---------------------------------------------------------

TEST(Predicates, OrientPlaneMatchesExactRationals) {
  Generator g(41);
  int zeros = 0;
  for (int i = 0; i < kRandomCases; ++i) {
    const double s = g.scale();
    const Vec3 origin = g.point3(s * 100, Vec3::Zero());
    const Vec3 normal = Vec3(g.uniform(-1, 1), g.uniform(-1, 1), g.uniform(-1, 1)).normalized();
    const Vec3 x = normal.unitOrthogonal(), y = normal.cross(x);
    const Vec3 p = g.nudge3(Vec3(origin + s * (g.uniform(-1, 1) * x + g.uniform(-1, 1) * y)));
    const int expected = reference_orient_plane(p, origin, normal);
    ASSERT_EQ(orient_plane(p, origin, normal), expected) << i;
    ASSERT_EQ(orient_plane(p, origin, Vec3(-normal)), -expected);
    zeros += expected == 0;
  }
  EXPECT_EQ(orient_plane(Vec3(1, 2, 3), Vec3(1, 2, 3), Vec3(0, 0, 1)), 0);
  EXPECT_EQ(orient_plane(Vec3(5, -7, 3), Vec3(1, 2, 3), Vec3(0, 0, 1)), 0);
  EXPECT_EQ(orient_plane(Vec3(5, -7, 3.0000001), Vec3(1, 2, 3), Vec3(0, 0, 1)), 1);
}

TEST(Predicates, CrossAndDotSignsMatchExactRationals) {
  Generator g(43);
  for (int i = 0; i < kRandomCases; ++i) {
    const double s = g.scale();
    const Vec2 u = g.point2(s, Vec2::Zero());
    const Vec2 v = g.nudge2(Vec2(g.uniform(-3, 3) * u));                    // nearly parallel
    const Vec2 w = g.nudge2(Vec2(g.uniform(-3, 3) * Vec2(-u.y(), u.x())));  // nearly perpendicular
    ASSERT_EQ(cross_sign(u, v), sgn_of(q(u.x()) * q(v.y()) - q(u.y()) * q(v.x())));
    ASSERT_EQ(dot_sign(u, w), sgn_of(q(u.x()) * q(w.x()) + q(u.y()) * q(w.y())));
    const Vec3 a = g.point3(s, Vec3::Zero());
    const Vec3 b = g.point3(s, Vec3::Zero());
    const Vec3 c = g.nudge3(Vec3(a.cross(b)));  // nearly perpendicular to both
    ASSERT_EQ(dot_sign(a, c),
              sgn_of(q(a.x()) * q(c.x()) + q(a.y()) * q(c.y()) + q(a.z()) * q(c.z())));
    // Four-point form: (a1 - a0) × (b1 - b0) with nearly parallel segments far from 0.
    const Vec2 a0 = g.point2(s, Vec2(s * 1e4, -s * 3e3)), a1 = g.point2(s, Vec2(s * 1e4, -s * 3e3));
    const Vec2 b0 = g.point2(s, Vec2(s * 1e4, -s * 3e3));
    const Vec2 b1 = g.nudge2(Vec2(b0 + g.uniform(-2, 2) * (a1 - a0)));
    const mpq_class expected = (q(a1.x()) - q(a0.x())) * (q(b1.y()) - q(b0.y())) -
                               (q(a1.y()) - q(a0.y())) * (q(b1.x()) - q(b0.x()));
    ASSERT_EQ(cross_sign(a0, a1, b0, b1), sgn_of(expected)) << i;
  }
}

// ---- Polygons -----------------------------------------------------------------------------

TEST(Predicates, PolygonOrientationMatchesExactRationals) {
  Generator g(47);
  for (int i = 0; i < 20000; ++i) {
    const double s = g.scale();
    const Vec2 a = g.point2(s, Vec2(s * 50, s * 20)), b = g.point2(s, Vec2(s * 50, s * 20));
    const int n = g.integer(3, i % 100 == 0 ? 400 : 12);
    std::vector<Vec2> ring;
    for (int k = 0; k < n; ++k) ring.push_back(g.nudge2(Vec2(a + g.uniform(0, 1) * (b - a))));
    ASSERT_EQ(polygon_orientation(ring), reference_polygon(ring)) << i;
  }
  const std::vector<Vec2> square{{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  EXPECT_EQ(polygon_orientation(square), 1);
  EXPECT_EQ(polygon_orientation(std::vector<Vec2>(square.rbegin(), square.rend())), -1);
  EXPECT_EQ(polygon_orientation(std::vector<Vec2>{{0, 0}, {1, 1}, {2, 2}, {3, 3}}), 0);
  EXPECT_EQ(polygon_orientation(std::vector<Vec2>{{0, 0}, {1, 1}}), 0);
}

TEST(Predicates, PointInPolygonIsExactOnTheBoundary) {
  // A square with a square hole; the hole's corners lie on the outer square's axes.
  const std::vector<std::vector<Vec2>> rings{{{0, 0}, {4, 0}, {4, 4}, {0, 4}},
                                             {{1, 1}, {1, 3}, {3, 3}, {3, 1}}};
  using L = PolygonLocation;
  EXPECT_EQ(locate_in_polygon(Vec2(0.5, 0.5), rings), L::Inside);
  EXPECT_EQ(locate_in_polygon(Vec2(2, 2), rings), L::Outside);
  EXPECT_EQ(locate_in_polygon(Vec2(5, 2), rings), L::Outside);
  EXPECT_EQ(locate_in_polygon(Vec2(0, 2), rings), L::OnBoundary);
  EXPECT_EQ(locate_in_polygon(Vec2(4, 4), rings), L::OnBoundary);
  EXPECT_EQ(locate_in_polygon(Vec2(2, 3), rings), L::OnBoundary);
  // The ray from these passes exactly through vertices and along horizontal edges.
  EXPECT_EQ(locate_in_polygon(Vec2(-1, 0), rings), L::Outside);
  EXPECT_EQ(locate_in_polygon(Vec2(0.5, 1), rings), L::Inside);
  EXPECT_EQ(locate_in_polygon(Vec2(0.5, 3), rings), L::Inside);
  EXPECT_EQ(locate_in_polygon(Vec2(-0.5, 3), rings), L::Outside);
  EXPECT_EQ(locate_in_polygon(Vec2(3.5, 1), rings), L::Inside);
  // Points of a slanted edge: exactly on it, or one ulp off to either side.
  const std::vector<std::vector<Vec2>> triangle{{{0.1, 0.1}, {0.7, 0.3}, {0.2, 0.9}}};
  Generator g(53);
  for (int i = 0; i < 20000; ++i) {
    const Vec2 a = triangle[0][0], b = triangle[0][1];
    const Vec2 p = g.nudge2(Vec2(a + g.uniform(0, 1) * (b - a)));
    const int side = reference_orient2d(a, b, p);  // left of a → b is inside (counter-clockwise)
    const L expected = side > 0 ? L::Inside : side < 0 ? L::Outside : L::OnBoundary;
    ASSERT_EQ(locate_in_polygon(p, triangle), expected) << i;
  }
}

// ---- Segments and angular order -------------------------------------------------------------

TEST(Predicates, SegmentRelations) {
  using R = SegmentRelation;
  const Vec2 o(0, 0), x(2, 0), y(0, 2), d(2, 2);
  EXPECT_EQ(classify_segments(o, d, x, y), R::Cross);
  EXPECT_EQ(classify_segments(o, x, o, y), R::Touch);                    // shared end
  EXPECT_EQ(classify_segments(o, x, Vec2(1, 0), Vec2(1, 5)), R::Touch);  // T junction
  EXPECT_EQ(classify_segments(o, x, Vec2(1, 0.5), Vec2(1, 5)), R::Disjoint);
  EXPECT_EQ(classify_segments(o, x, Vec2(1, 0), Vec2(3, 0)), R::Overlap);
  EXPECT_EQ(classify_segments(o, x, x, Vec2(3, 0)), R::Touch);  // collinear, end to end
  EXPECT_EQ(classify_segments(o, x, Vec2(3, 0), Vec2(4, 0)), R::Disjoint);
  EXPECT_EQ(classify_segments(o, y, Vec2(0, 3), Vec2(0, 4)), R::Disjoint);  // vertical line
  EXPECT_EQ(classify_segments(o, y, Vec2(0, 1), Vec2(0, 4)), R::Overlap);
  EXPECT_EQ(classify_segments(o, x, Vec2(0, 1), Vec2(2, 1)), R::Disjoint);  // parallel
  EXPECT_EQ(classify_segments(o, o, o, o), R::Touch);
  EXPECT_EQ(classify_segments(o, o, Vec2(0, 1), Vec2(0, 1)), R::Disjoint);
  EXPECT_EQ(classify_segments(Vec2(1, 0), Vec2(1, 0), o, x), R::Touch);
  // A segment's end nudged across the other one by an ulp: the relation follows exactly.
  Generator g(59);
  for (int i = 0; i < 20000; ++i) {
    const Vec2 a0 = g.point2(1, Vec2::Zero()), a1 = g.point2(1, Vec2::Zero());
    const Vec2 b0 = g.nudge2(Vec2(a0 + g.uniform(0.1, 0.9) * (a1 - a0)));
    const Vec2 b1 = g.point2(1, Vec2::Zero());
    const int o1 = reference_orient2d(a0, a1, b0), o2 = reference_orient2d(a0, a1, b1);
    const int o3 = reference_orient2d(b0, b1, a0), o4 = reference_orient2d(b0, b1, a1);
    R expected = R::Touch;
    if (o1 * o2 > 0 || o3 * o4 > 0) expected = R::Disjoint;
    if (o1 * o2 < 0 && o3 * o4 < 0) expected = R::Cross;
    ASSERT_EQ(classify_segments(a0, a1, b0, b1), expected) << i;
    ASSERT_EQ(on_segment(b0, a0, a1), o1 == 0);
  }
}

TEST(Predicates, ClockwiseOrderOfDirections) {
  const Vec2 east(1, 0), north(0, 1), west(-1, 0), south(0, -1);
  // From east, sweeping clockwise: south, west, north, then east itself.
  EXPECT_TRUE(clockwise_before(east, south, west));
  EXPECT_TRUE(clockwise_before(east, west, north));
  EXPECT_TRUE(clockwise_before(east, north, east));
  EXPECT_TRUE(clockwise_before(east, south, Vec2(2, 0)));
  EXPECT_FALSE(clockwise_before(east, west, south));
  EXPECT_FALSE(clockwise_before(east, east, Vec2(3, 0)));  // same angle
  EXPECT_FALSE(clockwise_before(east, Vec2(0, -2), south));
  // Directions one ulp apart are ordered.
  const Vec2 a(1, -1), b(1, std::nextafter(-1.0, 0.0));
  EXPECT_TRUE(clockwise_before(east, b, a));
  EXPECT_FALSE(clockwise_before(east, a, b));
  EXPECT_TRUE(clockwise_before(east, Vec2(1, std::nextafter(0.0, 1.0)), east));
}

TEST(Predicates, FilterDecidesTheGenericCasesAndCountsTheRest) {
  reset_predicate_stats();
  EXPECT_EQ(orient2d(Vec2(0, 0), Vec2(1, 0), Vec2(0, 1)), 1);
  EXPECT_EQ(orient3d(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)), 1);
  EXPECT_EQ(orient2d(Vec2(0, 0), Vec2(0, 0), Vec2(0, 1)), 0);  // a repeated point: no exact stage
  PredicateStats s = predicate_stats();
  EXPECT_EQ(s.calls, 3u);
  EXPECT_EQ(s.exact, 0u);
  EXPECT_EQ(orient2d(Vec2(0.1, 0.1), Vec2(0.3, 0.3), Vec2(0.7, 0.7)), 0);  // needs the exact stage
  s = predicate_stats();
  EXPECT_EQ(s.calls, 4u);
  EXPECT_EQ(s.exact, 1u);
  reset_predicate_stats();
  EXPECT_EQ(predicate_stats().calls, 0u);
}

// ---- The engine's decisions built on them ---------------------------------------------------

TEST(RobustDecisions, StraightPcurvesMeetAsTheExactSegmentsDo) {
  using detail::intersect_pcurves;
  const double tolerance = 1e-8;                   // the uv crossing tolerance of a unit face
  const Line2d a(Vec2(0.1, 0.3), Vec2(0.7, 0.2));  // t in [0, 1]
  const Vec2 m = a.point(0.5);
  // b starting exactly on a (a T junction), just across it, or just short of it.
  const Vec2 up(-0.2, 0.9);
  auto hits = intersect_pcurves(a, 0, 1, Line2d(m, up), 0, 1, tolerance);
  ASSERT_EQ(hits.size(), 1u);
  EXPECT_NEAR(hits[0].t, 0.5, 1e-15);
  EXPECT_EQ(hits[0].s, 0.0);
  const Vec2 below(m.x(), std::nextafter(m.y(), -1.0)), above(m.x(), std::nextafter(m.y(), 1.0));
  ASSERT_EQ(orient2d(a.point(0), a.point(1), below), -1);
  ASSERT_EQ(orient2d(a.point(0), a.point(1), above), 1);
  hits = intersect_pcurves(a, 0, 1, Line2d(below, up), 0, 1, tolerance);
  ASSERT_EQ(hits.size(), 1u);  // a proper crossing
  EXPECT_NEAR(hits[0].t, 0.5, 1e-15);
  hits = intersect_pcurves(a, 0, 1, Line2d(above, up), 0, 1, tolerance);
  ASSERT_EQ(hits.size(), 1u);  // a near miss by an ulp: within the parameter slack
  EXPECT_EQ(hits[0].s, 0.0);
  EXPECT_TRUE(
      intersect_pcurves(a, 0, 1, Line2d(m + 1e-6 * Vec2(-0.2, 1.0), up), 0, 1, tolerance).empty());
  // Parallel pieces (also collinear overlapping ones) never cross.
  EXPECT_TRUE(intersect_pcurves(a, 0, 1, Line2d(above, Vec2(0.7, 0.2)), -1, 1, tolerance).empty());
  EXPECT_TRUE(
      intersect_pcurves(a, 0, 1, Line2d(a.point(0.5), Vec2(0.7, 0.2)), 0, 2, tolerance).empty());
  // Proper crossings of random segments agree with the exact classification.
  Generator g(61);
  for (int i = 0; i < 2000; ++i) {
    const Vec2 p0 = g.point2(1, Vec2::Zero()), p1 = g.point2(1, Vec2::Zero());
    const Vec2 q0 = g.point2(1, Vec2::Zero()), q1 = g.point2(1, Vec2::Zero());
    const Line2d x(p0, p1 - p0), y(q0, q1 - q0);
    if (classify_segments(x.point(0), x.point(1), y.point(0), y.point(1)) != SegmentRelation::Cross)
      continue;
    ASSERT_EQ(intersect_pcurves(x, 0, 1, y, 0, 1, tolerance).size(), 1u) << i;
  }
}

TEST(RobustDecisions, PointInFacePolygonIsExactOutsideTheMargin) {
  detail::FacePolygon polygon;
  polygon.loops.push_back({{0.1, 0.1}, {0.7, 0.3}, {0.2, 0.9}});
  polygon.min = Vec2(0.1, 0.1);
  polygon.max = Vec2(0.7, 0.9);
  const Vec2 a = polygon.loops[0][0], b = polygon.loops[0][1];
  Generator g(67);
  for (int i = 0; i < 5000; ++i) {
    const Vec2 p = g.nudge2(Vec2(a + g.uniform(0.05, 0.95) * (b - a)));
    const int side = reference_orient2d(a, b, p);
    const auto in = polygon.inside(p, 0.0);
    if (side == 0) {
      EXPECT_FALSE(in.has_value());
    } else {
      ASSERT_TRUE(in.has_value());
      EXPECT_EQ(*in, side > 0) << i;
    }
    EXPECT_FALSE(polygon.inside(p, 1e-9).has_value());  // within the margin: undecided
  }
}

}  // namespace
}  // namespace csgtile::kernel::predicates
