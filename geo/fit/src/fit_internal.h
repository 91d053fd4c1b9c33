#pragma once
// Internals of the fitting module shared by its .cpp files: the spatial grid used for
// localised sampling and connected components, minimal-sample candidates and least-squares
// refits of the surfaces.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

#include "csgtile/fit/fit.h"
#include "csgtile/fit/segment.h"

namespace csgtile::fit::detail {

using kernel::Vec3;

/// floor(v / cell) as an integer, clamped to ±1e15 (and 0 for NaN) so that hostile
/// coordinates never overflow the conversion.
inline long long cell_index(double v, double cell) {
  const double f = std::floor(v / cell);
  if (!(f == f)) return 0;
  return static_cast<long long>(std::clamp(f, -1e15, 1e15));
}

/// A uniform grid of cubes of size `cell` over a subset of the points. Points of a cell are
/// stored contiguously, in an order shuffled by `seed` so that the first k of a cell are a
/// random sample of it. Cells are numbered in ascending key order (deterministic).
class PointGrid {
 public:
  PointGrid(std::span<const Vec3> points, std::span<const std::uint32_t> members, double cell,
            std::uint64_t seed);

  double cell() const { return cell_; }
  std::size_t cell_count() const { return begin_.size() - 1; }
  /// The cell holding point `i`, or -1 when the point is not a member.
  int cell_of(std::uint32_t i) const { return cell_of_[i]; }
  /// The cell at integer coordinates, or -1.
  int find(std::int64_t x, std::int64_t y, std::int64_t z) const;
  std::span<const std::uint32_t> points(int cell) const {
    return {order_.data() + begin_[static_cast<std::size_t>(cell)],
            order_.data() + begin_[static_cast<std::size_t>(cell) + 1]};
  }
  const std::array<std::int64_t, 3>& coords(int cell) const {
    return coords_[static_cast<std::size_t>(cell)];
  }

 private:
  double cell_;
  std::vector<int> cell_of_;
  std::vector<std::uint32_t> order_;
  std::vector<std::uint32_t> begin_;
  std::vector<std::array<std::int64_t, 3>> coords_;
  std::unordered_map<std::uint64_t, int> lookup_;
};

/// The `quantile` (0.5: median) of the local point spacing 1/sqrt(density), measured from the
/// distance r to the 16th neighbour (r·sqrt(π/16)) over a deterministic sample of the members;
/// 0 for fewer than 17 points.
double estimate_spacing(std::span<const Vec3> points, std::span<const std::uint32_t> members,
                        double quantile = 0.5);
/// The `quantile` of the distance to the 16th neighbour itself: the gap a neighbourhood
/// bridges, larger than the spacing where sampling is anisotropic (airborne scan lines are
/// close along a line and far apart across).
double neighbour_reach(std::span<const Vec3> points, std::span<const std::uint32_t> members,
                       double quantile);

/// The `quantile` of the RMS distance of a point's neighbourhood (it and its 16 nearest) to
/// their least-squares plane, over the same sample: the noise of the scan where its surfaces
/// are flat at the scale of a neighbourhood (a low quantile: curvature and edges raise the
/// others); 0 for fewer than 17 points. A neighbourhood on both sides of a plate thinner than
/// itself counts each side's spread about its own level, not their separation (grid.cpp,
/// sheet_residual).
double estimate_noise(std::span<const Vec3> points, std::span<const std::uint32_t> members,
                      double quantile);

/// The sample the three estimates above are quantiles of, taken once for a caller that needs
/// several of them on the same members (each a grid search over up to 2 000 points): the same
/// figures as the functions above. `with_noise`: also the neighbourhoods' plane residuals.
class NeighbourSample {
 public:
  /// `with_noise`: the plane residuals behind noise(); `with_curved`: also the quadric
  /// residuals behind curved_noise() (a QR per neighbourhood; only with `with_noise`).
  NeighbourSample(std::span<const Vec3> points, std::span<const std::uint32_t> members,
                  bool with_noise, bool with_curved = true);
  double spacing(double quantile = 0.5) const;  ///< as estimate_spacing
  double reach(double quantile) const;          ///< as neighbour_reach
  double noise(double quantile) const;          ///< as estimate_noise (0 without with_noise)
  /// The noise left by a quadric over each neighbourhood's plane instead of the plane: nil for
  /// exact points on a curved surface, about noise() for noisy ones (0 without with_noise).
  double curved_noise(double quantile) const;

