#pragma once
// The run's topology index: `csgtile run` writes <run dir>/index.gpkg from its done build
// jobs once the queue is drained (README "Topology index").

#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "csgtile/config/config.h"
#include "csgtile/geo/scene.h"
#include "csgtile/worker/errors.h"
#include "export/topology_index.h"

namespace csgtile::worker {

struct RunIndexReport {
  std::string key = "index.gpkg";  ///< relative to the run directory
  std::string sha256;
  std::uint64_t bytes = 0;
  int srs_id = -1;
  double seconds = 0.0;  ///< wall time of building and writing (for logs, not the manifest)
  IndexStats stats;
};

/// Objects of one build job's model: each solid of map_child_shapes(model, Solid) becomes
/// object "<input index>-<solid index>" with the CSG tree of the model. A model without history
/// that is a set of the scene's primitives (one solid per primitive, in order) gets each
/// primitive's leaf as its history. Primitives are the tree's Primitive leaves — for a model
/// with several solids, those whose faces the solid keeps — with the scene's fit quality
/// (matched by id). `scene` may be null (no quality, ids from the CSG labels).
std::vector<IndexObject> job_index_objects(std::size_t input_index, const kernel::CsgModel& model,
                                           const geo::Scene* scene);

/// Writes run_dir/index.gpkg from the done jobs among `results` (queue key → job record),
/// in run.inputs order: models read back from their published keys, scenes re-read for fit
/// quality and frames. When every job's scene has the same CRS ("crs"/"origin" keys), the
/// objects layer is in that CRS (EPSG code as srs_id) with all objects placed relative to the
/// first job's origin; otherwise it uses the undefined Cartesian SRS and model coordinates.
/// Errors: Io (cannot read a model or write the index), InputInvalid (a model that does not
/// parse), Internal (a malformed job record).
Failure write_run_index(const config::Config& config,
                        const std::vector<std::pair<std::string, std::string>>& results,
                        const std::filesystem::path& run_dir, RunIndexReport& report);

}  // namespace csgtile::worker
