#include "boolean/line_surface.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>

#include <Eigen/LU>

#include "boolean/tolerance.h"
#include "predicates/predicates.h"

namespace csgtile::kernel::detail {

namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();
constexpr double kTwoPi = 2.0 * std::numbers::pi;
// A ray closer than this (cosine) to perpendicular to a revolution axis, or to parallel to an
// extrusion direction, makes the swept-surface equations ill-conditioned: we report the line
// as degenerate and let the caller cast another one instead.
constexpr double kSweptConditioning = 1e-6;
// Relative window within which a cosine is taken as ±1: roots of a·cos u + b·sin u = c
// closer than about sqrt(2·kTrigDouble) radians are reported as one multiple root.
constexpr double kTrigDouble = 1e-12;
// Relative distance to a polyline breakpoint at which a root is flagged (it could be counted
// on both segments or on neither).
constexpr double kBreakpointSlack = 1e-10;
// Rounding-noise level of products of unit vectors and of the vectors they project: a
// projection this small relative to what was projected is zero (a perpendicular pair).
constexpr double kRelativeNoise = 1e-14;
// The cone equation's quadratic and linear coefficients (of order 1 and |q| for a unit
// direction) below this: the line runs along a ruling through the apex.
constexpr double kConeRulingNoise = 1e-20;
// A Newton polish step stops at a Jacobian whose determinant is this small relative to its
// columns' lengths (the line touches the surface there).
constexpr double kSingularJacobian = 1e-12;
// Roots of neighbouring chunks closer than this (relative) are one root found twice.
constexpr double kRootMergeRelative = 1e-12;
// Keeps "0 <= 0" from holding in relative tests of exactly zero quantities.
constexpr double kTiny = 1e-300;

double wrap(double a) {
  double r = std::fmod(a, kTwoPi);
  if (r < 0.0) r += kTwoPi;
  if (r >= kTwoPi) r = 0.0;
  return r;
}

// Roots u in [0, 2π) of α + β·cos u + γ·sin u = 0. Returns the count; `multiple` when the
// two roots merge (the line touches the swept curve).
int solve_trig_linear(double alpha, double beta, double gamma, std::array<double, 2>& r,
                      bool& multiple) {
  multiple = false;
  const double amplitude = std::hypot(beta, gamma);
  if (!(amplitude > 0.0)) return 0;
  const double ratio = -alpha / amplitude;  // cos(u − φ) = ratio
  const double phase = std::atan2(gamma, beta);
  if (std::abs(ratio) > 1.0 + kTrigDouble) return 0;
  if (std::abs(ratio) >= 1.0 - kTrigDouble) {
    r[0] = wrap(ratio > 0.0 ? phase : phase + std::numbers::pi);
    multiple = true;
    return 1;
  }
  const double delta = std::acos(ratio);
  r[0] = wrap(phase - delta);
  r[1] = wrap(phase + delta);
  return 2;
}

// Coordinates of p in a frame.
Vec3 in_frame(const Frame& f, const Vec3& p) {
  const Vec3 q = p - f.origin;
  return {q.dot(f.x), q.dot(f.y), q.dot(f.z)};
}
Vec3 direction_in_frame(const Frame& f, const Vec3& d) {
  return {d.dot(f.x), d.dot(f.y), d.dot(f.z)};
}

// The line re-centred at the middle of the window: roots are solved for τ = t − shift, whose
// coefficients are small (the window is where the face is), then shifted back.
struct CentredLine {
  Vec3 origin;     // original origin + shift·direction
  Vec3 direction;  // unit
  double shift;
  double lo, hi;  // the window in τ
};

CentredLine centre(const Vec3& o, const Vec3& d, double t0, double t1) {
  const double shift = 0.5 * (t0 + t1);
  return {o + shift * d, d, shift, t0 - shift, t1 - shift};
}

void push_hit(LineSurfaceIntersection& out, double t, const Vec2& uv, bool tangent) {
  out.hits.push_back({t, uv, tangent});
}

// ---- quadrics ----------------------------------------------------------------------------

void intersect_plane(const PlaneSurface& s, const Vec3& o, const Vec3& d, double t0, double t1,
                     double tolerance, LineSurfaceIntersection& out) {
  const Frame& f = s.frame();
  const double along = d.dot(f.z);
  const double height = (o - f.origin).dot(f.z);
  // Whether the line is parallel to the plane, and whether the plane lies ahead of its
  // origin, are decided exactly on the stored doubles; "in the plane" is a tolerance question.
  const int heading = predicates::dot_sign(d, f.z);
  if (heading == 0) {
    if (std::abs(height) <= tolerance) out.degenerate = true;
    return;
  }
  const int side = predicates::orient_plane(o, f.origin, f.z);
  if (side == heading && t0 >= 0.0) return;  // heading away: the plane is behind the origin
  const double t = side == 0 ? 0.0 : -side * heading * std::abs(height / along);
  if (t < t0 || t > t1) return;
  const Vec3 q = o + t * d - f.origin;
  push_hit(out, t, Vec2(q.dot(f.x), q.dot(f.y)), false);
}

void intersect_cylinder(const CylinderSurface& s, const Vec3& o, const Vec3& d, double t0,
                        double t1, double tolerance, LineSurfaceIntersection& out) {
  const CentredLine line = centre(o, d, t0, t1);
  const Vec3 q = in_frame(s.frame(), line.origin);
  const Vec3 e = direction_in_frame(s.frame(), d);
  const double r = s.radius();
  const double a = e.x() * e.x() + e.y() * e.y();
  // Parallel to the axis within tolerance over the window (its distance to the axis changes
  // by at most sin·(window / 2) from the one at the middle): on the surface along the whole
  // window, or it never meets it there.
  if (std::sqrt(a) * (line.hi - line.lo) <= tolerance) {
    if (std::abs(std::hypot(q.x(), q.y()) - r) <= tolerance) out.degenerate = true;
    return;
  }
  const double hb = q.x() * e.x() + q.y() * e.y();
  const double rho2 = q.x() * q.x() + q.y() * q.y();
  std::array<double, 2> roots{};
  bool multiple = false;
  const int n = solve_quadratic(a, hb, rho2 - r * r, rho2 + r * r, roots, multiple);
  for (int i = 0; i < n; ++i) {
    const double tau = roots[static_cast<std::size_t>(i)];
    if (tau < line.lo || tau > line.hi) continue;
    const Vec3 x = q + tau * e;
    const double cosine = std::abs(x.x() * e.x() + x.y() * e.y()) / r;
    push_hit(out, line.shift + tau, Vec2(wrap(std::atan2(x.y(), x.x())), x.z()),
             multiple || cosine < kGrazingCosine);
  }
}

void intersect_cone(const ConeSurface& s, const Vec3& o, const Vec3& d, double t0, double t1,
                    double tolerance, LineSurfaceIntersection& out) {
  const CentredLine line = centre(o, d, t0, t1);
  const Vec3 q = in_frame(s.frame(), line.origin);
  const Vec3 e = direction_in_frame(s.frame(), d);
  const double r = s.reference_radius();
  const double phi = s.semi_angle();
  const double k = std::tan(phi);
  // x² + y² = ρ(z)² with ρ(z) = r + k·z the radius of the face's nappe at height z.
  const double rho_q = r + k * q.z();
  const double a = e.x() * e.x() + e.y() * e.y() - k * k * e.z() * e.z();
  const double hb = q.x() * e.x() + q.y() * e.y() - k * e.z() * rho_q;
  const double planar2 = q.x() * q.x() + q.y() * q.y();
  const double c = planar2 - rho_q * rho_q;
  if (std::abs(a) <= kConeRulingNoise &&
      std::abs(hb) <= kConeRulingNoise * (1.0 + std::sqrt(planar2))) {
    // Along a ruling through the apex.
    if (std::abs(c) <= 2.0 * tolerance * (std::sqrt(planar2) + std::abs(rho_q))) {
      out.degenerate = true;
    }
    return;
  }
  std::array<double, 2> roots{};
  bool multiple = false;
  const int n = solve_quadratic(a, hb, c, planar2 + rho_q * rho_q, roots, multiple);
  for (int i = 0; i < n; ++i) {
    const double tau = roots[static_cast<std::size_t>(i)];
    if (tau < line.lo || tau > line.hi) continue;
    const Vec3 x = q + tau * e;
    const double rho_face = r + k * x.z();
    if (rho_face < -tolerance) continue;  // the other nappe is not part of the surface
    const double rho = std::hypot(x.x(), x.y());
    bool tangent = multiple || rho <= tolerance;
    if (!tangent) {
      const double cosine =
          std::abs(std::cos(phi) * (x.x() * e.x() + x.y() * e.y()) / rho - std::sin(phi) * e.z());
      tangent = cosine < kGrazingCosine;
    }
    const double u = rho > 0.0 ? wrap(std::atan2(x.y(), x.x())) : 0.0;
    push_hit(out, line.shift + tau, Vec2(u, x.z() / std::cos(phi)), tangent);
  }
}

void intersect_sphere(const SphereSurface& s, const Vec3& o, const Vec3& d, double t0, double t1,
                      double tolerance, LineSurfaceIntersection& out) {
  (void)tolerance;  // a line cannot lie on a sphere
  const CentredLine line = centre(o, d, t0, t1);
  const Vec3 q = in_frame(s.frame(), line.origin);
  const Vec3 e = direction_in_frame(s.frame(), d);
  const double r = s.radius();
  const double q2 = q.squaredNorm();
  std::array<double, 2> roots{};
  bool multiple = false;
  const int n = solve_quadratic(1.0, q.dot(e), q2 - r * r, q2 + r * r, roots, multiple);
  for (int i = 0; i < n; ++i) {
    const double tau = roots[static_cast<std::size_t>(i)];
    if (tau < line.lo || tau > line.hi) continue;
    const Vec3 x = q + tau * e;
    const double rho = std::hypot(x.x(), x.y());
    const double u = rho > 0.0 ? wrap(std::atan2(x.y(), x.x())) : 0.0;
    const double cosine = std::abs(x.dot(e)) / r;
    push_hit(out, line.shift + tau, Vec2(u, std::atan2(x.z(), rho)),
             multiple || cosine < kGrazingCosine);
  }
}

void intersect_torus(const TorusSurface& s, const Vec3& o, const Vec3& d, double t0, double t1,
                     LineSurfaceIntersection& out) {
  const CentredLine line = centre(o, d, t0, t1);
  const Vec3 q = in_frame(s.frame(), line.origin);
  const Vec3 e = direction_in_frame(s.frame(), d);
  const double big = s.major_radius();
  const double small = s.minor_radius();
  // Restrict τ to the torus's bounding sphere as well as the window.
  const double closest = -q.dot(e);
  const double miss2 = (q + closest * e).squaredNorm();
  const double outer = (big + small) * (1.0 + kBoundsPadRelative);
  if (miss2 > outer * outer) return;
  const double half = std::sqrt(outer * outer - miss2);
  const double lo = std::max(line.lo, closest - half);
  const double hi = std::min(line.hi, closest + half);
  if (!(lo <= hi)) return;
  // (|X|² + R² − r²)² − 4R²(x² + y²) = 0 along X = q + τe, |e| = 1.
  const double b = 2.0 * q.dot(e);
  const double c_value = q.squaredNorm() + big * big - small * small;
  const double c_size = q.squaredNorm() + big * big + small * small;
  const double a2 = e.x() * e.x() + e.y() * e.y();
  const double a1 = 2.0 * (q.x() * e.x() + q.y() * e.y());
  const double a0 = q.x() * q.x() + q.y() * q.y();
  const double r4 = 4.0 * big * big;
  const std::array<double, 5> coefficients{c_value * c_value - r4 * a0, 2.0 * b * c_value - r4 * a1,
                                           b * b + 2.0 * c_value - r4 * a2, 2.0 * b, 1.0};
  const std::array<double, 5> magnitudes{c_size * c_size + r4 * a0,
                                         2.0 * std::abs(b) * c_size + r4 * std::abs(a1),
                                         b * b + 2.0 * c_size + r4 * a2, 2.0 * std::abs(b), 1.0};
  std::vector<PolynomialRoot> roots;
  polynomial_roots(coefficients.data(), 4, lo, hi, roots, magnitudes.data());
  for (const PolynomialRoot& root : roots) {
    const Vec3 x = q + root.x * e;
    const double rho = std::hypot(x.x(), x.y());
    const double u = rho > 0.0 ? wrap(std::atan2(x.y(), x.x())) : 0.0;
    const double radial = rho - big;
    const double v = (radial == 0.0 && x.z() == 0.0) ? 0.0 : wrap(std::atan2(x.z(), radial));
    // Normal: from the tube's centre circle to x.
    const Vec3 tube_centre =
        rho > 0.0 ? Vec3(big * x.x() / rho, big * x.y() / rho, 0.0) : Vec3::Zero();
    const Vec3 n = x - tube_centre;
    const double len = n.norm();
    const double cosine = len > 0.0 ? std::abs(n.dot(e)) / len : 0.0;
    push_hit(out, line.shift + root.x, Vec2(u, v), root.multiple || cosine < kGrazingCosine);
  }
}

// ---- swept surfaces ------------------------------------------------------------------------

// A conic c + a·cos t + b·sin t (circle, ellipse, trig curve); false for other kinds.
bool as_conic(const Curve& curve, Vec3& c, Vec3& a, Vec3& b) {
  switch (curve.kind()) {
    case CurveKind::Circle: {
      const auto& circle = static_cast<const CircleCurve&>(curve);
      c = circle.frame().origin;
      a = circle.radius() * circle.frame().x;
      b = circle.radius() * circle.frame().y;
      return true;
    }
    case CurveKind::Ellipse: {
      const auto& ellipse = static_cast<const EllipseCurve&>(curve);
      c = ellipse.frame().origin;
      a = ellipse.major_radius() * ellipse.frame().x;
      b = ellipse.minor_radius() * ellipse.frame().y;
      return true;
    }
    case CurveKind::Trig: {
      const auto& trig = static_cast<const TrigCurve&>(curve);
      c = trig.center();
      a = trig.a();
      b = trig.b();
      return true;
    }
    default:
      return false;
  }
}

// Affine pieces of a line or polyline curve: C(t) = m + t·e for t in [first, last].
struct AffinePiece {
  Vec3 m, e;
  double first, last;
};

// The affine pieces of a line or polyline overlapping [t0, t1].
std::vector<AffinePiece> affine_pieces(const Curve& curve, double t0, double t1) {
  std::vector<AffinePiece> pieces;
  if (curve.kind() == CurveKind::Line) {
    const auto& line = static_cast<const LineCurve&>(curve);
    pieces.push_back({line.origin(), line.direction(), -std::numeric_limits<double>::infinity(),
                      std::numeric_limits<double>::infinity()});
  } else if (curve.kind() == CurveKind::Polyline) {
    const auto& points = static_cast<const PolylineCurve&>(curve).points();
    const auto last = static_cast<double>(points.size() - 1);
    const double from = std::max(0.0, std::floor(t0));
    const double to = std::min(last, std::ceil(t1));
    if (!(from < to)) return pieces;
    for (auto k = static_cast<std::size_t>(from); static_cast<double>(k) < to; ++k) {
      const auto i = static_cast<double>(k);
      const Vec3 e = points[k + 1] - points[k];
      pieces.push_back({points[k] - i * e, e, i, i + 1.0});
    }
  }
  return pieces;
}

// Whether a root at parameter s of a piece [first, last) belongs to it; `flag` is set when
// the root sits at a breakpoint shared with a neighbouring piece.
bool in_piece(double s, const AffinePiece& piece, bool& flag) {
  if (!std::isfinite(piece.first)) return true;
  if (s < piece.first || s >= piece.last) return false;
  const double slack = kBreakpointSlack * (piece.last - piece.first);
  flag = s - piece.first < slack || piece.last - s < slack;
  return true;
}

// Newton steps on S(u, v) = o + t·d from a root of the swept-surface equations: those
// eliminate a variable by dividing by a quantity that may be small (the line's component
// along the axis), which magnifies rounding in the eliminated one. Stops at a singular
// Jacobian (the line touches the surface there: the caller flags the hit as tangent anyway).
void polish(const Surface& s, const Vec3& o, const Vec3& d, double& t, Vec2& uv) {
  for (int iteration = 0; iteration < 4; ++iteration) {
    const Vec3 residual = s.point(uv.x(), uv.y()) - (o + t * d);
    Eigen::Matrix3d jacobian;
    jacobian.col(0) = s.du(uv.x(), uv.y());
    jacobian.col(1) = s.dv(uv.x(), uv.y());
    jacobian.col(2) = -d;
    const double det = jacobian.determinant();
    const double scale = jacobian.col(0).norm() * jacobian.col(1).norm();
    if (!(std::abs(det) > kSingularJacobian * scale)) return;
    const Vec3 step = jacobian.inverse() * residual;
    uv -= Vec2(step.x(), step.y());
    t -= step.z();
    if (step.norm() <= 4.0 * kEps * (std::abs(t) + uv.norm() + 1.0)) return;
  }
}

void intersect_extrusion(const ExtrusionSurface& s, const Vec3& o, const Vec3& d, double t0,
                         double t1, const ParamBox& range, double tolerance,
                         LineSurfaceIntersection& out) {
  const Vec3& axis = s.direction();
  Vec3 n = axis.cross(d);
  const double n_length = n.norm();
  if (n_length <= kSweptConditioning) {
    out.degenerate = true;  // parallel to the rulings
    return;
  }
  n /= n_length;
  // A point of the line is on the surface iff its projection along the rulings is on the
  // basis's projection: (C(u) − o)·n = 0, n ⊥ rulings and line.
  const double cos_ad = d.dot(axis);
  struct Root {
    double u;
    bool flag;
  };
  std::vector<Root> us;
  const Curve& basis = *s.basis();
  Vec3 c, a, b;
  if (as_conic(basis, c, a, b)) {
    std::array<double, 2> roots{};
    bool multiple = false;
    const double alpha = (c - o).dot(n);
    const double beta = a.dot(n);
    const double gamma = b.dot(n);
    if (std::hypot(beta, gamma) <= kRelativeNoise * (a.norm() + b.norm())) {
      if (std::abs(alpha) <= tolerance) out.degenerate = true;
      return;
    }
    const int k = solve_trig_linear(alpha, beta, gamma, roots, multiple);
    for (int i = 0; i < k; ++i) us.push_back({roots[static_cast<std::size_t>(i)], multiple});
  }
  for (const AffinePiece& piece : affine_pieces(basis, range.u0, range.u1)) {
    const double slope = piece.e.dot(n);
    const double value = (piece.m - o).dot(n);
    if (std::abs(slope) <= kRelativeNoise * piece.e.norm()) {
      // A ruling plane parallel to the line.
      if (std::abs(value) <= tolerance) out.degenerate = true;
      continue;
    }
    const double u = -value / slope;
    bool flag = false;
    if (!in_piece(u, piece, flag)) continue;
    us.push_back({u, flag});
  }
  for (const Root& root : us) {
    const Vec3 w = basis.point(root.u) - o;
    double t = (w.dot(d) - cos_ad * w.dot(axis)) / (1.0 - cos_ad * cos_ad);
    Vec2 uv(root.u, cos_ad * t - w.dot(axis));
    polish(s, o, d, t, uv);
    if (t < t0 || t > t1) continue;
    const double cosine = std::abs(s.normal(uv.x(), uv.y()).dot(d));
    push_hit(out, t, uv, root.flag || cosine < kGrazingCosine);
  }
}

// |w0 + w1·cos v + w2·sin v|² as h0 + h1c·cos v + h1s·sin v + h2c·cos 2v + h2s·sin 2v.
struct TrigQuadratic {
  double h0 = 0, h1c = 0, h1s = 0, h2c = 0, h2s = 0, size = 0;
  void add_square(const Vec3& w0, const Vec3& w1, const Vec3& w2, double sign) {
    h0 += sign * (w0.squaredNorm() + 0.5 * (w1.squaredNorm() + w2.squaredNorm()));
    h1c += sign * 2.0 * w0.dot(w1);
    h1s += sign * 2.0 * w0.dot(w2);
    h2c += sign * 0.5 * (w1.squaredNorm() - w2.squaredNorm());
    h2s += sign * w1.dot(w2);
    const double s = w0.norm() + w1.norm() + w2.norm();
    size += s * s;
  }
};

// Roots v in [v0, v1] of a degree-2 trigonometric polynomial: on chunks no wider than π/2,
// the substitution x = tan((v − m)/2) about the chunk's middle m turns it into a quartic in
// a bounded x (times the positive (1 + x²)²).
void trig_quadratic_roots(const TrigQuadratic& h, double v0, double v1,
                          std::vector<PolynomialRoot>& out) {
  const int chunks = std::max(1, static_cast<int>(std::ceil((v1 - v0) / (0.5 * std::numbers::pi))));
  const double width = (v1 - v0) / chunks;
  std::vector<PolynomialRoot> roots;
  for (int k = 0; k < chunks; ++k) {
    const double va = v0 + k * width;
    const double vb = k + 1 == chunks ? v1 : va + width;
    const double mid = 0.5 * (va + vb);
    const double c1 = std::cos(mid), s1 = std::sin(mid);
    const double c2 = std::cos(2.0 * mid), s2 = std::sin(2.0 * mid);
    // H(m + w) in cos w, sin w, cos 2w, sin 2w.
    const double p1c = h.h1c * c1 + h.h1s * s1, p1s = -h.h1c * s1 + h.h1s * c1;
    const double p2c = h.h2c * c2 + h.h2s * s2, p2s = -h.h2c * s2 + h.h2s * c2;
    const std::array<double, 5> c{h.h0 + p1c + p2c, 2.0 * p1s + 4.0 * p2s, 2.0 * h.h0 - 6.0 * p2c,
                                  2.0 * p1s - 4.0 * p2s, h.h0 - p1c + p2c};
    const std::array<double, 5> m{8.0 * h.size, 8.0 * h.size, 8.0 * h.size, 8.0 * h.size,
                                  8.0 * h.size};
    roots.clear();
    polynomial_roots(c.data(), 4, std::tan(0.5 * (va - mid)), std::tan(0.5 * (vb - mid)), roots,
                     m.data());
    for (const PolynomialRoot& r : roots) {
      const double v = mid + 2.0 * std::atan(r.x);
      // Chunks share their ends: a root there is found twice.
      if (!out.empty() && std::abs(v - out.back().x) <= kRootMergeRelative * (1.0 + std::abs(v))) {
        out.back().multiple = out.back().multiple || r.multiple;
        continue;
      }
      out.push_back({v, r.multiple});
    }
  }
}

void intersect_revolution(const RevolutionSurface& s, const Vec3& o, const Vec3& d, double t0,
                          double t1, const ParamBox& range, double tolerance,
                          LineSurfaceIntersection& out) {
  const Vec3& axis = s.axis_direction();
  const double dz = d.dot(axis);
  if (std::abs(dz) < kSweptConditioning) {
    out.degenerate = true;  // (nearly) perpendicular to the axis
    return;
  }
  const CentredLine line = centre(o, d, t0, t1);
  const Vec3 q = line.origin - s.axis_origin();
  const double qz = q.dot(axis);
  const Vec3 q_perp = q - qz * axis;
  const Vec3 d_perp = d - dz * axis;
  auto perp = [&](const Vec3& w) { return Vec3(w - w.dot(axis) * axis); };
  // A meridian point V(v) (relative to the axis origin) is met where the line reaches its
  // height, τ = (z(v) − qz)/dz, at its distance from the axis:
  //   |dz·q⊥ + (z(v) − qz)·d⊥|² − dz²·|V⊥(v)|² = 0.
  struct Root {
    double v;
    bool flag;
  };
  std::vector<Root> vs;
  const Curve& meridian = *s.meridian();
  Vec3 c, a, b;
  if (as_conic(meridian, c, a, b)) {
    c -= s.axis_origin();
    TrigQuadratic h;
    h.add_square(dz * q_perp + (c.dot(axis) - qz) * d_perp, a.dot(axis) * d_perp,
                 b.dot(axis) * d_perp, 1.0);
    h.add_square(dz * perp(c), dz * perp(a), dz * perp(b), -1.0);
    double v0 = range.v0, v1 = range.v1;
    if (!(v1 - v0 < kTwoPi)) v1 = v0 + kTwoPi;
    std::vector<PolynomialRoot> roots;
    trig_quadratic_roots(h, v0, v1, roots);
    for (const PolynomialRoot& r : roots) vs.push_back({r.x, r.multiple});
  }
  for (const AffinePiece& piece : affine_pieces(meridian, range.v0, range.v1)) {
    const Vec3 m = piece.m - s.axis_origin();
    const double zm = m.dot(axis), ez = piece.e.dot(axis);
    const Vec3 m_perp = perp(m), e_perp = perp(piece.e);
    const Vec3 a0 = dz * q_perp + (zm - qz) * d_perp;
    const Vec3 a1 = ez * d_perp;
    const double dz2 = dz * dz;
    const double qa = a1.squaredNorm() - dz2 * e_perp.squaredNorm();
    const double hb = a0.dot(a1) - dz2 * m_perp.dot(e_perp);
    const double qc = a0.squaredNorm() - dz2 * m_perp.squaredNorm();
    const double size = a0.squaredNorm() + dz2 * m_perp.squaredNorm();
    if (std::abs(qa) <= kRelativeNoise * (a1.squaredNorm() + dz2 * e_perp.squaredNorm() + kTiny) &&
        std::abs(hb) <=
            kRelativeNoise *
                (std::sqrt(size) * (a1.norm() + std::abs(dz) * e_perp.norm()) + kTiny)) {
      // The line lies on the cone (or cylinder) this segment sweeps, or never meets it.
      if (std::abs(qc) <= 2.0 * tolerance * std::sqrt(size)) out.degenerate = true;
      continue;
    }
    std::array<double, 2> roots{};
    bool multiple = false;
    const int n = solve_quadratic(qa, hb, qc, size, roots, multiple);
    for (int i = 0; i < n; ++i) {
      const double v = roots[static_cast<std::size_t>(i)];
      bool flag = false;
      if (!in_piece(v, piece, flag)) continue;
      vs.push_back({v, flag || multiple});
    }
  }
  for (const Root& root : vs) {
    const Vec3 meridian_point = meridian.point(root.v) - s.axis_origin();
    double tau = (meridian_point.dot(axis) - qz) / dz;
    const Vec3 x = q + tau * d;
    const Vec3 x_perp = perp(x), m_perp = perp(meridian_point);
    const double u = m_perp.squaredNorm() > 0.0
                         ? wrap(std::atan2(axis.dot(m_perp.cross(x_perp)), m_perp.dot(x_perp)))
                         : 0.0;
    Vec2 uv(u, root.v);
    polish(s, line.origin, d, tau, uv);
    if (tau < line.lo || tau > line.hi) continue;
    const double cosine = std::abs(s.normal(uv.x(), uv.y()).dot(d));
    push_hit(out, line.shift + tau, uv, root.flag || cosine < kGrazingCosine);
  }
}

}  // namespace

