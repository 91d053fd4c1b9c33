// Oblique stereographic, EPSG Guidance Note 7-2 §3.2.3 (method 9809).
//
// The constants and the reverse (g, h, i, j, then Newton on the isometric latitude) follow
// GN 7-2 term by term. The forward's w = c·(Sa·Sb^e)^n and sin χ = (w − 1)/(w + 1) are
// evaluated in logarithmic form, ln w = ln c + 2n·(atanh sin φ − e·atanh(e sin φ)) and
// sin χ = tanh(ln w / 2), cos χ = sech(ln w / 2): the same numbers, without the cancellation
// of (w − 1)/(w + 1) near the poles.

#include "crs/oblique_stereographic.h"

#include <cmath>

namespace csgtile::geo::detail {
namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

// Isometric latitude ψ(φ) = ln[tan(π/4 + φ/2) · ((1 − e sin φ)/(1 + e sin φ))^(e/2)].
double isometric_latitude(double phi, double e) {
  const double s = std::sin(phi);
  return std::atanh(s) - e * std::atanh(e * s);
}

double wrap_pi(double x) {
  x = std::remainder(x, 2.0 * kPi);
  return x;
}
}  // namespace

ObliqueStereographic::ObliqueStereographic(double a, double f, double lat0_deg, double lon0_deg,
                                           double k0, double false_easting, double false_northing)
    : lon0_(lon0_deg * kDeg), k0_(k0), fe_(false_easting), fn_(false_northing) {
  const double e2 = f * (2.0 - f);
  e_ = std::sqrt(e2);
  const double phi0 = lat0_deg * kDeg;
  const double s0 = std::sin(phi0);
  const double c0 = std::cos(phi0);
  const double d = 1.0 - e2 * s0 * s0;
  const double rho0 = a * (1.0 - e2) / (d * std::sqrt(d));
  const double nu0 = a / std::sqrt(d);
  r_ = std::sqrt(rho0 * nu0);
  n_ = std::sqrt(1.0 + e2 * c0 * c0 * c0 * c0 / (1.0 - e2));
  // w1 = (S1·S2^e)^n, sin χ0' = (w1 − 1)/(w1 + 1) (the "first" conformal latitude of GN 7-2).
  const double ln_w1 = 2.0 * n_ * isometric_latitude(phi0, e_);
  const double sin_chi0_first = std::tanh(ln_w1 / 2.0);
  c_ = (n_ + s0) * (1.0 - sin_chi0_first) / ((n_ - s0) * (1.0 + sin_chi0_first));
  const double ln_w2 = std::log(c_) + ln_w1;
  sin_chi0_ = std::tanh(ln_w2 / 2.0);
  cos_chi0_ = 1.0 / std::cosh(ln_w2 / 2.0);
  chi0_ = std::asin(sin_chi0_);
  g_ = 2.0 * r_ * k0_ * std::tan(kPi / 4.0 - chi0_ / 2.0);
  h_ = 4.0 * r_ * k0_ * std::tan(chi0_) + g_;
}

bool ObliqueStereographic::forward(double lat_deg, double lon_deg, double& easting,
                                   double& northing) const {
  const double phi = lat_deg * kDeg;
  const double dlambda = n_ * wrap_pi(lon_deg * kDeg - lon0_);  // Λ − Λ0
  const double ln_w = std::log(c_) + 2.0 * n_ * isometric_latitude(phi, e_);
  const double sin_chi = std::tanh(ln_w / 2.0);
  const double cos_chi = 1.0 / std::cosh(ln_w / 2.0);
  const double cos_dl = std::cos(dlambda);
  const double b = 1.0 + sin_chi * sin_chi0_ + cos_chi * cos_chi0_ * cos_dl;
  if (!(b > 1e-15)) return false;
  const double two_rk = 2.0 * r_ * k0_;
  easting = fe_ + two_rk * cos_chi * std::sin(dlambda) / b;
  northing = fn_ + two_rk * (sin_chi * cos_chi0_ - cos_chi * sin_chi0_ * cos_dl) / b;
  return std::isfinite(easting) && std::isfinite(northing);
}

bool ObliqueStereographic::reverse(double easting, double northing, double& lat_deg,
                                   double& lon_deg) const {
  if (!std::isfinite(easting) || !std::isfinite(northing)) return false;
  const double de = easting - fe_;
  const double dn = northing - fn_;
  const double i = std::atan(de / (h_ + dn));
  const double j = std::atan(de / (g_ - dn)) - i;
  const double chi = chi0_ + 2.0 * std::atan((dn - de * std::tan(j / 2.0)) / (2.0 * r_ * k0_));
  const double big_lambda = j + 2.0 * i;  // Λ − Λ0
  const double lambda = big_lambda / n_ + lon0_;
  const double sin_chi = std::sin(chi);
  // ψ = 0.5·ln[(1 + sin χ)/(c(1 − sin χ))]/n
  const double psi = (2.0 * std::atanh(sin_chi) - std::log(c_)) / (2.0 * n_);
  const double e2 = e_ * e_;
  double phi = 2.0 * std::atan(std::exp(psi)) - kPi / 2.0;
  for (int iteration = 0; iteration < 50; ++iteration) {
    const double s = std::sin(phi);
    const double step =
        (isometric_latitude(phi, e_) - psi) * std::cos(phi) * (1.0 - e2 * s * s) / (1.0 - e2);
    phi -= step;
    if (std::fabs(step) < 1e-14) {
      lat_deg = phi / kDeg;
      lon_deg = wrap_pi(lambda) / kDeg;
      return std::isfinite(lat_deg) && std::isfinite(lon_deg);
    }
  }
  return false;
}

}  // namespace csgtile::geo::detail
