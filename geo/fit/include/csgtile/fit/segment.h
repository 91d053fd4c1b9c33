#pragma once
/// \file
/// Cleaning and segmentation of a point cloud before fitting, each stage a separate call with
/// a plain options struct (statistical outliers, voxel downsampling, normals, ground,
/// Euclidean clusters, region growing), and the whole fit pipeline that chains them with fit.h.
///
/// Points are tile-local coordinates in metres. Outputs are index lists in ascending order or
/// per-point vectors in input order; clusters are ordered by size (largest first), ties by
/// their smallest point index. Every stage is single-threaded and deterministic.

#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "csgtile/fit/fit.h"
#include "csgtile/kernel/interrupt.h"

namespace csgtile::fit {

/// Statistical outlier removal: a point whose mean distance to its `neighbours` nearest
/// points exceeds the cloud's mean by `std_ratio` standard deviations is an outlier.
struct OutlierOptions {
  bool enabled = true;
  int neighbours = 12;
  double std_ratio = 3.0;
  bool operator==(const OutlierOptions&) const = default;
};
/// Indices of the points kept (finite and not outliers), ascending.
std::vector<std::uint32_t> remove_statistical_outliers(std::span<const kernel::Vec3> points,
                                                       const OutlierOptions& options);
/// The same among the points `subset` names (indices into `points`), without a copy of them:
/// the positions in `subset` of the points kept, ascending.
std::vector<std::uint32_t> remove_statistical_outliers(std::span<const kernel::Vec3> points,
                                                       std::span<const std::uint32_t> subset,
                                                       const OutlierOptions& options);

/// Voxel downsampling: one point (the centroid) per occupied cube of `size` metres; 0 keeps
/// every point. Output order: by voxel (x, then y, then z).
struct VoxelOptions {
  double size = 0.0;
  bool operator==(const VoxelOptions&) const = default;
};
std::vector<kernel::Vec3> voxel_downsample(std::span<const kernel::Vec3> points,
                                           const VoxelOptions& options);

/// Normals by principal components of each point's `neighbours` nearest points (PCL
/// NormalEstimation). Unit vectors, unoriented; zero where the neighbourhood is degenerate
/// (collinear or duplicated points).
struct NormalOptions {
  int neighbours = 16;
  /// At sharp edges, the normal of the face the point lies on: of the planes through the point
  /// and two of its ten nearest neighbours, the one most neighbours lie on (within 5 % of the
  /// neighbourhood's radius), refined by their principal components. For exact or nearly exact
  /// clouds (CAD objects), whose small features a normal averaged over an edge hides.
  bool sharp = false;
  bool operator==(const NormalOptions&) const = default;
};
std::vector<kernel::Vec3> estimate_normals(std::span<const kernel::Vec3> points,
                                           const NormalOptions& options);

/// Ground separation: LAS class 2 when the cloud has classes, some point carries it and some
/// a class above 2, else a progressive morphological filter: the grid (`cell`) of the lowest
/// points opened by squares growing from 3 cells to `window` (wider than the widest
/// building); at each step a point farther above the opened surface than `height` (the first
/// step), then `height` + `slope` × the window's growth, at most `max_height`, is not ground.
/// A cloud classified for its ground alone (classes 0-2) gets its class 2 and the filter's
/// ground among all its points: such a classification may have left ground unclassified.
struct GroundOptions {
  bool enabled = true;
  bool use_classification = true;
  double cell = 1.0;
  double window = 150.0;
  double height = 0.3;
  double slope = 0.2;
  double max_height = 3.0;
  bool operator==(const GroundOptions&) const = default;
};
/// Vegetation on unclassified inputs (issue #18 item 1): a laser pulse goes through a tree's
/// crown and returns several times, and a tree's points scatter their normals, where a roof
/// returns once and its points lie on planes. A point is vegetation when more than `share` of
/// the points within `radius` (0: four times the cloud's point spacing, so that the rule does
/// not depend on the unit; itself included) are of a pulse with several returns (when the
/// input says) or rough — their surface variation (the smallest eigenvalue of the
/// neighbourhood's covariance over the sum, from the `normals` neighbourhoods) above
/// `curvature` — so a roof's edges, lines of such points between smooth single returns, stay.
/// Vegetation is never fitted. Inputs with a classification use it instead (ClassOptions).
struct VegetationOptions {
  bool enabled = true;
  double curvature = 0.05;
  double radius = 0.0;
  double share = 0.65;
  bool operator==(const VegetationOptions&) const = default;
};

/// Per point: 1 ground, 0 not. `classes` may be empty (no classification).
std::vector<char> ground_mask(std::span<const kernel::Vec3> points,
                              std::span<const std::uint8_t> classes, const GroundOptions& options);

/// Euclidean clustering: points closer than `tolerance` (0: 1.5 × the 90th percentile of the
/// distance to the 16th neighbour) join;
/// clusters below `min_points` are dropped.
struct ClusterOptions {
  double tolerance = 0.0;
  long long min_points = 40;
  bool operator==(const ClusterOptions&) const = default;
};
/// `tolerance_used` (optional) receives the distance used.
std::vector<std::vector<std::uint32_t>> euclidean_clusters(std::span<const kernel::Vec3> points,
                                                           const ClusterOptions& options,
                                                           double* tolerance_used = nullptr);

/// Region growing on normals and curvature (PCL RegionGrowing), splitting a cluster into
/// smooth pieces (two walls meeting at an edge become two regions; a cylinder stays one).
/// From the seed of lowest curvature, a neighbour (one of the `neighbours` nearest) joins
/// when its normal is within `smoothness_deg` of the current point's, and keeps growing when
/// its curvature (surface variation λ0/(λ0+λ1+λ2) of its neighbourhood, at most 1/3) is
/// below `curvature` (1.0: every point keeps growing). Regions below `min_points` are dropped.
struct RegionGrowingOptions {
  bool enabled = false;  ///< off: the pipeline fits each Euclidean cluster whole
  int neighbours = 16;
  double smoothness_deg = 10.0;
  double curvature = 1.0;
  long long min_points = 40;
  bool operator==(const RegionGrowingOptions&) const = default;
};
/// Smooth regions of `points` (indices, ascending within a region; regions by size, largest
/// first, ties by smallest index). `normals` are per point (zero: none, e.g. from
/// estimate_normals); `curvature` per point, or empty to compute it from the `neighbours`
/// nearest points. Points without a finite non-zero normal, and those of regions below
/// `min_points`, are in no region. Disabled: one region of every finite point. Mismatched
/// sizes, empty or degenerate (e.g. collinear) input: no region.
std::vector<std::vector<std::uint32_t>> region_growing(std::span<const kernel::Vec3> points,
                                                       std::span<const kernel::Vec3> normals,
                                                       const RegionGrowingOptions& options,
                                                       std::span<const double> curvature = {});

/// Which classified points are fitted. An input that carries a classification (LAS, some
/// point of a class above 1) and some point of a `keep` class fits only the non-ground points
/// of those classes (default 6, buildings: trees, cars and bridges do not compete for
/// primitives; add 26 for AHN's civil structures); one classified without them fits every
/// non-ground point except the `drop` classes (vegetation 3-5, noise 7 and 18, water 9).
/// Ground (class 2, GroundOptions) is always taken for the terrain. Unclassified inputs (no
/// classes, or every point class 0 or 1) keep all.
struct ClassOptions {
  std::vector<std::uint8_t> keep{6};
  std::vector<std::uint8_t> drop{3, 4, 5, 7, 9, 18};
  bool operator==(const ClassOptions&) const = default;
};

/// Every option of the fit pipeline.
struct FitPipelineOptions {
  ClassOptions classes;
  OutlierOptions outliers;
  VoxelOptions voxel;
  NormalOptions normals;
  GroundOptions ground;
  VegetationOptions vegetation;
  ClusterOptions clusters;
  /// When enabled, each Euclidean cluster is split into grown regions; its points in no
  /// grown region stay together as one more region of that cluster (after its grown ones),
  /// so that the RANSAC still sees them (edges, noisy normals) instead of losing them.
  /// Normals and curvature come from the `normals` neighbourhoods.
  RegionGrowingOptions regions;
  RansacOptions ransac;
  PrimitiveOptions primitives;
  bool keep_detections = false;  ///< diagnostics: fill FitOutput::detections
  bool keep_segments = false;    ///< fill FitOutput::segments and ::point_segment
  /// Not a setting: looked at between stages and regions; once it fires, the fit returns
  /// Cancelled (a worker shutting down, a job's time limit).
  kernel::Interrupt interrupt{};
  bool keep_structure_points = {};  ///< fill FitOutput::structure_points
  /// Regions detected and fitted at once (TBB): 0 all cores, 1 one. Not a setting of the
  /// result: the output is the same for every value (regions are gathered in order).
  int threads = {};
  bool operator==(const FitPipelineOptions&) const = default;
};

/// One region (Euclidean cluster, or a grown region of one) as the RANSAC saw it.
struct FitRegion {
  long long points = 0;
  double spacing = 0.0;          ///< estimated point spacing
  double cluster_epsilon = 0.0;  ///< connectivity size used
  double epsilon = 0.0;          ///< inlier distance used (the option, or derived)
  long long min_points = 0;      ///< smallest shape used
  int shapes = 0;                ///< surfaces detected
  int primitives = 0;            ///< primitives kept
  std::uint64_t candidates = 0;
  std::string building;  ///< its footprint's id, "" for a cluster of points
};

/// One region as the RANSAC saw it: its points and normals (region order) and the shapes it
/// found, with each point's shape (diagnostics, e.g. tests/bench/beam_causes.py).
struct RegionDetection {
  std::vector<kernel::Vec3> points;
  std::vector<kernel::Vec3> normals;
  RansacResult shapes;
};

/// One detected surface of the segmentation: the RANSAC's shapes of every region, numbered
/// region by region in extraction order.
struct Segment {
  int region = 0;
  Surface surface;
  long long inliers = 0;  ///< points of the fitted cloud on it
  double rms = 0.0;       ///< of their distances to the surface
};

/// What the pipeline found and how long each stage took.
struct FitOutput {
  std::vector<geo::ScenePrimitive> primitives;  ///< ids "r<region>-<n>"
  std::vector<Rejection> rejected;
  std::array<long long, kernel::kPrimitiveTypeCount> per_type{};
  long long input_points = 0;
  long long ground_points = 0;
  long long other_class_points = 0;  ///< non-ground points of classes not kept
  long long outlier_points = 0;
  long long vegetation_points = 0;     ///< fitted-cloud points taken for vegetation (unclassified)
  long long fitted_points = 0;         ///< points given to the RANSAC (after downsampling)
  long long assigned_points = 0;       ///< of those, explained by an output primitive
  long long unassigned_points = 0;     ///< fitted_points - assigned_points
  long long small_cluster_points = 0;  ///< in clusters below min_points
  int regions = 0;
  int footprint_regions = 0;       ///< the first regions: one per footprint with points
  long long footprint_points = 0;  ///< fitted points in those regions
  /// Ids of the footprints with too few points for a building (each also a rejection).
  std::vector<std::string> footprints_without_building;
  std::vector<FitRegion> region_stats;  ///< per region, in region order
  double cluster_tolerance = 0.0;       ///< Euclidean clustering distance used
  std::uint64_t candidates = 0;
  std::vector<std::pair<std::string, double>> seconds;  ///< per stage, in order
  std::vector<RegionDetection> detections;  ///< per region, when keep_detections was set
  /// When keep_segments was set: every detected surface, and per input point (input order)
  /// the index of its surface, -1 for none (ground, other classes, outliers, small clusters,
  /// unassigned). With voxel downsampling an input point takes the surface of the nearest
  /// downsampled point.
  std::vector<Segment> segments;
  std::vector<std::int32_t> point_segment;
  /// When keep_structure_points was set: the points the model is to explain — the fitted cloud
  /// (above the ground, of a kept class, not outliers; downsampled when `voxel` is set)
  /// without the points taken for vegetation, in the cloud's order.
  std::vector<kernel::Vec3> structure_points = {};
  /// With a TileShare: the neighbours' points given, and the fitted points left to the
  /// neighbours' fits (in buildings they make, or own points of a building kept `none`).
  long long neighbour_points = 0;
  long long points_left_to_neighbours = 0;
  int clusters_left_to_neighbours = 0;
  int clusters_split_with_neighbours = 0;  ///< kept `own_points`: larger than the halo
};

/// Which of a building's points a tile's fit keeps, in a run of several tiles.
enum class ShareKind {
  whole,       ///< all of them, its neighbours' too: the building is this fit's
  own_points,  ///< this tile's own: the building is larger than the halo, each tile fits its part
  none,        ///< none: a neighbouring tile's fit makes it
};

/// A tile fitted with its neighbours' points (each tile of a run read with the points of the
/// tiles around it within city.halo), so that a building across a tile edge is fitted once,
/// whole, by one tile's fit: which points are the neighbours' and which buildings are this
/// fit's. Points in no kept building are never fitted twice.
struct TileShare {
  /// Per input point: 1 for a neighbour's. They serve the terrain and the buildings kept
  /// `whole`; they are never among the structure points (each tile publishes its own).
  std::span<const std::uint8_t> foreign;
  /// Per footprint (the `footprints` given): how much of its building this fit makes.
  std::span<const ShareKind> footprints;
  /// For each cluster of the points in no footprint, from its points' xy box and the
  /// clustering distance: how much of it this fit keeps. Null: every cluster whole.
  std::function<ShareKind(const kernel::Vec2& lo, const kernel::Vec2& hi, double tolerance)>
      clusters;
};

/// Ground → outliers → voxels → normals → clusters (→ grown regions) → per region: RANSAC,
/// primitives.
/// `classes` may be empty; `returns` (each point's pulse's number of returns, 0 unknown) may
/// be empty. With `footprints` (in the points' frame), each footprint's points
/// (inside it, or within kFootprintBuffer of its boundary: eaves) are one region, fitted as
/// one building standing exactly on it (PrimitiveOptions::footprint), its primitives carrying
/// its id (ScenePrimitive::building); only the other points are clustered. A footprint with
/// too few points is a rejection naming it. Errors: InvalidArgument for bad options (naming
/// the option), Cancelled (options.interrupt fired). With `share`, the points and buildings
/// of a tile among neighbours (TileShare); its spans sized as the points and the footprints.
kernel::Result<FitOutput> fit_point_cloud(std::span<const kernel::Vec3> points,
                                          std::span<const std::uint8_t> classes,
                                          const FitPipelineOptions& options,
                                          std::span<const geo::Footprint> footprints = {},
                                          std::span<const std::uint8_t> returns = {},
                                          const TileShare* share = nullptr);

/// How far past a footprint's boundary its building's points reach (eaves), metres.
inline constexpr double kFootprintBuffer = 1.0;

}  // namespace csgtile::fit