void intersect_line_surface(const Surface& surface, const Vec3& origin, const Vec3& direction,
                            double t0, double t1, const ParamBox& range, double tolerance,
                            LineSurfaceIntersection& out) {
  out.hits.clear();
  out.degenerate = false;
  if (!(t0 <= t1)) return;
  switch (surface.kind()) {
    case SurfaceKind::Plane:
      intersect_plane(static_cast<const PlaneSurface&>(surface), origin, direction, t0, t1,
                      tolerance, out);
      break;
    case SurfaceKind::Cylinder:
      intersect_cylinder(static_cast<const CylinderSurface&>(surface), origin, direction, t0, t1,
                         tolerance, out);
      break;
    case SurfaceKind::Cone:
      intersect_cone(static_cast<const ConeSurface&>(surface), origin, direction, t0, t1, tolerance,
                     out);
      break;
    case SurfaceKind::Sphere:
      intersect_sphere(static_cast<const SphereSurface&>(surface), origin, direction, t0, t1,
                       tolerance, out);
      break;
    case SurfaceKind::Torus:
      intersect_torus(static_cast<const TorusSurface&>(surface), origin, direction, t0, t1, out);
      break;
    case SurfaceKind::Extrusion:
      intersect_extrusion(static_cast<const ExtrusionSurface&>(surface), origin, direction, t0, t1,
                          range, tolerance, out);
      break;
    case SurfaceKind::Revolution:
      intersect_revolution(static_cast<const RevolutionSurface&>(surface), origin, direction, t0,
                           t1, range, tolerance, out);
      break;
  }
}

}  // namespace csgtile::kernel::detail
