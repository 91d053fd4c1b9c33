#pragma once
/// \file
/// Builders for the primitive solids (local frames of ../shared/spec/scene-format.md).
/// Every builder returns a closed, valid, outward-oriented solid whose faces share their
/// edges and vertices; place it with Shape::moved(location).
///
/// Topology counts (solid / shell / face / wire / edge / vertex; degenerate edges included
/// in "edge" and listed separately):
/// | primitive                    | F  | W  | E             | V  | notes                          |
/// |------------------------------|----|----|---------------|----|--------------------------------|
/// | box                          | 6  | 6  | 12            | 8  |                                |
/// | cylinder                     | 3  | 3  | 3             | 2  | 2 circles + 1 seam line        |
/// | frustum (r1, r2 > 0)         | 3  | 3  | 3             | 2  | as cylinder                    |
/// | cone (one radius 0)          | 2  | 2  | 3 (1 degen.)  | 2  | circle, seam, apex             |
/// | sphere                       | 1  | 1  | 3 (2 degen.)  | 2  | seam half-circle, two poles    |
/// | torus                        | 1  | 1  | 2             | 1  | meridian and equator seams     |
/// | extrusion, n profile vertices (all rings), r rings | n+2 | n+2r | 3n | 2n |            |
/// | revolution: see make_revolution                                                      |

#include <vector>

#include "csgtile/kernel/shape.h"

namespace csgtile::kernel {

/// Tolerance given to the vertices, edges and faces of built primitives (metres).
inline constexpr double kDefaultTolerance = 1e-7;

/// [0,dx]×[0,dy]×[0,dz]. Error: InvalidArgument unless all sizes are finite and > 0.
Result<Shape> make_box(double dx, double dy, double dz, double tolerance = kDefaultTolerance);

/// Axis +Z, base disc at z = 0, top at z = h. Error: InvalidArgument unless r, h > 0.
Result<Shape> make_cylinder(double r, double h, double tolerance = kDefaultTolerance);

/// Radius r1 at z = 0, r2 at z = h; one radius may be 0 (a cone with its apex there),
/// r1 = r2 gives a cylinder. Error: InvalidArgument for negative radii, both zero, h <= 0.
Result<Shape> make_cone(double r1, double r2, double h, double tolerance = kDefaultTolerance);

/// Centred at the origin; the seam lies in the half-plane y = 0, x > 0.
Result<Shape> make_sphere(double r, double tolerance = kDefaultTolerance);

/// Centred at the origin, axis Z, major radius R > minor radius r > 0.
Result<Shape> make_torus(double major_radius, double minor_radius,
                         double tolerance = kDefaultTolerance);

/// A simple polygon (outer ring, any orientation) with holes in the XY plane, swept along +Z
/// by h. Errors: DegenerateGeometry for fewer than 3 distinct points, zero area,
/// self-intersecting rings, holes outside the outer ring or overlapping each other;
/// InvalidArgument for h <= 0.
Result<Shape> make_extrusion(const std::vector<Vec2>& outer,
                             const std::vector<std::vector<Vec2>>& holes, double h,
                             double tolerance = kDefaultTolerance);

/// Revolution about Z of a closed profile polygon given as (rho, z) points with rho >= 0
/// (any orientation), by `angle` in (0, 2π]. A profile segment becomes a cylinder (rho
/// constant), a plane (z constant) or a cone face; segments on the axis bound nothing for a
/// full revolution. A full revolution has one face per off-axis segment, one circle edge and
/// vertex per off-axis profile vertex, one seam edge per curved face and one degenerate edge
/// per cone face touching the axis; a partial one adds two planar end faces, arcs instead of
/// circles and no seams. Errors: DegenerateGeometry (self-intersecting or zero-area profile,
/// rho < 0), InvalidArgument (angle out of range).
Result<Shape> make_revolution(const std::vector<Vec2>& profile, double angle,
                              double tolerance = kDefaultTolerance);

}  // namespace csgtile::kernel

namespace csgtile::kernel {

enum class PrimitiveType : std::uint8_t {
  Box = 0,
  Cylinder = 1,
  Cone = 2,
  Sphere = 3,
  Torus = 4,
  Extrusion = 5,
  Revolution = 6
};
inline constexpr int kPrimitiveTypeCount = 7;

/// "box", "cylinder", "cone", "sphere", "torus", "extrusion", "revolution".
const char* primitive_type_name(PrimitiveType type);

/// Parameters of one primitive in its local frame, and its placement: the CSG leaf that a
/// solid is built from (and that CSG history and the native format keep).
struct PrimitiveSpec {
  PrimitiveType type = PrimitiveType::Box;
  Vec3 size = Vec3::Ones();              ///< box: dx, dy, dz
  double radius = 0.0;                   ///< cylinder r, cone r1, sphere r, torus R (major)
  double radius2 = 0.0;                  ///< cone r2, torus r (minor)
  double height = 0.0;                   ///< cylinder, cone, extrusion h
  std::vector<Vec2> profile;             ///< extrusion outer ring (x, y); revolution (rho, z)
  std::vector<std::vector<Vec2>> holes;  ///< extrusion holes
  double angle = 6.283185307179586;      ///< revolution angle
  /// Half-spaces the primitive is cut by, in its local frame: the part where n·p <= d is
  /// kept, for each (n, d) = (x, y, z), w with n a unit vector (a building's roof part: the
  /// extrusion of its outline under its roof plane). Empty for a plain primitive.
  std::vector<Eigen::Vector4d> clips;
  Location placement;
};

/// Builds the primitive's solid (cut by its clips, exactly, with the Boolean engine at
/// `tolerance`) and moves it by its placement. Errors as the builders; DegenerateGeometry when
/// a clip is not a unit normal and a finite offset, removes the whole solid or splits it.
Result<Shape> build_primitive(const PrimitiveSpec& spec, double tolerance = kDefaultTolerance);

}  // namespace csgtile::kernel
