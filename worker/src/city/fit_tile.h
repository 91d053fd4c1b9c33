#pragma once
/// \file
/// One LIDAR tile → fitted primitives: the fit options from the config (its `fit:` section,
/// run.seed, kernel.linear_tolerance) and the read → segment → fit step shared by `csgtile
/// fit` and the run's fit jobs. Internal to the worker.

#include <array>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "city/tile_share.h"
#include "csgtile/config/config.h"
#include "csgtile/fit/segment.h"
#include "csgtile/geo/byte_source.h"
#include "csgtile/geo/footprints.h"
#include "csgtile/geo/point.h"
#include "csgtile/geo/scene.h"
#include "csgtile/worker/errors.h"

namespace csgtile::worker::city {

/// The fit's options: `config.fit` key for key, the RANSAC seeded with `run.seed` (the one
/// seed rule: `csgtile fit --seed` replaces run.seed), every solid the fit builds at
/// `kernel.linear_tolerance`. The default config gives fit::FitPipelineOptions{} (a test).
fit::FitPipelineOptions fit_options(const config::Config& config);

struct FittedTile {
  /// The primitives in the tile-local frame: origin = the LAS offset when the points lie
  /// within 10 km of it, else (and for other formats) the floor of the smallest x and y; CRS
  /// from the file or the override; the seed.
  geo::Scene scene;
  fit::FitOutput output;           ///< counts, rejections, stage seconds
  std::array<double, 3> origin{};  ///< of the tile-local frame, whether the scene has one or not
  double read_seconds = 0.0;
  /// With footprints: those read for the tile (meeting its points' extent), and the features
  /// that gave none, with their reasons.
  long long footprints_read = 0;
  std::vector<std::string> footprints_skipped;
  /// With neighbours (TileNeighbours): the tiles read, and those not read with their reasons;
  /// footprints whose building a neighbour makes, and those larger than the halo, fitted in
  /// parts (this tile's: the footprint cut to its extent).
  long long neighbours_read = 0;
  std::vector<std::string> neighbours_skipped = {};
  long long footprints_left_to_neighbours = 0;
  std::vector<std::string> footprints_split = {};
};

/// The tiles around a tile of a run of several, whose points its fit reads within the halo
/// (tile_share.h): where they are, and each neighbour's local file (the job resolves URLs),
/// in the order of `where.neighbours`; an empty path for one not to be read (it does not meet
/// the read region, or could not be fetched: named in `skipped`, then in
/// FittedTile::neighbours_skipped).
struct TileNeighbours {
  TileNeighbourhood where;
  std::vector<std::filesystem::path> paths;
  std::vector<std::string> skipped;  ///< "input: reason" of those the job could not fetch
  /// The tile's own read holds its neighbours' points too (a cell of a COPC input or a block
  /// of a large tile, read with its halo): each point is its owner's (owns_point).
  bool own_read_is_shared = false;
};

/// A fit record's account of the neighbours (fit jobs): tiles read and skipped, their points,
/// the points, clusters and footprints left to them or split with them.
nlohmann::ordered_json neighbours_record(const FittedTile& tile);

/// The footprints' part of a fit's record (fit jobs, `csgtile fit --json`): the source, the
/// footprints read, the buildings made and their points, the ids without a building and the
/// features skipped with their reasons.
nlohmann::ordered_json footprints_record(const geo::FootprintSource& source,
                                         const FittedTile& tile);

/// The fit's point counts as `csgtile fit --json` and a fit job's record give them: points,
/// ground_points, other_class_points, outlier_points, vegetation_points, fitted_points,
/// small_cluster_points, assigned_points, unassigned_points, regions.
nlohmann::ordered_json fit_counts_json(const fit::FitOutput& output);

/// Where a tile's points come from: a local file, or a random-access source (a URL read by
/// range requests); with a region, only the points inside it (a COPC file reads only the
/// octree nodes that meet it).
struct TileSource {
  std::filesystem::path path;               ///< used when `remote` is null
  std::unique_ptr<geo::ByteSource> remote;  ///< LAS/LAZ/COPC over ranges
  std::optional<geo::Bounds3> region;
};

/// Reads every point of a LAS/PLY/PCD/XYZ file (or of its region) and fits primitives to
/// them. `crs_override` is used when the file names no CRS ("" = none). With `footprints`
/// (source non-empty), the footprints meeting the tile's points (cut to their extent), reprojected
/// to its CRS (as stored when the tile has none), make one building each (fit_point_cloud). Errors:
/// as the readers (Io, InputInvalid, Unsupported), ConfigInvalid (bad options or override),
/// InputInvalid / Io (footprints that cannot be read, naming them).
/// With `around`, the neighbours' points in this tile's read region are read too, and each
/// building across its edges is fitted by one tile (fit::TileShare); footprints are read over
/// the read region, uncut.
Failure fit_tile(TileSource source, const std::string& name, const fit::FitPipelineOptions& options,
                 const std::string& crs_override, FittedTile& out,
                 const geo::FootprintSource& footprints = {},
                 const TileNeighbours* around = nullptr);
inline Failure fit_tile(const std::filesystem::path& path, const std::string& name,
                        const fit::FitPipelineOptions& options, const std::string& crs_override,
                        FittedTile& out) {
  TileSource source;
  source.path = path;
  return fit_tile(std::move(source), name, options, crs_override, out);
}

}  // namespace csgtile::worker::city
