#pragma once
/// \file
/// Primitive fitting: an efficient RANSAC (after Schnabel, Wahl and Klein 2007) that finds
/// planes, spheres, cylinders, cones and tori in a point cloud with normals, and the step that
/// turns those shapes into scene primitives (extrusions from walls or from a flat roof's
/// outline, revolutions from coaxial surfaces, boxes from orthogonal planes, bounded
/// cylinders, cones, spheres, tori) built and checked as kernel solids.
///
/// Determinism. Every random choice comes from one seeded generator with our own transforms;
/// the detection is single-threaded and iterates in index order, so the same points, options
/// and seed give the same shapes, bit for bit.

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "csgtile/geo/footprints.h"
#include "csgtile/geo/scene.h"
#include "csgtile/kernel/interrupt.h"
#include "csgtile/kernel/location.h"

namespace csgtile::fit {

/// The surfaces the RANSAC detects.
enum class ShapeType : std::uint8_t { Plane, Sphere, Cylinder, Cone, Torus };
inline constexpr int kShapeTypeCount = 5;
/// "plane", "sphere", "cylinder", "cone", "torus".
const char* shape_type_name(ShapeType type);

/// An unbounded surface. `axis` is a unit vector.
///  - plane: `point` on it, `axis` its normal;
///  - sphere: `point` the centre, `radius`;
///  - cylinder: `point` on the axis, `axis`, `radius`;
///  - cone: `point` the apex, `axis` pointing into the cone, `angle` the half-angle (radians);
///  - torus: `point` the centre, `axis`, `radius` major R, `radius2` minor r.
struct Surface {
  ShapeType type = ShapeType::Plane;
  kernel::Vec3 point = kernel::Vec3::Zero();
  kernel::Vec3 axis = kernel::Vec3::UnitZ();
  double radius = 0.0;
  double radius2 = 0.0;
  double angle = 0.0;
};

/// Signed distance from `p` to the surface (positive outside / along the normal).
double surface_distance(const Surface& s, const kernel::Vec3& p);
/// Unit normal of the surface at the foot of `p` (unoriented for a plane: its axis).
kernel::Vec3 surface_normal(const Surface& s, const kernel::Vec3& p);

/// Options of the RANSAC. Lengths in metres (in the cloud's units). The scale-dependent ones
/// may be 0: then each region derives them from its own points (see RansacResult), so that
/// one setting serves a CAD object in millimetres and a city tile in metres alike.
struct RansacOptions {
  /// Inlier distance; 0: the larger of 3 × the region's noise (the 5 % quantile of its
  /// neighbourhoods' RMS distance to their plane) and 0.1 × its point spacing.
  double epsilon = 0.02;
  double normal_deviation_deg = 25.0;  ///< largest angle between a point's normal and the surface's
  double cluster_epsilon = 0.0;        ///< connectivity (grid cell) size; 0: from the spacing
  /// Smallest shape; 0: 1 ‰ of the region's points, at least 8 (exact points need few).
  long long min_points = 40;
  double probability = 0.99;  ///< of not having missed a shape of min_points
  /// Larger radii are treated as planes; 0: ten times the region's largest extent.
  double max_radius = 30.0;
  std::uint64_t seed = 1;
  std::array<bool, kShapeTypeCount> shapes{true, true, true, true, true};  ///< by ShapeType
  std::uint64_t max_candidates = 2000000;  ///< hard cap on minimal samples drawn
  /// After detection, each point goes to the neighbouring shape it fits best (not to the one
  /// found first), free points join a shape they lie on, changed shapes are refitted.
  bool relabel = false;
  /// Then (with or without relabel) a point on two neighbouring shapes (within epsilon of
  /// both: their shared edge, on exact points) goes to the smaller one when that has at most
  /// half the other's points — a hole's or fillet's rim, not the face's. For exact clouds; on
  /// noisy ones epsilon is wide and small shapes would take a face's points.
  bool edges_to_smaller = false;
  /// Each extracted shape's type is chosen by evidence: the plane or cylinder (for a sphere
  /// also the cone, from the points' normals) fitting the same points replaces it when it
  /// keeps them and scores better by an information criterion (n·ln(RSS/n) + k·ln n, the
  /// residual floored at the noise); a simpler surface replaces a curved one only when it also
  /// scores no worse. On exact clouds (noise under a twentieth of epsilon) a plane whose points
  /// bend away from it is a cylinder when one through them is exact (RMS within that floor)
  /// and scores better: a narrow strip of a wide cylinder; and a plane whose points lie on one
  /// circle of it, with points of the cylinder through that circle off its plane next to it,
  /// is that cylinder: a hole's wall seen as one ring of points between its rims.
  bool by_evidence = false;
  /// Factor on the connectivity derived when cluster_epsilon is 0 (1.5 × the spacing, or the
  /// 90 % quantile of the distance to the 16th neighbour where larger): below 1, coplanar faces
  /// with a narrow gap between them stay two shapes.
  double cluster_scale = 1.0;
  /// Looked at between batches of samples: once it fires, detect_shapes returns Cancelled.
  kernel::Interrupt interrupt{};
  /// Last, two shapes of one type on one surface (95 % of each one's inliers within epsilon of
  /// the other's surface) whose points come within a narrow gap of each other
  /// become one shape, refitted: one face the connectivity broke apart (a sparse or uneven
  /// sampling, a thin neck) is one shape again. The gap allowed is 1.9 times the larger of
  /// the two shapes' 90 % quantiles of their points' nearest-neighbour distances: across a
  /// face, gaps stay under twice that quantile, while distinct coplanar faces of designed
  /// objects lie further apart (measured on the Fit4CAD training clouds: merged pairs up to
  /// 1.74, distinct faces from 2.13). For CAD-like clouds; off by default.
  bool merge_same_surface = false;
  bool operator==(const RansacOptions&) const = default;
};

/// One detected shape: the refitted surface and its inliers (a connected component).
struct DetectedShape {
  Surface surface;
  std::vector<std::uint32_t> inliers;  ///< indices into the input, ascending
  double rms = 0.0;                    ///< of the inliers' distances
};

struct RansacResult {
  std::vector<DetectedShape> shapes;  ///< in the order they were extracted
  std::vector<int> assignment;        ///< per point: index into shapes, -1 unassigned
  std::uint64_t candidates = 0;       ///< minimal samples drawn
  double spacing = 0.0;               ///< median of 1/sqrt(local density)
  double cluster_epsilon = 0.0;       ///< connectivity size used
  double epsilon = 0.0;               ///< inlier distance used (the option, or derived)
  long long min_points = 0;           ///< smallest shape used
  double max_radius = 0.0;            ///< largest radius used
  double noise = 0.0;                 ///< estimated when epsilon was derived, else 0
  /// The 5 % quantile of the region's neighbourhood plane residuals, over all its points
  /// (the primitives' quality reads it); unset when some points are not finite.
  std::optional<double> plane_noise = {};
  std::string reason;  ///< why nothing was found (empty when shapes were)
};

/// Detects shapes in `points` with unit `normals` (same size; a zero normal marks a point
/// without one, which can only join shapes, never seed them). Non-finite points are ignored.
/// Errors: InvalidArgument for mismatched sizes or bad options. An input with too few usable
/// points is not an error: the result has no shapes and a reason.
kernel::Result<RansacResult> detect_shapes(std::span<const kernel::Vec3> points,
                                           std::span<const kernel::Vec3> normals,
                                           const RansacOptions& options);

/// Terrain heights on a grid (cells without ground are NaN): lets a roof seen from the air,
/// whose walls the scan barely sees, reach down to the ground as a box.
struct GroundGrid {
  double x0 = 0.0, y0 = 0.0, cell = 1.0;
  int nx = 0, ny = 0;
  std::vector<double> z;  ///< row-major by y, nx × ny
  /// Mean ground height per cell (same layout; may be empty: then `z` stands for it).
  std::vector<double> mean;
  /// The lowest height within `radius` metres of (x, y); NaN when there is none.
  double lowest_near(double x, double y, double radius) const;
  /// The median of the cells' mean heights within `radius` metres of (x, y): the terrain
  /// level there without the noise's lowest extremes (flat terrain); NaN when there is none.
  double median_near(double x, double y, double radius) const;
};

/// Options of the step from shapes to primitives.
struct PrimitiveOptions {
  bool boxes = true;            ///< build boxes from orthogonal/parallel planes
  double max_box_depth = 40.0;  ///< farthest a box face may lie from its seed plane
  double min_box_thickness = 0.04;
  double min_seed_coverage = 0.6;  ///< share of a seed plane's rectangle its points cover
  double angle_tolerance_deg = 5.0;
  /// Cylinders, cones and tori whose inliers span a smaller angle around the axis (or, for
  /// cylinders and cones, are shorter than two connectivity cells) are rejected as spurious.
  double min_angular_span_deg = 90.0;
  /// When set, a horizontal seed plane with no depth of its own (none beyond its noise: 3 ε or
  /// 4 × its points' robust σ) at least min_building_height above the ground, and at least
  /// min_building_width wide, becomes a box from the ground up to it (a roof whose walls the
  /// airborne scan barely sees; not a beam's underside); tilted roof planes (one, or two at a
  /// ridge) become extrusions down to the ground; no box reaches below the ground.
  const GroundGrid* ground = nullptr;
  double min_building_height = 2.0;
  double min_building_width = 1.0;
  double linear_tolerance = 1e-7;  ///< of the kernel solids built to check primitives
  /// Extrusions from planes parallel to one direction (an L-shaped or courtyard building, a
  /// gabled house), kept when they describe the region more briefly than a box; also the
  /// buildings under flat roof outlines and under pitched roofs (off: those stay boxes or
  /// roof slabs).
  bool extrusions = true;
  /// Revolutions from coaxial cylinders and cones and the planes ⟂ their axis (a fountain, a
  /// vase, a curved wall); a plain cylinder or cone stays one.
  bool revolutions = true;
  /// Tilted roof planes no pitched roof took become roof parts: the extrusion of their
  /// points' outline from the terrain, clipped by the half-space under the plane (needs
  /// `ground`; issue #18).
  bool roof_parts = true;
  /// Buildings seen from the air as a roof partition (issue #18 item 3): the outline of a
  /// region's points is partitioned among its roof planes (each cell of a grid to the plane
  /// that explains its points, smoothed; points no plane explains as flat LoD1.2 pieces), each
  /// part the extrusion of its polygon from the terrain clipped under its plane, the parts
  /// sharing their walls exactly. Runs after the revolutions and before every other
  /// building step, which then see only the points it left (needs `ground`).
  bool roof_partition = true;
  /// Without a footprint, a block's roof partition is split into houses where its roofs say
  /// so (issue #18 item 2): parts whose roofs meet along their boundary (ridge, hip, valley)
  /// are one house, a height step between them separates two; a house under min_house_area
  /// (square metres), narrower than 1.5 m or with a tenth of its boundary outside joins the
  /// neighbour it shares most boundary with; houses whose solids overlap are one. Each house is a
  /// building of its own (geo::ScenePrimitive::house): never fused with its neighbours, its
  /// contact with them a relation (a party wall).
  bool split_houses = true;
  double min_house_area = 25.0;
  /// A building's footprint (its polygons, in the points' frame; set per region by the fit
  /// pipeline): the roof partition covers exactly it — the grid's cells meeting it, its parts
  /// clipped to it, no outline derived from the points — and the region makes nothing else
  /// (one building per footprint). Points are not needed for its walls.
  const std::vector<geo::FootprintPolygon>* footprint = nullptr;
  /// Points of a region no primitive explains become LoD1.2 blocks (their outline extruded
  /// from the terrain to the 70th percentile of their heights; needs `ground`). The fit
  /// pipeline makes blocks only of classified building points (ClassOptions::keep found).
  bool blocks = true;
  /// Support (every primitive, whichever step made it): a cylinder, cone, sphere, torus or
  /// revolution whose inliers cover less of its surface than this (voxels of the
  /// connectivity cell) is rejected ...
  double min_curved_coverage = 0.05;
  /// ... and so is any primitive reaching farther beyond its region's points (below: beyond
  /// the terrain too) than this share of the region's largest extent, or three
  /// connectivity cells when more.
  double max_overreach = 0.25;
  bool operator==(const PrimitiveOptions&) const = default;
};

/// Why a shape or primitive was dropped.
struct Rejection {
  std::string what;    ///< e.g. "plane 12", "box beam candidate 3"
  std::string reason;  ///< e.g. "no box: no face of a box behind or before it is seen"
  long long points = 0;
};

struct FittedPrimitives {
  std::vector<geo::ScenePrimitive> primitives;  ///< ids "r<region>-<n>", quality filled
  std::vector<Rejection> rejected;
  std::array<long long, kernel::kPrimitiveTypeCount> per_type{};
  long long assigned_points = 0;  ///< points explained by an output primitive
};

/// Turns detected shapes into primitives, in this order: revolutions from two or more
/// distinct coaxial cylinders, cones or tori with the planes ⟂ their axis (a full turn, or the
/// inliers' angular span); extrusions from three or more planes parallel to one direction
/// whose traces close a profile, then from flat roofs' outlines over the ground grid, each
/// kept only when its description length (points unexplained + λ·parameters) beats the box
/// around its profile (so a plain box stays a box); then pitched roofs (one tilted plane, or
/// two rising to a ridge) as extrusions down to the ground grid; then boxes from planes (a seed
/// plane well covered by its points; its depth from the region's points facing like it at the
/// opposite face or across it on its long edges, whether or not the RANSAC made planes of them; its
/// length grown over the points of its faces up to whatever else stands in its cross-section),
/// cylinders and cones bounded by their inliers along the axis, spheres and tori as they are.
/// Each primitive is built as a kernel solid and checked; invalid ones are rejected with the
/// kernel's reason. `region` becomes part of the ids. `normals` are those given to
/// detect_shapes (unit or zero; may be empty, then box faces are found without them).
/// `shapes.assignment` has one entry per point; where it (or `normals`) does not match the
/// points, the result has no primitive and a rejection saying so.
FittedPrimitives primitives_from_shapes(std::span<const kernel::Vec3> points,
                                        std::span<const kernel::Vec3> normals,
                                        const RansacResult& shapes, const PrimitiveOptions& options,
                                        const RansacOptions& ransac, int region);

}  // namespace csgtile::fit
