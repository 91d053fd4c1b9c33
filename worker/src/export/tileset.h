#pragma once
/// \file
/// 3D Tiles 1.1 (README "3D Tiles"): `tileset.json` with one tile whose content is the run's
/// objects as a glTF binary (tile_content.h), placed on the globe.
///
/// Placement. The tile's content is in the east-north-up frame tangent to the WGS 84
/// ellipsoid at the run's origin (geo::Georeferencer, the exact path from the CRS); the
/// tile's `transform` is that frame → WGS 84 ECEF (column-major 4×4: the east, north and up
/// axes, then the ECEF of the origin). The bounding volume is a `region` (EPSG:4979: west,
/// south, east, north in radians, minimum and maximum ellipsoidal height in metres) that
/// holds the content's ENU box, which 3D Tiles does not transform.
///
/// Internal API of the worker (exporters); not installed.

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "csgtile/geo/georeference.h"
#include "csgtile/kernel/result.h"
#include "csgtile/worker/errors.h"
#include "export/run_index.h"

namespace csgtile::worker {

/// west, south, east, north (radians; west > east across the antimeridian), minimum and
/// maximum height (metres above the WGS 84 ellipsoid).
using Region = std::array<double, 6>;

/// The tile frame → ECEF as 3D Tiles' column-major `transform`.
std::array<double, 16> tile_transform(const geo::TileFrame& frame);

/// A region holding every point of the ENU box [low, high] of `frame`'s Georeferencer: the
/// box sampled on a 3×3×3 grid and at its lowest point nearest the origin's vertical, widened
/// by a margin (1 cm plus the curvature between samples) so that no point of the box falls
/// outside. Preconditions: low <= high, finite.
Region enu_box_region(const geo::Georeferencer& frame, const kernel::Vec3& low,
                      const kernel::Vec3& high);

struct TilesetOptions {
  std::string content_uri = "model.glb";
  /// The tileset's geometricError (metres): the error of not rendering it at all.
  double geometric_error = 0.0;
  /// The tile's geometricError (metres): its content's distance from the exact geometry.
  double tile_geometric_error = 0.0;
};

/// tileset.json text (asset version "1.1", one root tile with refine "ADD", the content, the
/// region and the transform), keys in a fixed order and numbers in their shortest
/// round-trip form, ending in '\n'.
std::string tileset_json(const Region& region, const std::array<double, 16>& transform,
                         const TilesetOptions& options);

struct TilesReport {
  bool written = false;
  std::string skipped;                     ///< why no tiles were written (when !written)
  std::string key = "tiles/tileset.json";  ///< relative to the run directory
  std::string content = "tiles/model.glb";
  std::string sha256, content_sha256;
  std::uint64_t bytes = 0, content_bytes = 0;
  std::size_t objects = 0, triangles = 0;
  std::vector<std::string> warnings;  ///< objects left out of the content
};

/// Writes run_dir/tiles/model.glb, then run_dir/tiles/tileset.json, atomically, from the
/// run's objects at settings.chordal_tolerance. Without a common CRS (or with one that cannot
/// be placed on WGS 84, or without an object to draw) nothing is written, stale tiles from
/// an earlier run are removed and report.skipped says why: 3D Tiles need a georeference.
/// Errors: Io (cannot write), Internal (objects the exporter refuses).
Failure write_run_tiles(const RunExportOptions& settings, const RunObjects& run,
                        const std::filesystem::path& run_dir, TilesReport& report);

}  // namespace csgtile::worker
