#pragma once
/// \file
/// A city run as a job graph (DESIGN.md §1): `fit` per LIDAR tile → `assemble` per output
/// cell (after every fit has finished) → `index` per run (after every assemble). Internal to
/// the worker; the job table (jobs/job_table.h) runs these.
///
/// Cells are squares of `city.cell_size` aligned to multiples of it in the tiles' CRS
/// (origin 0, 0), named "c<column>_r<row>". A primitive's anchor cell holds the minimum
/// (x, y) corner of its bounding box in CRS coordinates, computed by one function from the
/// fit's published bytes by every job; an object belongs to the least (column, then row) of
/// its primitives' anchor cells, which the fits named, so it has an assemble job. A cell is
/// assembled from the primitives whose boxes meet the cell grown by `city.halo`, in a frame
/// whose origin is the cell's minimum corner (coordinates stay small); an object reaching
/// past the halo is reported in the cell's problems.
///
/// Job graph without a coordinator: after each fit or assemble completes, and whenever a
/// worker finds the run with no unfinished job, `advance_city_run` enqueues the next stage
/// once its predecessors are all done or dead. Enqueueing is idempotent (unique keys), so
/// concurrent or repeated calls are harmless and a crash between a completion and the
/// enqueue is repaired by the next worker that looks.
///
/// Outputs (under <run.output>/runs/<name>/), all deterministic:
///   fits/<sha256>.json                 fitted primitives of a tile (scene format, tile frame)
///   objects/<sha256>.csgt              one native model per object (CSG tree, face history)
///   cells/<cell>/model.csgt            the cell's objects as one native model
///   cells/<cell>/index.gpkg            topology index of the cell
///   cells/<cell>/model.city.jsonl      CityJSONSeq of the cell
///   cells/<cell>/tiles/{tileset.json,model.glb}   3D Tiles of the cell
///   cells/<cell>/manifest.json         every file of the cell with SHA-256 and size, written last
///   index.gpkg, tiles/tileset.json (root, cells as external tilesets), manifest.json (last)

#include <filesystem>
#include <stop_token>
#include <string>

#include "csgtile/config/config.h"
#include "csgtile/worker/job_support.h"
#include "csgtile/worker/log.h"
#include "csgtile/worker/queue.h"
#include "job_context.h"

namespace csgtile::worker::city {

/// True for inputs read as LIDAR tiles (LAS, PLY, PCD, XYZ/TXT by extension, ignoring a
/// URL's query and fragment) and for local directories (each stands for the tile files
/// directly inside it, in name order); scene JSON inputs are build jobs.
bool is_tile_input(const std::string& input);

/// Queue keys: "fit:<run>:<input>", "assemble:<run>:<cell>", "index:<run>:run".
std::string fit_key(const std::string& run, const std::string& input);
std::string assemble_key(const std::string& run, const std::string& cell);
std::string index_key(const std::string& run);

/// Enqueues one fit job per tile of the run — a distinct tile input, a cell of a COPC input,
/// a block of cells of a LAS/LAZ input over city.split_points; `added` counts new ones. The
/// first enqueue fixes the run's tile list in <run dir>/tiles.json (a directory input is
/// expanded then), so tiles added later do not change a run under way. Errors: as the
/// readers of the inputs' headers; Internal for a tiles.json it cannot read.
Failure enqueue_fits(const config::Config& config, JobQueue& queue, std::size_t& added);

/// Enqueues the run's assemble jobs once every fit is done or dead, and its index job once
/// every assemble is. `enqueued` counts the jobs added by this call.
Failure advance_city_run(const config::Config& config, JobQueue& queue, const Logger& log,
                         std::size_t& enqueued);

/// Progress of a city run through its graph, from the queue's done and dead jobs.
struct CityProgress {
  std::size_t tiles = 0, fits_done = 0, fits_dead = 0;
  std::size_t cells = 0;  ///< known once every fit has finished (0 before)
  std::size_t cells_done = 0, cells_dead = 0;
  bool indexed = false, index_dead = false;
};
Failure city_progress(const config::Config& config, JobQueue& queue, CityProgress& progress);

/// The runners of the graph's jobs (jobs/job_table.h: kinds "fit", "assemble", "index"). On
/// success `result` is the job's deterministic JSON record. The index job reads the run's
/// other records from the context's queue. Once the context's stop token is asked (a worker
/// shutting down), a fit or an assembly under way returns Cancelled at its next step.
Failure run_fit(const Job& job, const jobs::JobContext& context, std::string& result,
                StageTimings* timings);
Failure run_assemble(const Job& job, const jobs::JobContext& context, std::string& result,
                     StageTimings* timings);
Failure run_index(const Job& job, const jobs::JobContext& context, std::string& result,
                  StageTimings* timings);

}  // namespace csgtile::worker::city
