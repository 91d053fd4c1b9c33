// Run manifests (manifest.h).

#include "export/manifest.h"

#include "csgtile/worker/publish.h"

namespace csgtile::worker {

using nlohmann::ordered_json;

ordered_json manifest_head(const ManifestIdentity& identity, std::string_view kind) {
  ordered_json head;
  head["run"] = identity.run;
  head["kind"] = std::string(kind);
  head["csgtile_version"] = CSGTILE_VERSION;
  head["config_sha256"] = identity.config_sha256;
  head["seed"] = identity.seed;
  return head;
}

ordered_json index_entry(const RunIndexReport& index) {
  return {{"key", index.key},
          {"sha256", index.sha256},
          {"bytes", index.bytes},
          {"srs_id", index.srs_id},
          {"objects", index.stats.objects},
          {"shapes", index.stats.shapes},
          {"relations", index.stats.relations},
          {"unknown_relations", index.stats.unknown_relations},
          {"warnings", index.stats.warnings}};
}

ordered_json cityjson_entry(const CityJsonReport& cityjson) {
  return {{"key", cityjson.key},
          {"sha256", cityjson.sha256},
          {"bytes", cityjson.bytes},
          {"features", cityjson.stats.features},
          {"collapsed_triangles", cityjson.stats.collapsed_triangles},
          {"open_objects", cityjson.stats.open_objects},
          {"warnings", cityjson.stats.warnings}};
}

ordered_json tiles_entry(const TilesReport& tiles) {
  if (!tiles.written) return nullptr;
  return {{"key", tiles.key},
          {"sha256", tiles.sha256},
          {"bytes", tiles.bytes},
          {"content", tiles.content},
          {"content_sha256", tiles.content_sha256},
          {"content_bytes", tiles.content_bytes},
          {"objects", tiles.objects},
          {"triangles", tiles.triangles},
          {"warnings", tiles.warnings}};
}

Failure write_run_manifest(const std::filesystem::path& run_dir, const std::string& run,
                           ordered_json manifest, const JobRecords& records,
                           const std::vector<DeadJob>& dead, std::string& text) {
  if (Failure f = write_timings(run_dir, run, records); !f.ok()) return f;
  manifest["jobs"] = records.jobs;
  manifest["dead"] = dead_jobs_json(dead);
  manifest["timings"] = "timings.json";
  text = manifest.dump(2) + "\n";
  return write_file_atomic(run_dir / "manifest.json", text);
}

}  // namespace csgtile::worker
