// Publishing a run directory to S3 against real loopback servers: @20minutes/s3rver (it
// checks SigV4 signatures) and, for faults, tests/support/fault_tcp_proxy.py in front of it.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "background_process.h"
#include "csgtile/worker/publish.h"
#include "fetch/fetch.h"
#include "publish/s3_publish.h"
#include "s3_test_server.h"
#include "test_commands.h"
#include "test_support.h"

namespace fs = std::filesystem;
using namespace csgtile::worker;
using csgtile::test::BackgroundProcess;
using csgtile::test::quoted;
using publish::PublishPlan;
using publish::PublishReport;

namespace {

constexpr const char* kBucket = "pub";

void write_file(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary) << text;
}

// A small run directory shaped like a city run's output: run files, tiles, objects and two
// cells. `version` changes every content; `extra` adds that many more objects. Two files
// share one content, so they share one object.
PublishPlan make_run(const fs::path& root, const std::string& version, int extra = 0) {
  PublishPlan plan;
  plan.root = root;
  auto add = [&](const std::string& path, const std::string& text) {
    write_file(root / path, text);
    plan.objects.push_back(path);
  };
  add("index.gpkg", "SQLite format 3 " + version);
  add("model.city.jsonl", "{\"type\":\"CityJSON\",\"v\":\"" + version + "\"}\n");
  add("tiles/tileset.json", "{\"asset\":{\"version\":\"1.1\"},\"v\":\"" + version + "\"}");
  add("tiles/model.glb", "glTF " + version + std::string(3000, 'g'));
  add("objects/a1.csgt", "csgt object a " + version);
  add("timings.json", "{\"fit\":1.5}");
  for (const std::string cell : {"0_0", "0_1"}) {
    add("cells/" + cell + "/model.glb", "glTF cell " + cell + " " + version);
    add("cells/" + cell + "/model.csgt", "csgt object a " + version);  // same as objects/a1.csgt
    write_file(root / "cells" / cell / "manifest.json",
               "{\"cell\":\"" + cell + "\",\"v\":\"" + version + "\"}");
    plan.manifests.push_back("cells/" + cell + "/manifest.json");
  }
  for (int i = 0; i < extra; ++i)
    add("objects/x" + std::to_string(i) + ".csgt", version + " extra " + std::to_string(i));
  write_file(root / "manifest.json", "{\"run\":\"" + version + "\"}");
  plan.manifests.push_back("manifest.json");
  return plan;
}

// Distinct contents in a plan made by make_run: every path but the shared cell .csgt copies.
std::size_t distinct_files(const PublishPlan& plan) {
  return plan.objects.size() + plan.manifests.size() - 2;
}

std::size_t regular_files(const fs::path& dir) {
  std::size_t n = 0;
  if (!fs::exists(dir)) return 0;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) n += entry.is_regular_file();
  return n;
}

}  // namespace

