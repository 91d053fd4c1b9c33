// HTTP range reads (fetch::open_range_source) against a loopback server: a COPC region query
// fetches its hierarchy and the chunks it needs, not the file; a server without Range support
// still works; errors are named. The LAZ/COPC data are ../shared/data/laz (skipped if absent).

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <tuple>

#include "background_process.h"
#include "csgtile/geo/las.h"
#include "fetch/fetch.h"
#include "s3_test_server.h"
#include "test_commands.h"
#include "test_support.h"

namespace {

using namespace csgtile;
using namespace csgtile::worker;
namespace fs = std::filesystem;
using csgtile::test::BackgroundProcess;
using csgtile::test::quoted;

fs::path laz_dir() { return test::shared_dir() / "data" / "laz"; }

using Xyz = std::tuple<double, double, double>;

std::vector<Xyz> all_points(geo::PointReader& reader) {
  std::vector<Xyz> out;
  geo::PointBatch batch;
  for (;;) {
    auto n = reader.read(batch, 4096);
    EXPECT_TRUE(n.ok()) << n.error().message;
    if (!n.ok() || n.value() == 0) break;
    for (const geo::Point& p : batch.points) out.emplace_back(p.x, p.y, p.z);
  }
  std::sort(out.begin(), out.end());
  return out;
}

// Read options for the lower-left quarter of a file's extent in x and y (all heights).
geo::PointReadOptions quarter_of(const fs::path& file) {
  auto whole = geo::LasReader::open(file);
  EXPECT_TRUE(whole.ok());
  geo::PointReadOptions options;
  if (!whole.ok()) return options;
  const geo::LasHeader& h = whole.value()->header();
  geo::Bounds3 region;
  region.min = {h.min[0], h.min[1], -1e300};
  region.max = {0.5 * (h.min[0] + h.max[0]), 0.5 * (h.min[1] + h.max[1]), 1e300};
  options.region = region;
  return options;
}

class RangeSource : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::is_directory(laz_dir())) GTEST_SKIP() << "LAZ data not found at " << laz_dir();
    server = std::make_unique<BackgroundProcess>(
        "exec python3 " +
        quoted(fs::path(CSGTILE_SOURCE_DIR) / "tests/support/fault_http_server.py") + " " +
        quoted(laz_dir()));
    ASSERT_TRUE(server->running()) << server->problem();
    base = "http://127.0.0.1:" + server->first_line();
    policy.retry_delay_ms = 10;
  }
  std::unique_ptr<geo::LasReader> open(const std::string& path,
                                       const geo::PointReadOptions& options = {},
                                       std::shared_ptr<fetch::RangeStats> stats = nullptr,
                                       std::uint64_t block = 64 * 1024) {
    std::unique_ptr<geo::ByteSource> source;
    Failure f = fetch::open_range_source(base + path, policy, source, std::move(stats), block);
    EXPECT_TRUE(f.ok()) << f.message;
    if (!f.ok()) return nullptr;
    auto reader = geo::LasReader::open_source(std::move(source), options);
    EXPECT_TRUE(reader.ok()) << reader.error().message;
    return reader.ok() ? std::move(reader).value() : nullptr;
  }
  std::unique_ptr<BackgroundProcess> server;
  std::string base;
  fetch::Policy policy;
};

TEST_F(RangeSource, ACopcRegionOverHttpFetchesOnlyItsNodes) {
  const fs::path local = laz_dir() / "1.2-with-color.copc.laz";
  auto whole = geo::LasReader::open(local);
  ASSERT_TRUE(whole.ok());
  const geo::PointReadOptions options = quarter_of(local);
  auto local_query = geo::LasReader::open(local, options);
  ASSERT_TRUE(local_query.ok());
  const auto expected = all_points(*local_query.value());

  auto stats = std::make_shared<fetch::RangeStats>();
  // The shared COPC file is small (33 KB): blocks of 1 KiB stand for the 64 KiB of a real one.
  auto remote = open("/range/1.2-with-color.copc.laz", options, stats, 1024);
  ASSERT_NE(remote, nullptr);
  EXPECT_EQ(all_points(*remote), expected);
  const auto size = fs::file_size(local);
  EXPECT_GT(stats->requests, 1u);
  EXPECT_LT(stats->bytes, size) << "a region must not fetch the whole file";
  std::cout << "[copc over http] region of a quarter: " << stats->bytes << " of " << size
            << " bytes in " << stats->requests << " requests\n";

  // Every point over ranges equals the local file's.
  auto all = open("/range/1.2-with-color.copc.laz");
  ASSERT_NE(all, nullptr);
  EXPECT_EQ(all_points(*all), all_points(*whole.value()));
}

TEST_F(RangeSource, ALargeLazIsReadChunkByChunkAndEqualsTheLocalFile) {
  auto stats = std::make_shared<fetch::RangeStats>();
  auto remote = open("/range/ahn3_cropped_2.laz", {}, stats);
  ASSERT_NE(remote, nullptr);
  auto local = geo::LasReader::open(laz_dir() / "ahn3_cropped_2.laz");
  ASSERT_TRUE(local.ok());
  EXPECT_EQ(all_points(*remote), all_points(*local.value()));
  // Chunks are fetched exactly; the header's block and the chunk table's overlap them a little.
  EXPECT_LE(stats->bytes, fs::file_size(laz_dir() / "ahn3_cropped_2.laz") + 3 * 64 * 1024);
}

