#include "predicates/predicates.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace csgtile::kernel::predicates {

namespace {

// ---- Filters --------------------------------------------------------------------------------
//
// Each predicate first evaluates its polynomial P in doubles, giving D, together with the
// "permanent" S: the same expression with every monomial replaced by its absolute value,
// also in doubles. With u = 2^-53 the unit roundoff, a monomial that went through k
// roundings carries a relative error of at most γk = k·u / (1 - k·u); the rounding of the
// last operation never changes a sign (rounding is monotone and only 0 rounds to 0), so it
// does not count. Hence |D' - P| ≤ γk·S_exact for the value D' before the last rounding, and
// sign D = sign P whenever |D| > c·S with c a little above k·u. Each constant below is
// (k + 1)·u: the extra u covers the O(u²) terms and the rounding of S and of c·S themselves.
// kAbsoluteSlack covers the absolute error of products that would fall below the normal
// range (outside the documented domain, where relative bounds stop holding).

constexpr double kU = 0x1p-53;
constexpr double kAbsoluteSlack = 0x1p-1000;
// Two products, one subtraction (the last operation): k = 1.
constexpr double kCross2Bound = 2.0 * kU;
// Two products summed: k = 1.
constexpr double kDot2Bound = 2.0 * kU;
// Three products, two additions (the first of which counts): k = 2.
constexpr double kDot3Bound = 3.0 * kU;
// orient2d (and the cross product of two differences): the differences of both factors
// (2), the product (1), the subtraction (last): k = 3.
constexpr double kOrient2dBound = 4.0 * kU;
// (p - o)·n: difference (1), product (1), first addition (1): k = 3.
constexpr double kOrientPlaneBound = 4.0 * kU;
// orient3d as u·(v × w) of differences: differences (3 factors), inner products (1), inner
// subtraction (1), outer product (1), first outer addition (1): k = 7.
constexpr double kOrient3dBound = 8.0 * kU;

thread_local PredicateStats t_stats;

inline int sign_of(double x) { return (x > 0.0) - (x < 0.0); }

inline void count_call(PredicateKind kind) {
  ++t_stats.calls;
  ++t_stats.calls_by_kind[static_cast<int>(kind)];
}
inline void count_exact(PredicateKind kind) {
  ++t_stats.exact;
  ++t_stats.exact_by_kind[static_cast<int>(kind)];
}

// ---- Exact stage: expansions -----------------------------------------------------------------

// s + e = a + b exactly, s = fl(a + b) (Knuth's branch-free two-sum).
inline void two_sum(double a, double b, double& s, double& e) {
  s = a + b;
  const double b_part = s - a;
  const double a_part = s - b_part;
  e = (a - a_part) + (b - b_part);
}

// p + e = a·b exactly, p = fl(a·b) (needs no underflow: see the domain in the header).
inline void two_product(double a, double b, double& p, double& e) {
  p = a * b;
  e = std::fma(a, b, -p);
}

// Adds b to the expansion c[0..n) exactly: c stays a sum of nonoverlapping doubles in
// increasing order of magnitude, with zeros dropped, and grows by at most one component.
// (A chain of two-sums from the smallest component up: each step keeps its rounding error
// as a component and carries the rounded sum on; the carried sum ends as the largest.)
// The sign of such an expansion is the sign of its largest component.
void grow(double* c, int& n, double b) {
  double carry = b;
  int m = 0;
  for (int i = 0; i < n; ++i) {
    double s = 0.0, e = 0.0;
    two_sum(carry, c[i], s, e);
    if (e != 0.0) c[m++] = e;
    carry = s;
  }
  if (carry != 0.0) c[m++] = carry;
  n = m;
}

// An exact sum of at most N doubles.
template <int N>
class Exact {
 public:
  void add(double b) { grow(c_.data(), n_, b); }
  void add_product(double x, double y) {
    double p = 0.0, e = 0.0;
    two_product(x, y, p, e);
    add(e);
    add(p);
  }
  // x·y·z, four doubles.
  void add_product(double x, double y, double z) {
    double p = 0.0, pe = 0.0, a = 0.0, ae = 0.0, b = 0.0, be = 0.0;
    two_product(x, y, p, pe);
    two_product(p, z, a, ae);
    two_product(pe, z, b, be);
    add(be);
    add(ae);
    add(b);
    add(a);
  }
  // s·det[p, q, r] (rows), s = ±1: six products of three.
  void add_det3(double s, const Vec3& p, const Vec3& q, const Vec3& r) {
    add_product(s * p.x(), q.y(), r.z());
    add_product(-s * p.x(), q.z(), r.y());
    add_product(s * p.y(), q.z(), r.x());
    add_product(-s * p.y(), q.x(), r.z());
    add_product(s * p.z(), q.x(), r.y());
    add_product(-s * p.z(), q.y(), r.x());
  }
  int sign() const { return n_ == 0 ? 0 : sign_of(c_[static_cast<std::size_t>(n_ - 1)]); }

