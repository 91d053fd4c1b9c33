#pragma once
/// \file
/// CityJSONSeq (CityJSON 2.0 text sequence, README "CityJSON"): line 1 a CityJSON object with
/// the transform and the metadata and no objects, then one CityJSONFeature per object, each
/// with its own integer vertices (scale × v + translate gives CRS coordinates).
///
/// Each object is a Building with one lod-2 Solid (a compound of several solids is a
/// GenericCityObject with a MultiSolid, which Building does not admit). A building (an
/// object with a LoD1.2 block, add_building_lods) has its model as lod 2.2, its multi-height
/// block as lod 1.3 and its block as lod 1.2, with the heights and "lod_reached"; when its
/// model is in several solids it is a Building of its blocks alone with "lod22_failure"
/// saying why. Planar faces
/// become one surface each (exterior ring and holes), curved faces the triangles of their
/// tessellation. Every surface gets a semantic surface from its outward normal n and height:
/// GroundSurface when n_z < -0.9 and it lies within the ground tolerance of the object's
/// lowest point, RoofSurface when n_z > 0.2 and it reaches above that, WallSurface otherwise.
/// Vertices are quantised and deduplicated per feature; a shell that is not closed and
/// outward once quantised is written as a MultiSurface with the attribute "closed": false.
///
/// Internal API of the worker (exporters); not installed.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "csgtile/geo/crs.h"
#include "csgtile/worker/errors.h"
#include "export/run_index.h"
#include "export/topology_index.h"

namespace csgtile::worker {

struct CityJsonOptions {
  /// The objects' CRS (metadata.referenceSystem); unset: none, model coordinates.
  std::optional<geo::Crs> crs;
  /// CRS coordinates of the objects' origin: the transform's translate.
  kernel::Vec3 origin = kernel::Vec3::Zero();
  /// Size of one vertex unit in model units (> 0): the transform's scale.
  double scale = 0.001;
  /// Chordal tolerance of curved faces' triangles (model units, > 0).
  double chordal_tolerance = 0.01;
  /// Surfaces within this height of an object's lowest point are at ground level (>= 0).
  double ground_tolerance = 0.01;
};

struct CityJsonStats {
  std::size_t features = 0;
  std::size_t surfaces = 0;
  /// Triangles left out because two of their vertices met after quantisation (leaving them
  /// out keeps the shell closed).
  std::size_t collapsed_triangles = 0;
  /// Surfaces kept with zero area after quantisation (collinear vertices): removing them
  /// would open the shell.
  std::size_t flat_surfaces = 0;
  /// Objects written as MultiSurface: a shell not closed or not outward once quantised.
  std::size_t open_objects = 0;
  std::vector<std::string> warnings;
};

/// The sequence for `objects` (ids unique and non-empty, each a solid or a compound of
/// solids): one line per object after the header, in the given order, each ending in '\n'.
/// Keys in a fixed order, numbers in their shortest round-trip form: the same objects and
/// options give the same bytes. An object whose tessellation fails is written without
/// geometry and named in the warnings. Error: InputInvalid (bad options, empty or duplicate
/// ids, an object that is not a solid).
Result<std::string> cityjson_seq(const std::vector<IndexObject>& objects,
                                 const CityJsonOptions& options = {},
                                 CityJsonStats* stats = nullptr);

/// The CRS URL of metadata.referenceSystem: "https://www.opengis.net/def/crs/EPSG/0/<code>"
/// with the compound code when EPSG has one for the horizontal + vertical pair (28992 + 5709
/// → 7415), else the horizontal code (and a warning that the vertical CRS is not named).
/// Empty for a CRS without an EPSG code.
std::string cityjson_reference_system(const geo::Crs& crs, std::vector<std::string>* warnings);

struct CityJsonReport {
  std::string key = "model.city.jsonl";  ///< relative to the run directory
  std::string sha256;
  std::uint64_t bytes = 0;
  CityJsonStats stats;
};

/// Writes run_dir/<report.key> atomically from the run's objects, in their common CRS (see
/// collect_run_objects) at settings.chordal_tolerance. Errors: Io (cannot write), Internal
/// (objects the exporter refuses).
Failure write_run_cityjson(const RunExportOptions& settings, const RunObjects& run,
                           const std::filesystem::path& run_dir, CityJsonReport& report);

}  // namespace csgtile::worker