TEST_F(RangeSource, AServerWithoutRangesSendsTheWholeObjectOnce) {
  auto stats = std::make_shared<fetch::RangeStats>();
  auto remote = open("/ok/point10.laz", {}, stats);
  ASSERT_NE(remote, nullptr);
  auto local = geo::LasReader::open(laz_dir() / "point10.laz");
  ASSERT_TRUE(local.ok());
  EXPECT_EQ(all_points(*remote), all_points(*local.value()));
  EXPECT_EQ(stats->requests, 1u);
}

// A server that stops answering after the header: the read fails as an I/O error of the
// reader naming the URL, and the stats keep the transfer's own failure (Network, retryable).
TEST_F(RangeSource, AFailureMidReadKeepsItsNetworkCode) {
  auto stats = std::make_shared<fetch::RangeStats>();
  auto remote = open("/range-then-503/2/ahn3_cropped_2.laz", {}, stats);
  ASSERT_NE(remote, nullptr);  // the header, VLRs and chunk table were answered
  geo::PointBatch batch;
  kernel::Result<std::size_t> n = std::size_t{0};
  for (int i = 0; i < 100; ++i) {
    n = remote->read(batch, 4096);
    if (!n.ok() || n.value() == 0) break;
  }
  ASSERT_FALSE(n.ok());
  EXPECT_EQ(n.error().code, kernel::ErrorCode::IoError);
  EXPECT_NE(n.error().message.find("HTTP 503"), std::string::npos) << n.error().message;
  EXPECT_EQ(stats->last_failure.code, ErrorCode::Network) << stats->last_failure.message;
}

TEST_F(RangeSource, MissingObjectsAndRefusedSchemesAreNamed) {
  std::unique_ptr<geo::ByteSource> source;
  Failure f = fetch::open_range_source(base + "/status/404", policy, source);
  EXPECT_EQ(f.code, ErrorCode::FetchRefused) << f.message;
  EXPECT_NE(f.message.find("404"), std::string::npos) << f.message;
  f = fetch::open_range_source("file:///etc/hostname", policy, source);
  EXPECT_EQ(f.code, ErrorCode::FetchRefused) << f.message;
  f = fetch::open_range_source(base + "/flaky/10/point10.laz", policy, source);
  EXPECT_EQ(f.code, ErrorCode::Network) << f.message;
  f = fetch::open_range_source("http://169.254.169.254/latest", policy, source);
  EXPECT_EQ(f.code, ErrorCode::FetchRefused) << f.message;
  EXPECT_EQ(source, nullptr);
}

// Range reads of an s3:// object, signed per request (s3rver checks every signature): a COPC
// region query gives the local file's points and fetches less than the object.
TEST(RangeSourceS3, ACopcRegionFromS3EqualsTheLocalQuery) {
  if (!fs::is_directory(laz_dir())) GTEST_SKIP() << "LAZ data not found at " << laz_dir();
  csgtile::test::TempDir tmp{"csgtile-range-s3-"};
  std::string missing;
  auto server = csgtile::test::start_s3rver(tmp.path() / "s3", "tiles", missing);
  if (!server && csgtile::test::s3rver_required()) FAIL() << missing;
  if (!server) GTEST_SKIP() << missing;
  ASSERT_TRUE(server->running()) << server->problem();
  fetch::Policy policy;
  policy.s3.endpoint = "http://127.0.0.1:" + server->first_line();
  policy.retry_delay_ms = 10;
  csgtile::test::ScopedEnv env(
      {{"AWS_ACCESS_KEY_ID", "S3RVER"}, {"AWS_SECRET_ACCESS_KEY", "S3RVER"}});
  const fs::path local = laz_dir() / "1.2-with-color.copc.laz";
  std::ifstream in(local, std::ios::binary);
  const std::string bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  ASSERT_TRUE(fetch::s3_put("s3://tiles/city/copc.copc.laz", bytes, policy).ok());

  const geo::PointReadOptions options = quarter_of(local);
  auto local_query = geo::LasReader::open(local, options);
  ASSERT_TRUE(local_query.ok());

  auto stats = std::make_shared<fetch::RangeStats>();
  std::unique_ptr<geo::ByteSource> source;
  Failure f =
      fetch::open_range_source("s3://tiles/city/copc.copc.laz", policy, source, stats, 1024);
  ASSERT_TRUE(f.ok()) << f.message;
  auto remote = geo::LasReader::open_source(std::move(source), options);
  ASSERT_TRUE(remote.ok()) << remote.error().message;
  EXPECT_EQ(all_points(*remote.value()), all_points(*local_query.value()));
  EXPECT_GT(stats->requests, 1u);
  EXPECT_LT(stats->bytes, bytes.size());
  // A missing key is a named refusal.
  f = fetch::open_range_source("s3://tiles/city/none.copc.laz", policy, source);
  EXPECT_EQ(f.code, ErrorCode::FetchRefused) << f.message;
}

}  // namespace