 private:
  std::array<double, N> c_{};
  int n_ = 0;
};

inline int decided(double value, double bound) {
  if (value > bound) return 1;
  if (value < -bound) return -1;
  return 2;  // undecided
}

}  // namespace

PredicateStats predicate_stats() { return t_stats; }
void reset_predicate_stats() { t_stats = PredicateStats{}; }

int orient2d(const Vec2& a, const Vec2& b, const Vec2& c) {
  count_call(PredicateKind::Orient2d);
  // det[b - a, c - a] = det[a - c, b - c].
  const double acx = a.x() - c.x(), acy = a.y() - c.y();
  const double bcx = b.x() - c.x(), bcy = b.y() - c.y();
  const double left = acx * bcy, right = acy * bcx;
  const double det = left - right;
  const double permanent = std::abs(left) + std::abs(right);
  if (const int s = decided(det, kOrient2dBound * permanent + kAbsoluteSlack); s != 2) return s;
  // Both products 0 in doubles: each has a factor that is an exactly zero difference.
  if (permanent == 0.0) return 0;
  count_exact(PredicateKind::Orient2d);
  // det[b - a, c - a] = det(b, c) - det(a, c) + det(a, b), det(p, q) = p.x·q.y - p.y·q.x.
  Exact<12> x;
  x.add_product(b.x(), c.y());
  x.add_product(-b.y(), c.x());
  x.add_product(-a.x(), c.y());
  x.add_product(a.y(), c.x());
  x.add_product(a.x(), b.y());
  x.add_product(-a.y(), b.x());
  return x.sign();
}

int orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  count_call(PredicateKind::Orient3d);
  const double ux = b.x() - a.x(), uy = b.y() - a.y(), uz = b.z() - a.z();
  const double vx = c.x() - a.x(), vy = c.y() - a.y(), vz = c.z() - a.z();
  const double wx = d.x() - a.x(), wy = d.y() - a.y(), wz = d.z() - a.z();
  const double vywz = vy * wz, vzwy = vz * wy;
  const double vzwx = vz * wx, vxwz = vx * wz;
  const double vxwy = vx * wy, vywx = vy * wx;
  const double det = ux * (vywz - vzwy) + uy * (vzwx - vxwz) + uz * (vxwy - vywx);
  const double permanent = std::abs(ux) * (std::abs(vywz) + std::abs(vzwy)) +
                           std::abs(uy) * (std::abs(vzwx) + std::abs(vxwz)) +
                           std::abs(uz) * (std::abs(vxwy) + std::abs(vywx));
  if (const int s = decided(det, kOrient3dBound * permanent + kAbsoluteSlack); s != 2) return s;
  // Every monomial 0 in doubles: each has an exactly zero difference as a factor.
  if (permanent == 0.0) return 0;
  count_exact(PredicateKind::Orient3d);
  // det[b - a, c - a, d - a] = det(b, c, d) - det(a, c, d) + det(a, b, d) - det(a, b, c).
  Exact<96> x;
  x.add_det3(1.0, b, c, d);
  x.add_det3(-1.0, a, c, d);
  x.add_det3(1.0, a, b, d);
  x.add_det3(-1.0, a, b, c);
  return x.sign();
}

int orient_plane(const Vec3& p, const Vec3& origin, const Vec3& normal) {
  count_call(PredicateKind::OrientPlane);
  const double tx = (p.x() - origin.x()) * normal.x();
  const double ty = (p.y() - origin.y()) * normal.y();
  const double tz = (p.z() - origin.z()) * normal.z();
  const double value = tx + ty + tz;
  const double permanent = std::abs(tx) + std::abs(ty) + std::abs(tz);
  if (const int s = decided(value, kOrientPlaneBound * permanent + kAbsoluteSlack); s != 2)
    return s;
  if (permanent == 0.0) return 0;
  count_exact(PredicateKind::OrientPlane);
  Exact<12> x;
  for (int i = 0; i < 3; ++i) {
    x.add_product(p[i], normal[i]);
    x.add_product(-origin[i], normal[i]);
  }
  return x.sign();
}

