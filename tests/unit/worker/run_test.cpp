// The embedded run: jobs per input, failures as dead jobs with reasons, deterministic
// content-addressed outputs, atomic publishing helpers.

#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <set>

#include "csgtile/worker/publish.h"
#include "csgtile/worker/run.h"
#include "test_support.h"

namespace csgtile::worker {
namespace {

namespace fs = std::filesystem;

class RunTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("csgtile-run-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  config::Config make_config(const std::string& out, std::vector<std::string> inputs) {
    config::Config c;
    c.run.name = "t";
    c.run.output = (dir_ / out).string();
    c.run.inputs = std::move(inputs);
    c.queue.max_attempts = 2;
    return c;
  }
  std::string write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
    return (dir_ / name).string();
  }
  fs::path dir_;
};

TEST_F(RunTest, BadInputsEndDeadWithReasonsAndTheRestIsPublished) {
  const std::string good = (test::source_dir() / "config/examples/scenes/pavilion.json").string();
  const std::string broken = write("broken.json", "{\"primitives\": [{\"type\": \"box\"}]}");
  const std::string degenerate = write(
      "flat.json",
      "{\"primitives\": [{\"type\": \"extrusion\", \"profile\": [[0,0],[1,0],[2,0]], \"h\": 1}]}");
  const std::string missing = (dir_ / "missing.json").string();
  Logger log(config::LogLevel::Error, config::LogFormat::Json, stderr);
  RunSummary summary;
  const Failure f =
      run_embedded(make_config("out", {good, broken, degenerate, missing}), log, summary);
  ASSERT_TRUE(f.ok()) << f.message;
  EXPECT_EQ(summary.counts.done, 1);
  EXPECT_EQ(summary.counts.dead, 3);
  std::string reasons;
  for (const auto& d : summary.dead) reasons += d.last_error + "\n";
  EXPECT_NE(reasons.find("key \"size\""), std::string::npos) << reasons;
  EXPECT_NE(reasons.find("geometry_invalid"), std::string::npos) << reasons;
  EXPECT_NE(reasons.find("cannot read scene file"), std::string::npos) << reasons;
  const auto manifest = nlohmann::json::parse(test::read_file(summary.manifest));
  ASSERT_EQ(manifest["jobs"].size(), 1u);
  const std::string key = manifest["jobs"][0]["result"]["model"]["key"];
  const std::string bytes = test::read_file(summary.run_dir / key);
  EXPECT_EQ(sha256_hex(bytes), manifest["jobs"][0]["result"]["model"]["sha256"]);
  EXPECT_EQ(manifest["dead"].size(), 3u);
}

TEST_F(RunTest, SameInputsGiveByteIdenticalOutputs) {
  const std::string scene =
      (test::source_dir() / "config/examples/scenes/courtyard_block.json").string();
  Logger log(config::LogLevel::Error, config::LogFormat::Json, stderr);
  RunSummary a, b;
  ASSERT_TRUE(run_embedded(make_config("a", {scene}), log, a).ok());
  ASSERT_TRUE(run_embedded(make_config("b", {scene}), log, b).ok());
  // Everything but the config hash (the output folders differ) is identical, object bytes too.
  auto ma = nlohmann::json::parse(test::read_file(a.manifest));
  auto mb = nlohmann::json::parse(test::read_file(b.manifest));
  EXPECT_EQ(ma["jobs"].dump(), mb["jobs"].dump());
  const std::string key = ma["jobs"][0]["result"]["model"]["key"];
  EXPECT_EQ(test::read_file(a.run_dir / key), test::read_file(b.run_dir / key));
  // Running again on the same queue publishes nothing new and keeps the manifest.
  const std::string before = test::read_file(a.manifest);
  RunSummary again;
  ASSERT_TRUE(run_embedded(make_config("a", {scene}), log, again).ok());
  EXPECT_EQ(test::read_file(again.manifest), before);
}

TEST(Publish, Sha256MatchesKnownVectors) {
  EXPECT_EQ(sha256_hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(sha256_hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
}

TEST(Publish, KeysWithTraversalOrOddCharactersAreRefused) {
  EXPECT_TRUE(is_safe_key("objects/ab12.csgt"));
  EXPECT_FALSE(is_safe_key("../etc/passwd"));
  EXPECT_FALSE(is_safe_key("objects/../../x"));
  EXPECT_FALSE(is_safe_key("/abs"));
  EXPECT_FALSE(is_safe_key("a//b"));
  EXPECT_FALSE(is_safe_key("a/./b"));
  EXPECT_FALSE(is_safe_key("a b"));
  EXPECT_FALSE(is_safe_key(""));
}

TEST(Publish, AtomicWriteLeavesNoTemporaryAndReplacesWhole) {
  const fs::path dir =
      fs::temp_directory_path() / ("csgtile-publish-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  ASSERT_TRUE(write_file_atomic(dir / "sub" / "f.txt", "first").ok());
  ASSERT_TRUE(write_file_atomic(dir / "sub" / "f.txt", "second").ok());
  EXPECT_EQ(test::read_file(dir / "sub" / "f.txt"), "second");
  int entries = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir / "sub")) ++entries;
  EXPECT_EQ(entries, 1);
  const Failure f = write_file_atomic("/proc/csgtile-cannot-write/x", "y");
  EXPECT_EQ(f.code, ErrorCode::Io);
  fs::remove_all(dir);
}

TEST(ErrorTable, ExitCodesAreDistinctAndAvoidReservedValues) {
  std::size_t n = 0;
  const ErrorInfo* table = error_table(&n);
  std::set<int> seen;
  for (std::size_t i = 0; i < n; ++i) {
    EXPECT_EQ(static_cast<std::size_t>(table[i].code), i);
    EXPECT_TRUE(seen.insert(table[i].exit_code).second) << table[i].name;
    EXPECT_FALSE(table[i].exit_code >= 124 && table[i].exit_code <= 127);
    EXPECT_NE(table[i].exit_code, 137);
  }
}

TEST(ErrorTable, KernelErrorsBecomeFailuresWithTheirContext) {
  const kernel::Error error{kernel::ErrorCode::CorruptData, "bad checksum"};
  const Failure bare = failure_of(error);
  EXPECT_EQ(bare.code, ErrorCode::InputInvalid);
  EXPECT_EQ(bare.message, "bad checksum");
  const Failure named = failure_of(error, "a.csgt");
  EXPECT_EQ(named.code, from_kernel(kernel::ErrorCode::CorruptData));
  EXPECT_EQ(named.message, "a.csgt: bad checksum");
  EXPECT_EQ(failure_of({kernel::ErrorCode::IoError, "x"}).code, ErrorCode::Io);
}

}  // namespace
}  // namespace csgtile::worker