 private:
  std::vector<double> distances_, residuals_, curved_;
};

/// For each query point, the index of the nearest of `targets` (PCL kd-tree; ties as PCL
/// breaks them, deterministically); -1 for a non-finite query or when there is no target.
std::vector<std::int32_t> nearest_of(std::span<const Vec3> queries, std::span<const Vec3> targets);

/// Normals as estimate_normals gives them and, from the same neighbourhoods, the curvature
/// (surface variation λ0/(λ0+λ1+λ2)); 1/3, the largest, where there is no normal. Both are
/// resized to the number of points.
/// `sharp`: where a neighbourhood straddles an edge, the normal of the face the point lies on
/// (NormalOptions::sharp), not their average.
void normals_and_curvature(std::span<const Vec3> points, int neighbours, std::vector<Vec3>& normals,
                           std::vector<double>& curvature, bool sharp = false);

/// Candidates from samples with unit normals (index 0 is the seed). Each returns nullopt when
/// the samples are degenerate for the type; the caller verifies the candidate on the samples.
std::optional<Surface> plane_from_samples(std::span<const Vec3> p, std::span<const Vec3> n);
std::optional<Surface> sphere_from_samples(std::span<const Vec3> p, std::span<const Vec3> n,
                                           double max_radius);
std::optional<Surface> cylinder_from_samples(std::span<const Vec3> p, std::span<const Vec3> n,
                                             double max_radius);
std::optional<Surface> cone_from_samples(std::span<const Vec3> p, std::span<const Vec3> n,
                                         double max_radius);
/// Needs at least 6 samples: the axis is the line meeting every normal line.
std::optional<Surface> torus_from_samples(std::span<const Vec3> p, std::span<const Vec3> n,
                                          double max_radius);

/// Parameters of a surface of the type: plane 3, sphere 4, cylinder 5, cone 6, torus 7.
int parameter_count(ShapeType type);

/// Bayesian information criterion of a fit with `k` parameters to `n` points:
/// n·ln(max(rss/n, floor²)) + k·ln(penalty_n), the residual floored at the noise (`penalty_n`:
/// the points of the whole model when the fit is one part of it, else n).
double information_criterion(double rss, double n, double floor, int k, double penalty_n);

/// Centroid and principal axes of the points of `subset`: the eigenvalues of their scatter
/// (the sum of the outer products of their offsets from the centroid) ascending, and the unit
/// eigenvectors as the columns of `axes`. nullopt for fewer than 3 points or a failed solve.
struct PrincipalAxes {
  Vec3 centroid = Vec3::Zero();
  Vec3 values = Vec3::Zero();
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
};
std::optional<PrincipalAxes> principal_axes(std::span<const Vec3> points,
                                            std::span<const std::uint32_t> subset);

/// Least-squares plane through the points (centroid and smallest principal direction).
std::optional<Surface> fit_plane(std::span<const Vec3> points,
                                 std::span<const std::uint32_t> subset);
/// Levenberg-Marquardt on the distances of `subset` from `start` (its type kept); at most
/// `max_points` of the subset are used (an even stride). nullopt when the fit degenerates.
std::optional<Surface> refine_surface(const Surface& start, std::span<const Vec3> points,
                                      std::span<const std::uint32_t> subset,
                                      std::size_t max_points = 4000);

/// `axis` or its opposite, whichever has its first non-zero component of (z, y, x) positive,
/// so that equal lines print equally.
Vec3 canonical_axis(const Vec3& axis);

/// Two unit vectors completing `axis` to a right-handed orthonormal frame.
void orthonormal_basis(const Vec3& axis, Vec3& e1, Vec3& e2);

// ---- Extrusions and revolutions (extrusion.cpp) ----

/// A piece of a profile: the seen part of a straight line in a 2-D profile plane, from `a` to
/// `b` (a wall's trace in an extrusion's section, a cylinder's or cone's generator in (ρ, z)).
struct ProfileSegment {
  kernel::Vec2 a, b;
};

/// Closed rings from profile segments: each ring starts at the longest segment left and
/// follows, from its free end, the nearest free end of another segment, joining the two at
/// the intersection of their lines when that lies within `reach` of both ends (a corner),
/// else by a straight edge between the ends (a side the scan did not see); a ring closes when
/// its own start is the nearest end. Collinear and repeated vertices are removed; rings of
/// fewer than 3 vertices or no area are dropped. Deterministic (ties by segment order).
std::vector<std::vector<kernel::Vec2>> chain_profile(const std::vector<ProfileSegment>& segments,
                                                     double reach);

/// A higher-level primitive proposed from several shapes: its spec, the points it explains,
/// its surface area (for coverage) and the shapes it absorbs (they make no primitive of their
/// own once it is kept).
struct Proposal {
  kernel::PrimitiveSpec spec;
  std::vector<std::uint32_t> members;  ///< ascending
  double area = 0.0;
  std::vector<int> shapes;  ///< ascending
  std::string what;
  /// Stands under the proposal before it (a dome's drum): supported by that one's points, not
  /// by its own coverage (walls a scan from the air does not see).
  bool carried = false;
  /// The house of a roof partition's part, when the partition split its block into houses
  /// (houses.h, PrimitiveOptions::split_houses); −1: none.
  int house = -1;
};

/// Inputs shared by the proposers: the region's points and normals, its shapes, which points
/// an earlier primitive already took, and the options.
struct ProposalInput {
  std::span<const Vec3> points;
  std::span<const Vec3> normals;
  const RansacResult* shapes = nullptr;
  const std::vector<char>* used = nullptr;
  const std::vector<char>* absorbed = nullptr;  ///< per shape: taken by an earlier proposal
  const PrimitiveOptions* options = nullptr;
  const RansacOptions* ransac = nullptr;
  double cell = 0.1;  ///< connectivity size of the region
};

/// The planes not yet absorbed whose inliers lie at least 80% among `members` (ascending
/// indices of in.shapes): those a proposal explaining `members` absorbs.
std::vector<int> planes_explained_by(const ProposalInput& in,
                                     const std::vector<std::uint32_t>& members);

/// Domes seen from the air (domes.cpp): a sphere whose points are the upper cap of a roof — up
/// to its top and all around its vertical axis, described better by the sphere than by a plane
/// (information criterion on the same points) — becomes the sphere cut at the cap's base, then,
/// when the base stands above the terrain, the drum under it: a vertical cylinder of the base's
/// radius from the terrain (`carried`). Needs PrimitiveOptions::ground. Reasons for spheres
/// that make none are appended to `rejected`.
std::vector<Proposal> propose_domes(const ProposalInput& in, std::vector<Rejection>& rejected);

/// Cuts a dome (a sphere proposal, placed at its centre) at height `base`: its one clip, and
/// the area of the cap left.
void cut_dome(Proposal& dome, double base);

/// Where a cut dome (a sphere proposal with its one clip, cut_dome) meets its cut: the height
/// of its base and the radius of its rim there.
struct CapBase {
  double z = 0.0;
  double rim = 0.0;
};
CapBase cap_base(const Proposal& dome);

/// A drum: the vertical cylinder about `axis` (x, y) of `radius` and `height` from z0 up;
/// nullopt when it cannot be placed.
std::optional<kernel::PrimitiveSpec> drum_spec(const kernel::Vec2& axis, double radius, double z0,
                                               double height);

/// Revolutions from coaxial cylinders and cones (two or more) and the planes ⟂ their axis
/// within their radius. Groups whose profile is a plain cylinder or cone stay those.
/// Reasons for groups that make no revolution are appended to `rejected`.
std::vector<Proposal> propose_revolutions(const ProposalInput& in,
                                          std::vector<Rejection>& rejected);

/// One extrusion from the planes parallel to a common direction (walls, roof slopes) with
/// the planes ⟂ it as caps, kept only when it describes the region more briefly than the box
/// around its profile (points unexplained + parameter cost). nullopt and a reason otherwise.
std::optional<Proposal> propose_extrusion(const ProposalInput& in,
                                          std::vector<Rejection>& rejected);

/// The outline of a roof's points seen from the air (roof.cpp): an occupancy grid in the
/// points' principal frame, closed over the gaps between scan lines, holes under something
/// standing on the roof (`above_roof`) or under 4 m² filled, its boundary traced, simplified,
/// its edges snapped to the principal directions and moved onto the outermost points.
struct RoofOutline {
  kernel::Vec2 u{1.0, 0.0}, v{0.0, 1.0};         ///< principal frame: (a, b) = (p·u, p·v)
  double cell = 0.0;                             ///< occupancy grid cell (1.5 × the spacing)
  std::size_t seen_cells = 0;                    ///< cells holding a roof point
  std::vector<kernel::Vec2> profile;             ///< outer ring in (a, b), counter-clockwise
  std::vector<std::vector<kernel::Vec2>> holes;  ///< courtyards in (a, b), clockwise
};
/// nullopt when the points make no outline (too narrow, too large a grid; `why` says so
/// when it is worth a rejection).
/// With `heights` (each flat point's z), an edge under which the scan sees a wall (facade points
/// well below the roof, at one offset) is moved onto that wall instead of the eaves' end.
std::optional<RoofOutline> roof_outline(const ProposalInput& in,
                                        const std::vector<kernel::Vec2>& flat,
                                        const std::function<bool(const kernel::Vec3&)>& above_roof,
                                        std::string& why,
                                        const std::vector<double>* heights = nullptr);
/// The outline as a polygon in world x, y (the points' frame), its rings as the outline's.
geo::FootprintPolygon outline_polygon(const RoofOutline& outline);

/// The outline's footprint in world x, y, its centre, and the terrain under it: the lowest
/// level around it (lowest_ground_under), else the median level near it; NaN without ground.
struct OutlineGround {
  std::vector<kernel::Vec2> footprint;         ///< the outer ring in world x, y
  kernel::Vec2 centre = kernel::Vec2::Zero();  ///< in the outline's (a, b) frame
  kernel::Vec2 world_centre = kernel::Vec2::Zero();
  double ground = NAN;
};
OutlineGround outline_ground(const RoofOutline& outline, const GroundGrid& ground);

/// The vertical extrusion of `outline` (profile and holes about its centre) from `g.ground`
/// up by `height`, x along the outline's u; nullopt when the placement fails.
std::optional<kernel::PrimitiveSpec> outline_extrusion(const RoofOutline& outline,
                                                       const OutlineGround& g, double height);

/// One vertical extrusion from a flat roof seen from the air (roof.cpp): the outline of its
/// points as the footprint (inner rings as courtyards), the roof as the top, the ground grid
/// as the bottom; needs PrimitiveOptions::ground. Kept only when it describes the region more
/// briefly than the box around its footprint (a rectangular roof stays the boxes' work).
std::optional<Proposal> propose_roof_extrusion(const ProposalInput& in,
                                               std::vector<Rejection>& rejected);

/// The lowest terrain level (GroundGrid::mean, or z without means) of the cells whose centre
/// lies within one cell of the polygon `footprint` (a simple ring in x, y, any orientation):
/// the ground under a building, where the scan sees it around the walls, at the foot of a
/// slope, without the lower ground farther off (a quay beside a canal) or the noise's lowest
/// points. NaN when no such cell has ground (pitched.cpp).
double lowest_ground_under(const GroundGrid& ground, const std::vector<kernel::Vec2>& footprint);

/// Buildings under pitched roofs seen from the air (pitched.cpp): a tilted roof plane, or two
/// sharing their horizontal direction and meeting at a ridge, become one extrusion along that
/// direction whose section is the roof's profile down to the terrain (a trapezoid under a
/// shed roof, a pentagon under a gable); needs PrimitiveOptions::ground. Proposals share no
/// point; reasons for planes that make none are appended to `rejected`.
std::vector<Proposal> propose_pitched_roofs(const ProposalInput& in,
                                            std::vector<Rejection>& rejected);

/// Roof parts (roof_parts.cpp): each tilted roof plane left after the pitched roofs becomes
/// the extrusion of its points' outline from the terrain up past the roof, clipped by the
/// half-space under its plane. Needs PrimitiveOptions::ground and roof_parts. Proposals
/// share no point; reasons for planes that make none are appended to `rejected`.
std::vector<Proposal> propose_roof_parts(const ProposalInput& in, std::vector<Rejection>& rejected);

/// The roof partition of a building (roof_partition.cpp): the outline of the region's unused
/// points as grid cells, each labelled with the roof plane that explains its points (or a
/// flat piece at the 70th percentile of points no plane explains), smoothed; each part is
/// the extrusion of its polygon from the building's ground, clipped under its plane. The
/// parts share their boundaries exactly. Needs PrimitiveOptions::ground and roof_partition.
std::vector<Proposal> propose_roof_partition(const ProposalInput& in,
                                             std::vector<Rejection>& rejected);

/// LoD1.2 blocks (blocks.cpp) of the points no kept primitive explains (`explained` false):
/// pieces of one height, each its outline extruded from the terrain to the 70th percentile of
/// its heights. Needs PrimitiveOptions::ground and blocks. Proposals share no point.
std::vector<Proposal> propose_blocks(const ProposalInput& in,
                                     const std::function<bool(const Vec3&)>& explained,
                                     std::vector<Rejection>& rejected);

/// The LoD1.2 block of a building's footprint (PrimitiveOptions::footprint) when its roof
/// partition made nothing: each polygon extruded from the terrain around it to the 70th
/// percentile of the region's points' heights, or to `top` when given (the base of a dome).
std::vector<Proposal> propose_footprint_block(const ProposalInput& in,
                                              std::vector<Rejection>& rejected,
                                              std::optional<double> top = std::nullopt);

/// Per point of the cloud: 1 when it is vegetation (VegetationOptions), from each point's
/// surface variation and whether its pulse returned several times (`several`, per point).
std::vector<char> vegetation_mask(std::span<const Vec3> points, std::span<const double> curvature,
                                  std::span<const char> several, const VegetationOptions& options);

/// The ring without the vertices lying within `deviation` of the chord of their neighbours
/// (walls digitised with several nearly collinear vertices: their near-parallel faces are
/// sections the Booleans cannot compute reliably). Keeps at least 3 vertices.
std::vector<kernel::Vec2> straightened_ring(const std::vector<kernel::Vec2>& ring,
                                            double deviation);

/// Per point: the index of the footprint it lies in (the first, where footprints overlap),
/// else of the footprint whose boundary is nearest within `buffer` (eaves reach past the
/// walls a footprint draws), else -1.
std::vector<int> footprint_of_points(std::span<const Vec3> points,
                                     std::span<const geo::Footprint> footprints, double buffer);

/// Rule 4 of issue #18 (support.cpp): empty when a primitive whose solid has bounding box
/// `box` and whose inliers cover `coverage` of its surface is supported by the points of its
/// region (bounding box `region`, connectivity `cell`), else the reason: a curved primitive
/// covered below PrimitiveOptions::min_curved_coverage, or any primitive reaching beyond the
/// region (below: beyond the terrain under and around the region too) by more than
/// max_overreach of its extent.
std::string unsupported(const kernel::PrimitiveSpec& spec, const kernel::BoundingBox& box,
                        double coverage, const kernel::BoundingBox& region, double cell,
                        const PrimitiveOptions& o);

/// Empty when a cylinder's or cone's points show its curvature, else the reason: its inliers,
/// cut into pieces around its axis where they leave a gap of two connectivity `cell`s, are
/// explained as well by one plane per piece (the information criterion, residuals floored at
/// the noise `sigma`) — the faces of two beams meeting at a node lie on a 45° cone whose axis
/// bisects them, and a narrow strip of a wide cylinder bends by less than the noise.
std::string flat_strips(const kernel::PrimitiveSpec& spec, std::span<const Vec3> points,
                        std::span<const std::uint32_t> members, double sigma, double cell);

/// How far a primitive's points lie from its solid: their RMS distance ("the RMSE of its
/// points to the model") and the share of them within `near` of it.
struct BoundaryFit {
  double rms = 0.0;
  double share_near = 0.0;
};

/// The distances of the points `members` (indices into `points`) to the boundary of `solid`,
/// a primitive's built solid (model_distance.cpp), measured on its tessellation at
/// `chordal_tolerance` (exact for planar faces, within the tolerance for curved ones).
/// nullopt when there is no finite member or the solid cannot be meshed.
std::optional<BoundaryFit> boundary_fit(const kernel::Shape& solid, std::span<const Vec3> points,
                                        std::span<const std::uint32_t> members,
                                        double chordal_tolerance, double near);

/// One ground per building (bases.cpp): vertical extrusions whose footprint boxes touch and
/// whose bases lie within `tolerance` above the lowest of them are lowered onto it (height
/// grown, clips moved: the top stays); returns how many moved. Deterministic.
std::size_t snap_extrusion_bases(std::vector<geo::ScenePrimitive>& primitives, double tolerance);

}  // namespace csgtile::fit::detail
