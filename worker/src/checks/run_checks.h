#pragma once
// Checks of a loaded config against the world, made before any job is: what the schema cannot
// know (whether run.crs names a CRS, whether a local input exists and holds something to
// read). Each finding is a config problem with its key path and line, so `validate-config`
// lists it and `run` / `enqueue` refuse the config (exit 78) instead of queueing jobs that
// can only fail.

#include <vector>

#include "csgtile/config/config.h"

namespace csgtile::worker::detail {

/// What to check: the CRS always; the inputs for the commands that make jobs.
enum class RunChecks { CrsOnly, CrsAndInputs };

/// Problems of `loaded` (which must have loaded): run.crs that is not a CRS; a local input
/// path that does not exist; a local directory (a city of tiles) that holds no LIDAR tile
/// (.las .laz .ply .pcd .xyz .txt); city.footprints that GDAL cannot open, without the named
/// layer or attribute, or that do not reproject to run.crs. URLs, file:// too, are checked
/// when a job fetches them.
std::vector<config::Problem> check_run_config(const config::LoadResult& loaded, RunChecks what);

}  // namespace csgtile::worker::detail