class S3Publish : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string missing;
    server = csgtile::test::start_s3rver(tmp.path() / "s3", kBucket, missing);
    if (!server && csgtile::test::s3rver_required()) FAIL() << missing;
    if (!server) GTEST_SKIP() << missing;
    ASSERT_TRUE(server->running()) << server->problem();
    s3_port = server->first_line();
    policy.s3.endpoint = "http://127.0.0.1:" + s3_port;
    policy.retry_delay_ms = 10;
    use_secret("S3RVER");
  }
  // s3rver's access key with `secret`; the environment is restored after the test.
  void use_secret(const std::string& secret) {
    credentials_.reset();
    credentials_.emplace(std::map<std::string, std::string>{{"AWS_ACCESS_KEY_ID", "S3RVER"},
                                                            {"AWS_SECRET_ACCESS_KEY", secret},
                                                            {"AWS_SESSION_TOKEN", ""}});
  }
  // A fault proxy in front of s3rver running `plan` (see fault_tcp_proxy.py).
  fetch::Policy through_proxy(const std::string& plan) {
    proxy = std::make_unique<BackgroundProcess>(
        "exec python3 " +
        quoted(fs::path(CSGTILE_SOURCE_DIR) / "tests/support/fault_tcp_proxy.py") + " " + s3_port +
        " " + plan);
    EXPECT_TRUE(proxy->running()) << proxy->problem();
    fetch::Policy p = policy;
    p.s3.endpoint = "http://127.0.0.1:" + proxy->first_line();
    return p;
  }

  std::optional<std::string> get(const std::string& key) {
    fetch::S3Object object;
    std::string bytes;
    const Failure f =
        fetch::s3_get("s3://" + std::string(kBucket) + "/" + key, policy, object, bytes);
    EXPECT_TRUE(f.ok()) << f.message;
    if (!object.exists) return std::nullopt;
    return bytes;
  }

  // Follows the pointer of `run` under `prefix` as a reader would and checks that everything
  // it names is there with its SHA-256 and size. Returns a problem, or "" (and the manifest).
  std::string follow(const std::string& prefix, const std::string& run,
                     nlohmann::json* manifest_out = nullptr) {
    const std::string base = prefix.empty() ? "" : prefix + "/";
    const auto pointer_text = get(base + "runs/" + run + "/CURRENT");
    if (!pointer_text) return "no pointer";
    const auto pointer = nlohmann::json::parse(*pointer_text);
    const auto manifest_text = get(base + pointer.at("manifest").get<std::string>());
    if (!manifest_text) return "the pointer names a missing manifest";
    if (sha256_hex(*manifest_text) != pointer.at("sha256"))
      return "manifest SHA-256 differs from the pointer's";
    const auto manifest = nlohmann::json::parse(*manifest_text);
    if (manifest.at("run") != run || manifest.at("scope") != "") return "not the run's manifest";
    for (const auto& [path, entry] : manifest.at("files").items()) {
      const auto object = get(base + entry.at("key").get<std::string>());
      if (!object) return "missing object for " + path;
      if (sha256_hex(*object) != entry.at("sha256") || object->size() != entry.at("size")) {
        return "object for " + path + " does not match its manifest entry";
      }
    }
    if (!manifest.at("files").contains(manifest.at("local_manifest").get<std::string>())) {
      return "the local manifest is not among the files";
    }
    for (const auto& cell : manifest.at("cells")) {
      const auto cell_text = get(base + cell.at("key").get<std::string>());
      if (!cell_text || sha256_hex(*cell_text) != cell.at("sha256"))
        return "cell manifest missing or changed";
      const auto cell_manifest = nlohmann::json::parse(*cell_text);
      for (const auto& [path, entry] : cell_manifest.at("files").items()) {
        if (path.rfind(cell.at("scope").get<std::string>() + "/", 0) != 0)
          return path + " outside its cell";
        if (manifest.at("files").value(path, nlohmann::json()) != entry)
          return path + " differs between manifests";
      }
    }
    if (manifest_out != nullptr) *manifest_out = manifest;
    return "";
  }

  bool exists(const std::string& key) {
    fetch::S3Object object;
    const Failure f = fetch::s3_head("s3://" + std::string(kBucket) + "/" + key, policy, object);
    EXPECT_TRUE(f.ok()) << f.message;
    return object.exists;
  }

  csgtile::test::TempDir tmp{"csgtile-publish-"};
  std::unique_ptr<BackgroundProcess> server;
  std::unique_ptr<BackgroundProcess> proxy;
  std::string s3_port;
  fetch::Policy policy;

 private:
  std::optional<csgtile::test::ScopedEnv> credentials_;
};

