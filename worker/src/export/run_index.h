#pragma once
// The run's topology index: `csgtile run` writes <run dir>/index.gpkg from its done build
// jobs once the queue is drained (README "Topology index").

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "csgtile/geo/crs.h"
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

/// The PrimitiveInfo of a model's Primitive node `node` (`leaf`), with its fit quality.
PrimitiveInfo primitive_info(int node, const kernel::CsgNode& leaf,
                             const std::optional<geo::FitQuality>& quality);
/// One PrimitiveInfo per Primitive node of `model`, in node order; `quality` gives a leaf's
/// fit quality by its label.
std::vector<PrimitiveInfo> model_primitives(
    const kernel::CsgModel& model,
    const std::function<std::optional<geo::FitQuality>(const std::string&)>& quality);

/// The objects of a run's done jobs in one frame, shared by the run's exports.
struct RunObjects {
  std::vector<IndexObject> objects;  ///< run.inputs order, then job_index_objects order
  /// The scenes' common CRS (an EPSG code); unset when the jobs do not share one, and then
  /// each object is in its scene's local coordinates.
  std::optional<geo::Crs> crs;
  /// CRS coordinates of the objects' origin: p_crs = origin + p (zero without a CRS).
  kernel::Vec3 origin = kernel::Vec3::Zero();
  std::vector<std::string> warnings;  ///< e.g. inputs that do not share one CRS
  /// The relations of objects of the same cell as the cells classified them (indices into
  /// `objects`, a < b), when every cell gave them: the index classifies only pairs across
  /// cells (IndexOptions::cell_relations).
  std::optional<std::vector<ObjectRelation>> cell_relations = {};
  /// The cells' own indexes, holding `objects` in order (merge_topology_indexes), and their
  /// warnings: when given, the run's index is merged from them instead of built again.
  std::vector<IndexPart> cell_indexes = {};
  std::vector<std::string> cell_index_warnings = {};
};

/// What the run's exporters (index, CityJSON, 3D Tiles) take from the configuration; the
/// job layer builds it (jobs/export_settings.h), the exporters never see the config.
struct RunExportOptions {
  double chordal_tolerance = 0.0;  ///< kernel.chordal_tolerance: tessellation, LoD rings
  double linear_tolerance = 0.0;   ///< kernel.linear_tolerance: LoD footprints and checks
  int threads = 0;                 ///< run.threads: the index's relations and rows; 0 = all cores
};

/// The jobs of a scene run whose objects are collected: `inputs` in run order (one build job
/// each, keyed "build:<run>:<input>").
struct RunJobs {
  std::string run;
  std::vector<std::string> inputs;
};

/// Collects the done jobs among `results` (queue key → job record), in run.inputs order:
/// models read back from their published keys, scenes re-read for fit quality and frames.
/// When every job's scene has the same CRS ("crs"/"origin" keys) and it has an EPSG code, all
/// objects are placed relative to the first job's origin, which becomes `origin`; otherwise
/// they stay in model coordinates. Errors: Io (cannot read a model), InputInvalid (a model
/// that does not parse), Internal (a malformed job record).
Failure collect_run_objects(const RunJobs& jobs, const RunExportOptions& options,
                            const std::vector<std::pair<std::string, std::string>>& results,
                            const std::filesystem::path& run_dir, RunObjects& out);

/// Writes run_dir/index.gpkg from the run's objects: the objects layer is in their common CRS
/// (EPSG code as srs_id) when they have one, else in the undefined Cartesian SRS.
/// Errors: Io (cannot write the index), as write_topology_index otherwise.
Failure write_run_index(const RunExportOptions& options, const RunObjects& run,
                        const std::filesystem::path& run_dir, RunIndexReport& report);

}  // namespace csgtile::worker
