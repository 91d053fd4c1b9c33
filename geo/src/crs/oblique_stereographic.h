#pragma once
// The oblique stereographic projection (EPSG method 9809, "double stereographic"), as in EPSG
// Guidance Note 7-2 §3.2.3 (the formulas used for RD New): a conformal mapping of the
// ellipsoid to a sphere (Gauss), then a stereographic projection of that sphere.
// GeographicLib has no such projection.

namespace csgtile::geo::detail {

class ObliqueStereographic {
 public:
  /// a: semi-major axis (m); f: flattening; origin latitude/longitude in degrees (|lat0| < 90);
  /// k0: scale at the origin; false easting/northing in metres.
  ObliqueStereographic(double a, double f, double lat0_deg, double lon0_deg, double k0,
                       double false_easting, double false_northing);

  /// Geodetic (degrees) → easting, northing (metres). Returns false for the antipode of the
  /// origin, where the projection is undefined.
  bool forward(double lat_deg, double lon_deg, double& easting, double& northing) const;
  /// Easting, northing → geodetic (degrees). The latitude iteration converges to 1e-14 rad
  /// in a handful of steps; returns false if it does not within 50 or the input is not finite.
  bool reverse(double easting, double northing, double& lat_deg, double& lon_deg) const;

 private:
  double e_;     // first eccentricity
  double lon0_;  // radians
  double k0_, fe_, fn_;
  double r_;     // radius of the conformal sphere, sqrt(rho0 · nu0)
  double n_;     // longitude ratio between sphere and ellipsoid
  double c_;     // latitude mapping constant
  double chi0_;  // conformal latitude of the origin
  double sin_chi0_, cos_chi0_;
  double g_, h_;  // reverse constants of GN 7-2
};

}  // namespace csgtile::geo::detail