TEST_F(S3Publish, AReaderFollowingThePointerFindsEveryFileWithItsHash) {
  const PublishPlan plan = make_run(tmp / "run", "v1");
  PublishReport report;
  const Failure f = publish::publish_run_to_s3(plan, "s3://pub/city", "berlin", policy, report);
  ASSERT_TRUE(f.ok()) << f.message;
  EXPECT_EQ(report.uploaded, distinct_files(plan) + 3)
      << "objects, two cell manifests, the run manifest";
  EXPECT_EQ(report.skipped_existing, 0u);
  EXPECT_TRUE(report.pointer_changed);
  EXPECT_EQ(report.pointer_key, "city/runs/berlin/CURRENT");
  EXPECT_EQ(report.manifest_key.rfind("city/runs/berlin/manifests/", 0), 0u) << report.manifest_key;

  nlohmann::json manifest;
  ASSERT_EQ(follow("city", "berlin", &manifest), "");
  EXPECT_EQ(manifest.at("files").size(), plan.objects.size() + plan.manifests.size());
  EXPECT_EQ(manifest.at("local_manifest"), "manifest.json");
  ASSERT_EQ(manifest.at("cells").size(), 2u);
  EXPECT_EQ(manifest.at("cells")[0].at("scope"), "cells/0_0");
  const auto& glb = manifest.at("files").at("tiles/model.glb");
  EXPECT_EQ(glb.at("key"), "objects/" + glb.at("sha256").get<std::string>() + ".glb");
  EXPECT_EQ(manifest.at("files").at("model.city.jsonl").at("key").get<std::string>().substr(72),
            ".jsonl");
  // The stored object is byte-identical to the local file.
  std::ifstream in(plan.root / "tiles/model.glb", std::ios::binary);
  const std::string local{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  EXPECT_EQ(get("city/" + glb.at("key").get<std::string>()).value_or(""), local);

  EXPECT_GT(regular_files(tmp.path() / "s3" / kBucket), 0u) << "s3rver keeps objects as files";

  std::string key;
  ASSERT_TRUE(publish::pointer_key("s3://pub/city/", "berlin", key).ok());
  EXPECT_EQ(key, report.pointer_key);
}

TEST_F(S3Publish, RepublishingUploadsNothingNew) {
  const PublishPlan plan = make_run(tmp / "run", "v1");
  PublishReport first, second;
  ASSERT_TRUE(publish::publish_run_to_s3(plan, "s3://pub", "r1", policy, first).ok());
  const Failure f = publish::publish_run_to_s3(plan, "s3://pub", "r1", policy, second);
  ASSERT_TRUE(f.ok()) << f.message;
  EXPECT_EQ(second.uploaded, 0u);
  EXPECT_EQ(second.bytes, 0u);
  EXPECT_EQ(second.skipped_existing, first.uploaded);
  EXPECT_FALSE(second.pointer_changed);
  EXPECT_EQ(second.manifest_key, first.manifest_key);
  EXPECT_EQ(second.pointer_key, "runs/r1/CURRENT");
  EXPECT_EQ(follow("", "r1"), "");
}

TEST_F(S3Publish, ANewVersionOfTheRunMovesThePointerAndKeepsTheOldManifest) {
  PublishReport first, second;
  ASSERT_TRUE(
      publish::publish_run_to_s3(make_run(tmp / "a", "v1"), "s3://pub", "r", policy, first).ok());
  const PublishPlan v2 = make_run(tmp / "b", "v2");
  ASSERT_TRUE(publish::publish_run_to_s3(v2, "s3://pub", "r", policy, second).ok());
  EXPECT_NE(second.manifest_key, first.manifest_key);
  EXPECT_TRUE(second.pointer_changed);
  EXPECT_EQ(second.skipped_existing, 1u) << "only timings.json is unchanged";
  nlohmann::json manifest;
  ASSERT_EQ(follow("", "r", &manifest), "");
  EXPECT_EQ(manifest.at("files").size(), v2.objects.size() + v2.manifests.size());
  EXPECT_EQ(second.manifest_key,
            "runs/r/manifests/" + sha256_hex(get(second.manifest_key).value_or("")) + ".json")
      << "manifest keys are content-addressed";
  EXPECT_TRUE(exists(first.manifest_key)) << "published manifests are never deleted or changed";
}

TEST_F(S3Publish, AManifestKeyHoldingOtherBytesIsRefusedNotOverwritten) {
  const PublishPlan plan = make_run(tmp / "run", "v1");
  PublishReport report;
  ASSERT_TRUE(publish::publish_run_to_s3(plan, "s3://pub/a", "r", policy, report).ok());
  // Manifests name keys relative to the prefix, so the same run has the same manifest key
  // under prefix b. Something else already sits there.
  const std::string taken = "b/" + report.manifest_key.substr(2);
  ASSERT_TRUE(fetch::s3_put("s3://pub/" + taken, "{\"someone\":\"else\"}\n", policy).ok());

  PublishReport refused;
  const Failure f = publish::publish_run_to_s3(plan, "s3://pub/b", "r", policy, refused);
  EXPECT_EQ(f.code, ErrorCode::ResultInvalid) << f.message;
  EXPECT_NE(f.message.find("publish conflict"), std::string::npos) << f.message;
  EXPECT_NE(f.message.find(taken), std::string::npos) << f.message;
  EXPECT_EQ(get(taken).value_or(""), "{\"someone\":\"else\"}\n") << "never overwritten";
  EXPECT_FALSE(exists("b/runs/r/CURRENT")) << "no pointer to a conflicting manifest";
  EXPECT_TRUE(refused.pointer_key.empty());

  // The same for a content-addressed object whose key holds something of another size.
  const std::string object = "c/" + nlohmann::json::parse(get(report.manifest_key).value())
                                        .at("files")
                                        .at("index.gpkg")
                                        .at("key")
                                        .get<std::string>();
  ASSERT_TRUE(fetch::s3_put("s3://pub/" + object, "short", policy).ok());
  const Failure g = publish::publish_run_to_s3(plan, "s3://pub/c", "r", policy, refused);
  EXPECT_EQ(g.code, ErrorCode::ResultInvalid) << g.message;
  EXPECT_FALSE(exists("c/runs/r/CURRENT"));
}

TEST_F(S3Publish, AWrongSecretIsRefusedAndNothingIsPublished) {
  const PublishPlan plan = make_run(tmp / "run", "v1");
  use_secret("not-the-secret");
  PublishReport report;
  const Failure f = publish::publish_run_to_s3(plan, "s3://pub", "r", policy, report);
  EXPECT_EQ(f.code, ErrorCode::FetchRefused) << f.message;
  EXPECT_NE(f.message.find("HTTP 403"), std::string::npos) << f.message;
  EXPECT_NE(f.message.find("credentials"), std::string::npos) << f.message;
  EXPECT_EQ(f.message.find("not-the-secret"), std::string::npos) << "the secret is never shown";
  EXPECT_FALSE(error_info(f.code).retryable);
  EXPECT_EQ(report.uploaded, 0u);
  EXPECT_TRUE(report.pointer_key.empty());
  use_secret("S3RVER");
  EXPECT_FALSE(exists("runs/r/CURRENT"));
  EXPECT_EQ(regular_files(tmp.path() / "s3" / kBucket), 0u) << "no object stored at all";
}

TEST_F(S3Publish, UnsafePlansAreRefusedBeforeAnyRequest) {
  PublishPlan plan = make_run(tmp / "run", "v1");
  write_file(tmp / "outside.txt", "secret");
  fs::create_symlink(tmp / "outside.txt", tmp / "run" / "link.txt");
  struct Case {
    std::string name, prefix, run, path;
  };
  const std::vector<Case> cases = {
      {"dot-dot path", "s3://pub", "r", "../x"},
      {"nested dot-dot", "s3://pub", "r", "tiles/../../x"},
      {"absolute path", "s3://pub", "r", "/etc/passwd"},
      {"control character", "s3://pub", "r", "tiles/a\nb"},
      {"symbolic link out of the run", "s3://pub", "r", "link.txt"},
      {"listed twice", "s3://pub", "r", "index.gpkg"},
      {"dot-dot run name", "s3://pub", "..", ""},
      {"run name with a slash", "s3://pub", "a/b", ""},
      {"dot-dot prefix", "s3://pub/../x", "r", ""},
      {"bad bucket", "s3://Pub_1/x", "r", ""},
      {"not s3", "https://pub/x", "r", ""},
  };
  for (const Case& c : cases) {
    PublishPlan bad = plan;
    if (!c.path.empty()) bad.objects.push_back(c.path);
    PublishReport report;
    const Failure f = publish::publish_run_to_s3(bad, c.prefix, c.run, policy, report);
    EXPECT_EQ(f.code, ErrorCode::InputInvalid) << c.name << ": " << f.message;
    EXPECT_EQ(f.message.find('\n'), std::string::npos) << c.name << ": control characters escaped";
  }
  PublishPlan no_manifest = plan;
  no_manifest.manifests.clear();
  PublishReport report;
  EXPECT_EQ(publish::publish_run_to_s3(no_manifest, "s3://pub", "r", policy, report).code,
            ErrorCode::InputInvalid);
  EXPECT_EQ(regular_files(tmp.path() / "s3" / kBucket), 0u)
      << "nothing uploaded by any refused plan";
}

TEST_F(S3Publish, TransientResetsAreRetried) {
  const fetch::Policy flaky = through_proxy("reset:2,pass:3,reset:1,pass:*");
  const PublishPlan plan = make_run(tmp / "run", "v1");
  PublishReport report;
  const Failure f = publish::publish_run_to_s3(plan, "s3://pub", "r", flaky, report);
  ASSERT_TRUE(f.ok()) << f.message;
  EXPECT_EQ(follow("", "r"), "");
}

// A failure cut in at each phase: after two objects, after the first cell manifest, and at
// the pointer. Each leaves no pointer; a re-run over a healthy connection completes and
// re-uses what was stored.
TEST_F(S3Publish, AFailureMidwayLeavesNoPointerAndARerunCompletes) {
  const PublishPlan plan = make_run(tmp / "run", "v1");
  const std::size_t objects = distinct_files(plan);
  // Requests: HEAD + PUT per new object; HEAD + PUT per new manifest; HEAD + PUT for the pointer.
  const std::vector<std::size_t> cuts = {4, 2 * objects + 2, 2 * objects + 6};
  for (std::size_t i = 0; i < cuts.size(); ++i) {
    SCOPED_TRACE("cut after " + std::to_string(cuts[i]) + " requests");
    const std::string prefix = "cut" + std::to_string(i);
    fetch::Policy broken = through_proxy("pass:" + std::to_string(cuts[i]) + ",reset:*");
    broken.attempts = 3;
    PublishReport report;
    const Failure f = publish::publish_run_to_s3(plan, "s3://pub/" + prefix, "r", broken, report);
    EXPECT_EQ(f.code, ErrorCode::Network) << f.message;
    EXPECT_NE(f.message.find("after 3 attempts"), std::string::npos) << f.message;
    EXPECT_TRUE(error_info(f.code).retryable);
    EXPECT_EQ(report.uploaded, cuts[i] / 2);
    EXPECT_TRUE(report.pointer_key.empty());
    EXPECT_FALSE(exists(prefix + "/runs/r/CURRENT"));

    PublishReport rerun;
    const Failure g = publish::publish_run_to_s3(plan, "s3://pub/" + prefix, "r", policy, rerun);
    ASSERT_TRUE(g.ok()) << g.message;
    EXPECT_EQ(rerun.skipped_existing, report.uploaded);
    EXPECT_EQ(rerun.uploaded + rerun.skipped_existing, objects + 3);
    EXPECT_EQ(follow(prefix, "r"), "");
  }
}

// While a second version of a run is published, readers that follow the pointer always find
// a complete manifest: the old one until the pointer moves, the new one after.
TEST_F(S3Publish, ConcurrentReadersAlwaysFindACompleteRun) {
  PublishReport first;
  ASSERT_TRUE(
      publish::publish_run_to_s3(make_run(tmp / "v1", "v1", 10), "s3://pub", "r", policy, first)
          .ok());
  const PublishPlan v2 = make_run(tmp / "v2", "v2", 40);

  std::atomic<bool> publishing{true};
  std::vector<std::string> problems;
  std::size_t reads = 0, saw_old = 0, saw_new = 0;
  std::thread reader([&] {
    bool last = false;
    while (!last) {
      last = !publishing.load();
      nlohmann::json manifest;
      const std::string problem = follow("", "r", &manifest);
      ++reads;
      if (!problem.empty()) {
        problems.push_back(problem);
        continue;
      }
      (manifest.at("files").size() == v2.objects.size() + v2.manifests.size() ? saw_new
                                                                              : saw_old)++;
    }
  });
  PublishReport second;
  const Failure f = publish::publish_run_to_s3(v2, "s3://pub", "r", policy, second);
  publishing = false;
  reader.join();
  ASSERT_TRUE(f.ok()) << f.message;
  RecordProperty("reads", static_cast<int>(reads));
  RecordProperty("reads_of_the_old_version", static_cast<int>(saw_old));
  EXPECT_TRUE(problems.empty()) << problems.size() << " of " << reads
                                << " reads, first: " << problems.front();
  EXPECT_GE(saw_old, 1u) << "the reader ran while the new version was being published";
  EXPECT_GE(saw_new, 1u) << "the last read sees the new version";
}

TEST(S3PublishPlan, ARunDirectoryIsPlannedCellsFirstAndTheRunManifestLast) {
  csgtile::test::TempDir tmp{"csgtile-publish-"};
  PublishPlan expected = make_run(tmp / "run", "v1");
  write_file(tmp / "run" / ".manifest.json.tmp.1.2", "a temporary file of write_file_atomic");
  write_file(tmp / "run" / ".partial" / "x.glb", "hidden directory");
  PublishPlan plan;
  const Failure f = publish::plan_run_directory(tmp / "run", plan);
  ASSERT_TRUE(f.ok()) << f.message;
  EXPECT_EQ(plan.root, tmp / "run");
  EXPECT_EQ(plan.manifests, expected.manifests);
  std::sort(expected.objects.begin(), expected.objects.end());
  EXPECT_EQ(plan.objects, expected.objects);

  fs::remove(tmp / "run" / "manifest.json");
  EXPECT_EQ(publish::plan_run_directory(tmp / "run", plan).code, ErrorCode::InputInvalid);
}
