#pragma once
/// \file
/// One LIDAR tile → fitted primitives: the fit options' JSON form (the file `csgtile fit
/// --config` and `city.fit_config` name) and the read → segment → fit step shared by
/// `csgtile fit` and the run's fit jobs. Internal to the worker.

#include <filesystem>
#include <string>
#include <string_view>

#include "csgtile/geo/scene.h"
#include "csgtile/fit/segment.h"
#include "csgtile/worker/errors.h"

namespace csgtile::worker::city {

/// Reads fit options from JSON text: an object whose sections mirror fit::FitPipelineOptions
/// (outliers, voxel, normals, ground, clusters, ransac, primitives); every key optional,
/// unknown keys and wrong types are errors naming their path, prefixed by `file`.
bool parse_fit_options(std::string_view text, const std::string& file,
                       fit::FitPipelineOptions& options, std::string& error);
/// Reads `file` into `text` and parses it as parse_fit_options does.
bool read_fit_options(const std::string& file, fit::FitPipelineOptions& options, std::string& text,
                      std::string& error);

struct FittedTile {
  /// The primitives in the tile-local frame: origin = the LAS offset (the floor of the
  /// smallest x and y for other formats), CRS from the file or the override; the seed.
  geo::Scene scene;
  fit::FitOutput output;  ///< counts, rejections, stage seconds
  double read_seconds = 0.0;
};

/// Reads every point of a LAS/PLY/PCD/XYZ file and fits primitives to them. `crs_override`
/// is used when the file names no CRS ("" = none). Errors: as the readers (Io, InputInvalid,
/// Unsupported), ConfigInvalid (bad options or override).
Failure fit_tile(const std::filesystem::path& path, const std::string& name,
                 const fit::FitPipelineOptions& options, const std::string& crs_override,
                 FittedTile& out);

}  // namespace csgtile::worker::city
