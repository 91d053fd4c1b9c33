#pragma once
/// \file
/// A fast, verified stand-in for Georeferencer::to_local over one tile's box of source
/// coordinates, for bulk point clouds.
///
/// Method. For a fixed (x, y), the exact path is affine in z: local(x, y, z) = P(x, y) +
/// z·Q(x, y), because ECEF(φ, λ, h) = ECEF(φ, λ, 0) + h·n(φ, λ), and the Helmert shift, the
/// ENU frame and the z unit are affine. P and Q are smooth over a tile, so each of their six
/// components is interpolated by a tensor Chebyshev polynomial in (x, y) of the lowest degree
/// (3 to 12) whose error, measured against the exact path on a grid four times denser than the
/// interpolation nodes (edges and corners included) and at the box's lowest and highest z, is
/// at most the requested bound. Points outside the box take the exact path.
///
/// Cost: (degree + 1)² multiply-adds per component instead of a projection inverse, a datum
/// shift and an ECEF → ENU rotation per point. Immutable; const calls may run concurrently.
/// Deterministic: same Georeferencer, box and bound → same coefficients and outputs.

#include <span>
#include <vector>

#include "csgtile/geo/georeference.h"
#include "csgtile/kernel/bounding_box.h"

namespace csgtile::geo {

class TileMapping {
 public:
  /// Fits the mapping over `box` (source CRS coordinates, z included) for points whose
  /// result must be within `max_error_m` metres of the exact path. Errors: InvalidArgument
  /// for an empty or non-finite box, a bound <= 0, or a box reaching outside the projection's
  /// domain; Unsupported when degree 12 does not reach the bound (a box far too large).
  static kernel::Result<TileMapping> fit(const Georeferencer& georeferencer,
                                         const kernel::BoundingBox& box, double max_error_m = 1e-7);

  /// Source → local: the polynomial inside the box (x, y within, z anywhere within the box's
  /// z range), the exact path elsewhere (NaNs outside the domain, as Georeferencer).
  kernel::Vec3 to_local(const kernel::Vec3& source_xyz) const;
  /// Bulk form; `out` must have the size of `in`. Errors as Georeferencer's bulk to_local.
  kernel::Status to_local(std::span<const kernel::Vec3> in, std::span<kernel::Vec3> out) const;

  int degree() const { return degree_; }
  /// The largest deviation from the exact path found in verification, metres.
  double verified_error_m() const { return verified_error_m_; }
  const kernel::BoundingBox& box() const { return box_; }

 private:
  explicit TileMapping(Georeferencer georeferencer) : georeferencer_(std::move(georeferencer)) {}
  kernel::Vec3 evaluate(const kernel::Vec3& p) const;

  Georeferencer georeferencer_;
  kernel::BoundingBox box_;
  double cx_ = 0, cy_ = 0, inv_hx_ = 1, inv_hy_ = 1;
  int degree_ = 0;
  double verified_error_m_ = 0;
  /// Per (k, j) with k the y order and j the x order: the six components (P, Q).
  std::vector<double> coefficients_;
};

}  // namespace csgtile::geo
