// The one run-manifest writer (worker/src/export/manifest.h): the same head for every kind of
// manifest, jobs, dead jobs and timings last, timings outside the hashed bytes.

#include "export/manifest.h"
#include "export_settings.h"

#include <gtest/gtest.h>

#include "test_support.h"

namespace csgtile::worker {
namespace {

using nlohmann::ordered_json;

std::vector<std::string> keys_of(const ordered_json& j) {
  std::vector<std::string> out;
  for (const auto& [key, value] : j.items()) out.push_back(key);
  return out;
}

TEST(RunManifest, EveryKindStartsWithTheSameHead) {
  config::Config config;
  config.run.name = "delft";
  config.run.seed = 42;
  for (const char* kind : {"scenes", "city", "cell"}) {
    const ordered_json head = manifest_head(jobs::manifest_identity(config), kind);
    EXPECT_EQ(keys_of(head), (std::vector<std::string>{"run", "kind", "csgtile_version",
                                                       "config_sha256", "seed"}));
    EXPECT_EQ(head["kind"], kind);
    EXPECT_EQ(head["run"], "delft");
    EXPECT_EQ(head["seed"], 42);
    EXPECT_EQ(head["config_sha256"], output_config_sha256(config));
  }
  config::Config other = config;
  other.run.seed = 43;  // another seed: another publication
  EXPECT_NE(manifest_head(jobs::manifest_identity(config), "city"),
            manifest_head(jobs::manifest_identity(other), "city"));
}

TEST(RunManifest, ConfigHashSeesOnlyWhatShapesOutputs) {
  config::Config config;
  const std::string base = output_config_sha256(config);
  config::Config same = config;
  same.run.output = "elsewhere";
  same.run.threads = 7;
  same.queue.max_attempts = 2;
  same.queue.job_memory_mib = 512;
  same.log.level = config::LogLevel::Error;
  same.fetch.attempts = 1;
  same.publish.url = "s3://bucket/runs";
  EXPECT_EQ(output_config_sha256(same), base);
  config::Config other = config;
  other.kernel.chordal_tolerance *= 2.0;
  EXPECT_NE(output_config_sha256(other), base);
  other = config;
  other.city.cell_size = 100.0;
  EXPECT_NE(output_config_sha256(other), base);
}

TEST(RunManifest, ExportsAreListedAlikeAndTilesOnlyWhenWritten) {
  RunIndexReport index;
  index.sha256 = "ab";
  index.bytes = 10;
  index.srs_id = 7415;
  index.stats.objects = 3;
  index.stats.unknown_relations = 1;
  const ordered_json i = index_entry(index);
  EXPECT_EQ(i["key"], "index.gpkg");
  EXPECT_EQ(i["srs_id"], 7415);
  EXPECT_EQ(i["unknown_relations"], 1);
  CityJsonReport cityjson;
  cityjson.stats.features = 3;
  EXPECT_EQ(cityjson_entry(cityjson)["features"], 3);
  TilesReport tiles;
  EXPECT_TRUE(tiles_entry(tiles).is_null());
  tiles.written = true;
  tiles.objects = 3;
  EXPECT_EQ(tiles_entry(tiles)["content"], "tiles/model.glb");
  EXPECT_EQ(tiles_entry(tiles)["objects"], 3);
}

TEST(RunManifest, JobsDeadAndTimingsComeLastAndTimingsStayOutOfTheHashedBytes) {
  test::TempDir dir("csgtile_manifest_");
  config::Config config;
  config.run.name = "r";
  JobRecords records;
  records.add("fit:r:a", ordered_json::parse(R"({"points": 5, "timings": {"stages": {"fit": 1.5},
              "seconds": 1.5, "worker": "w", "attempt": 1}})"));
  const std::vector<DeadJob> dead{{"fit:r:b", "input_invalid: b: not LAS", 3}};
  ordered_json manifest = manifest_head(jobs::manifest_identity(config), "city");
  manifest["problems"] = ordered_json::array();
  std::string text;
  ASSERT_TRUE(write_run_manifest(dir.path(), "r", manifest, records, dead, text).ok());
  EXPECT_EQ(test::read_file(dir.path() / "manifest.json"), text);
  const ordered_json written = ordered_json::parse(text);
  const auto keys = keys_of(written);
  ASSERT_GE(keys.size(), 3u);
  EXPECT_EQ(std::vector<std::string>(keys.end() - 3, keys.end()),
            (std::vector<std::string>{"jobs", "dead", "timings"}));
  EXPECT_EQ(written["jobs"].size(), 1u);
  EXPECT_FALSE(written["jobs"][0]["result"].contains("timings")) << text;
  EXPECT_EQ(written["dead"][0]["key"], "fit:r:b");
  EXPECT_EQ(written["timings"], "timings.json");
  const ordered_json timings = ordered_json::parse(test::read_file(dir.path() / "timings.json"));
  EXPECT_NE(timings.dump().find("1.5"), std::string::npos) << timings.dump();
  EXPECT_EQ(text.find("1.5"), std::string::npos) << text;
}

}  // namespace
}  // namespace csgtile::worker