int cross_sign(const Vec2& u, const Vec2& v) {
  count_call(PredicateKind::Cross);
  const double left = u.x() * v.y(), right = u.y() * v.x();
  const double value = left - right;
  const double permanent = std::abs(left) + std::abs(right);
  if (const int s = decided(value, kCross2Bound * permanent + kAbsoluteSlack); s != 2) return s;
  if (permanent == 0.0) return 0;
  count_exact(PredicateKind::Cross);
  Exact<4> x;
  x.add_product(u.x(), v.y());
  x.add_product(-u.y(), v.x());
  return x.sign();
}

int cross_sign(const Vec2& a0, const Vec2& a1, const Vec2& b0, const Vec2& b1) {
  count_call(PredicateKind::Cross);
  const double dax = a1.x() - a0.x(), day = a1.y() - a0.y();
  const double dbx = b1.x() - b0.x(), dby = b1.y() - b0.y();
  const double left = dax * dby, right = day * dbx;
  const double value = left - right;
  const double permanent = std::abs(left) + std::abs(right);
  if (const int s = decided(value, kOrient2dBound * permanent + kAbsoluteSlack); s != 2) return s;
  if (permanent == 0.0) return 0;
  count_exact(PredicateKind::Cross);
  // (a1x - a0x)(b1y - b0y) - (a1y - a0y)(b1x - b0x), expanded.
  Exact<16> x;
  x.add_product(a1.x(), b1.y());
  x.add_product(-a1.x(), b0.y());
  x.add_product(-a0.x(), b1.y());
  x.add_product(a0.x(), b0.y());
  x.add_product(-a1.y(), b1.x());
  x.add_product(a1.y(), b0.x());
  x.add_product(a0.y(), b1.x());
  x.add_product(-a0.y(), b0.x());
  return x.sign();
}

int dot_sign(const Vec2& u, const Vec2& v) {
  count_call(PredicateKind::Dot);
  const double tx = u.x() * v.x(), ty = u.y() * v.y();
  const double value = tx + ty;
  const double permanent = std::abs(tx) + std::abs(ty);
  if (const int s = decided(value, kDot2Bound * permanent + kAbsoluteSlack); s != 2) return s;
  if (permanent == 0.0) return 0;
  count_exact(PredicateKind::Dot);
  Exact<4> x;
  x.add_product(u.x(), v.x());
  x.add_product(u.y(), v.y());
  return x.sign();
}

int dot_sign(const Vec3& u, const Vec3& v) {
  count_call(PredicateKind::Dot);
  const double tx = u.x() * v.x(), ty = u.y() * v.y(), tz = u.z() * v.z();
  const double value = tx + ty + tz;
  const double permanent = std::abs(tx) + std::abs(ty) + std::abs(tz);
  if (const int s = decided(value, kDot3Bound * permanent + kAbsoluteSlack); s != 2) return s;
  if (permanent == 0.0) return 0;
  count_exact(PredicateKind::Dot);
  Exact<6> x;
  for (int i = 0; i < 3; ++i) x.add_product(u[i], v[i]);
  return x.sign();
}

int polygon_orientation(std::span<const Vec2> ring) {
  count_call(PredicateKind::PolygonOrientation);
  const std::size_t n = ring.size();
  if (n < 3) return 0;
  // Filter: Σ det(p_i - p_0, p_{i+1} - p_0) over i = 1 … n-2. A monomial goes through the
  // two differences of its factors, its product, the term's subtraction and at most n - 3
  // additions: k ≤ n + 1.
  const Vec2& o = ring[0];
  double value = 0.0, permanent = 0.0;
  for (std::size_t i = 1; i + 1 < n; ++i) {
    const double left = (ring[i].x() - o.x()) * (ring[i + 1].y() - o.y());
    const double right = (ring[i].y() - o.y()) * (ring[i + 1].x() - o.x());
    value += left - right;
    permanent += std::abs(left) + std::abs(right);
  }
  const double bound = (static_cast<double>(n) + 4.0) * kU * permanent + kAbsoluteSlack;
  if (const int s = decided(value, bound); s != 2) return s;
  if (permanent == 0.0) return 0;
  count_exact(PredicateKind::PolygonOrientation);
  // Σ det(p_i, p_{i+1}) around the ring (the translation by p_0 cancels exactly).
  std::vector<double> c(4 * n);
  int count = 0;
  auto add_product = [&](double x, double y) {
    double p = 0.0, e = 0.0;
    two_product(x, y, p, e);
    grow(c.data(), count, e);
    grow(c.data(), count, p);
  };
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2& p = ring[i];
    const Vec2& q = ring[(i + 1) % n];
    add_product(p.x(), q.y());
    add_product(-p.y(), q.x());
  }
  return count == 0 ? 0 : sign_of(c[static_cast<std::size_t>(count - 1)]);
}

