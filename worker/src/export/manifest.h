#pragma once
// Run manifests: the one writer of what a run (of scenes or of a city) publishes. Every
// manifest starts with the same head, names its exports with the same entries, and ends with
// its jobs, dead jobs and timings; it is written last, so a reader who finds it finds the rest.

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "csgtile/worker/errors.h"
#include "csgtile/worker/queue.h"
#include "export/cityjson_seq.h"
#include "export/run_index.h"
#include "export/tileset.h"
#include "job_records.h"

namespace csgtile::worker {

/// What identifies a publication besides its kind and csgtile's version; the job layer builds
/// it from the config (jobs/export_settings.h).
struct ManifestIdentity {
  std::string run;            ///< run.name
  std::string config_sha256;  ///< output_config_sha256 (job_support.h)
  std::uint64_t seed = 0;     ///< run.seed
};

/// What identifies a publication: {"run", "kind" ("scenes", "city" or "cell"),
/// "csgtile_version", "config_sha256", "seed"}.
nlohmann::ordered_json manifest_head(const ManifestIdentity& identity, std::string_view kind);

/// An export as manifests list it: its key, SHA-256 and size, then its writer's figures.
nlohmann::ordered_json index_entry(const RunIndexReport& index);
nlohmann::ordered_json cityjson_entry(const CityJsonReport& cityjson);
/// The glTF content and its tileset; null when none was written (`tiles_skipped` says why).
nlohmann::ordered_json tiles_entry(const TilesReport& tiles);

/// Ends `manifest` with "jobs" (the records' results), "dead" and "timings": "timings.json",
/// written first beside it (timings differ from run to run, so the manifest does not hash
/// them), then writes run_dir/manifest.json atomically; `text` receives its bytes. Error: Io.
Failure write_run_manifest(const std::filesystem::path& run_dir, const std::string& run,
                           nlohmann::ordered_json manifest, const JobRecords& records,
                           const std::vector<DeadJob>& dead, std::string& text);

}  // namespace csgtile::worker