bool on_segment(const Vec2& p, const Vec2& a, const Vec2& b) {
  if (p.x() < std::min(a.x(), b.x()) || p.x() > std::max(a.x(), b.x()) ||
      p.y() < std::min(a.y(), b.y()) || p.y() > std::max(a.y(), b.y())) {
    return false;
  }
  return orient2d(a, b, p) == 0;
}

SegmentRelation classify_segments(const Vec2& a0, const Vec2& a1, const Vec2& b0, const Vec2& b1) {
  const int o1 = orient2d(a0, a1, b0), o2 = orient2d(a0, a1, b1);
  const int o3 = orient2d(b0, b1, a0), o4 = orient2d(b0, b1, a1);
  if (o1 == 0 && o2 == 0 && o3 == 0 && o4 == 0) {
    // All four points on one line (or the segments are points): compare the intervals along
    // an axis the line is not perpendicular to; the projection keeps the order.
    const bool vertical = a0.x() == a1.x() && a0.x() == b0.x() && a0.x() == b1.x();
    const int k = vertical ? 1 : 0;
    const double lo = std::max(std::min(a0[k], a1[k]), std::min(b0[k], b1[k]));
    const double hi = std::min(std::max(a0[k], a1[k]), std::max(b0[k], b1[k]));
    if (lo > hi) return SegmentRelation::Disjoint;
    return lo == hi ? SegmentRelation::Touch : SegmentRelation::Overlap;
  }
  if (o1 * o2 > 0 || o3 * o4 > 0) return SegmentRelation::Disjoint;
  if (o1 * o2 < 0 && o3 * o4 < 0) return SegmentRelation::Cross;
  // One point of a segment lies on the other's line, and the lines separate each
  // segment's ends (closed): that point is the common one.
  return SegmentRelation::Touch;
}

bool crosses_ray(const Vec2& a, const Vec2& b, const Vec2& q) {
  if ((a.y() > q.y()) == (b.y() > q.y())) return false;
  // The segment straddles q's height; it crosses to the right of q when q is left of an
  // upward segment, or right of a downward one.
  const int side = orient2d(a, b, q);
  return b.y() > a.y() ? side > 0 : side < 0;
}

PolygonLocation locate_in_polygon(const Vec2& q, std::span<const std::vector<Vec2>> rings) {
  bool inside = false;
  for (const std::vector<Vec2>& ring : rings) {
    const std::size_t n = ring.size();
    for (std::size_t i = 0, j = n - 1; i < n; j = i++) {
      const Vec2& a = ring[j];
      const Vec2& b = ring[i];
      if (on_segment(q, a, b)) return PolygonLocation::OnBoundary;
      if (crosses_ray(a, b, q)) inside = !inside;
    }
  }
  return inside ? PolygonLocation::Inside : PolygonLocation::Outside;
}

bool clockwise_before(const Vec2& from, const Vec2& d1, const Vec2& d2) {
  // Rank of the clockwise turn from `from` to d: 0 for (0, π), 1 for π, 2 for (π, 2π), 3 for
  // no turn (a full turn: last).
  auto rank = [&](const Vec2& d) {
    if (d == from) return 3;  // the same vector (a twin's chord): no predicate needed
    const int side = cross_sign(from, d);
    if (side < 0) return 0;
    if (side > 0) return 2;
    return dot_sign(from, d) < 0 ? 1 : 3;
  };
  const int r1 = rank(d1), r2 = rank(d2);
  if (r1 != r2) return r1 < r2;
  if (r1 == 1 || r1 == 3) return false;
  // Both in one open half-plane: d1 comes first when d2 is further clockwise from it.
  return cross_sign(d1, d2) < 0;
}

}  // namespace csgtile::kernel::predicates
