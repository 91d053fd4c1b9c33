// COPC: the hierarchy of ../shared/data/laz/1.2-with-color.copc.laz, region and depth queries
// that read only the nodes they need (counted at the byte source), and broken hierarchies.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <tuple>
#include <vector>

#include "csgtile/geo/copc.h"
#include "csgtile/geo/las.h"
#include "test_support.h"

namespace csgtile::geo {
namespace {

namespace fs = std::filesystem;

fs::path copc_file() { return test::shared_dir() / "data" / "laz" / "1.2-with-color.copc.laz"; }

#define SKIP_WITHOUT_COPC()                                       \
  if (!fs::is_regular_file(copc_file())) {                        \
    GTEST_SKIP() << "COPC test file not found at " << copc_file() \
                 << " (see ../shared/data/laz/README.md)";        \
  }

std::vector<std::uint8_t> file_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Bytes in memory that count what is read of them.
class CountingSource final : public ByteSource {
 public:
  CountingSource(std::vector<std::uint8_t> bytes, std::uint64_t* read)
      : ByteSource("counted.copc.laz"), bytes_(std::move(bytes)), read_(read) {}
  std::uint64_t size() const override { return bytes_.size(); }
  kernel::Status read_at(std::uint64_t offset, std::span<std::uint8_t> out) override {
    if (offset > bytes_.size() || out.size() > bytes_.size() - offset) {
      return kernel::Status(kernel::ErrorCode::CorruptData, "past the end");
    }
    std::memcpy(out.data(), bytes_.data() + offset, out.size());
    *read_ += out.size();
    return kernel::Status();
  }

 private:
  std::vector<std::uint8_t> bytes_;
  std::uint64_t* read_;
};

using Xyz = std::tuple<double, double, double>;

std::vector<Xyz> all_points(PointReader& reader) {
  std::vector<Xyz> out;
  PointBatch batch;
  for (;;) {
    auto n = reader.read(batch, 100);
    EXPECT_TRUE(n.ok()) << n.error().message;
    if (!n.ok() || n.value() == 0) break;
    for (const Point& p : batch.points) out.emplace_back(p.x, p.y, p.z);
  }
  std::sort(out.begin(), out.end());
  return out;
}

TEST(Copc, HierarchyHoldsEveryPointInItsNodesCube) {
  SKIP_WITHOUT_COPC();
  auto reader = LasReader::open(copc_file());
  ASSERT_TRUE(reader.ok()) << reader.error().message;
  ASSERT_TRUE(reader.value()->copc().has_value());
  auto nodes = reader.value()->copc_hierarchy();
  ASSERT_TRUE(nodes.ok()) << nodes.error().message;
  std::uint64_t total = 0;
  int deepest = 0;
  for (const CopcNode& n : nodes.value()) {
    total += n.points;
    deepest = std::max(deepest, n.depth);
  }
  EXPECT_EQ(total, reader.value()->header().point_count);
  EXPECT_GT(deepest, 0);
  // Each node's points lie in its cube: read node by node through depth-limited queries of
  // one node's cube (the points of a region are exactly those of the nodes meeting it).
  const CopcNode& leaf =
      *std::max_element(nodes.value().begin(), nodes.value().end(),
                        [](const CopcNode& a, const CopcNode& b) { return a.depth < b.depth; });
  PointReadOptions options;
  options.region = leaf.bounds;
  auto one = LasReader::open(copc_file(), options);
  ASSERT_TRUE(one.ok()) << one.error().message;
  for (const auto& [x, y, z] : all_points(*one.value())) {
    EXPECT_TRUE(leaf.bounds.contains(x, y, z, {1e-9, 1e-9, 1e-9}));
  }
  // Not a COPC file: a named error.
  auto plain = LasReader::open(test::shared_dir() / "data" / "laz" / "point10.laz");
  ASSERT_TRUE(plain.ok());
  EXPECT_FALSE(plain.value()->copc().has_value());
  EXPECT_FALSE(plain.value()->copc_hierarchy().ok());
}

TEST(Copc, ARegionReadsOnlyTheNodesItMeetsAndGivesEveryPointInside) {
  SKIP_WITHOUT_COPC();
  std::uint64_t full_bytes = 0;
  auto full = LasReader::open_source(
      std::make_unique<CountingSource>(file_bytes(copc_file()), &full_bytes));
  ASSERT_TRUE(full.ok()) << full.error().message;
  const LasHeader h = full.value()->header();
  const auto everything = all_points(*full.value());
  ASSERT_EQ(everything.size(), h.point_count);

  // A quarter of the extent in x and y, all heights.
  Bounds3 region;
  region.min = {h.min[0], h.min[1], -1e300};
  region.max = {h.min[0] + 0.5 * (h.max[0] - h.min[0]), h.min[1] + 0.5 * (h.max[1] - h.min[1]),
                1e300};
  std::vector<Xyz> expected;
  for (const auto& [x, y, z] : everything) {
    if (region.contains(x, y, z, {0, 0, 0})) expected.emplace_back(x, y, z);
  }
  ASSERT_FALSE(expected.empty());
  ASSERT_LT(expected.size(), everything.size());

  PointReadOptions options;
  options.region = region;
  std::uint64_t query_bytes = 0;
  auto query = LasReader::open_source(
      std::make_unique<CountingSource>(file_bytes(copc_file()), &query_bytes), options);
  ASSERT_TRUE(query.ok()) << query.error().message;
  EXPECT_NE(query.value()->info().description.find("octree nodes"), std::string::npos)
      << query.value()->info().description;
  EXPECT_LT(*query.value()->info().point_count, h.point_count);
  EXPECT_EQ(all_points(*query.value()), expected);
  EXPECT_LT(query_bytes, full_bytes) << "a region must not read every chunk";

  // The same region on a plain LAZ (no hierarchy): every point read, the same points kept.
  auto plain_region =
      LasReader::open(test::shared_dir() / "data" / "laz" / "ahn3_cropped_2.laz", options);
  ASSERT_TRUE(plain_region.ok());
  for (const auto& [x, y, z] : all_points(*plain_region.value())) {
    EXPECT_TRUE(region.contains(x, y, z, {0, 0, 0}));
  }
}

TEST(Copc, ADepthLimitReadsTheUpperLevelsOnly) {
  SKIP_WITHOUT_COPC();
  auto reader = LasReader::open(copc_file());
  ASSERT_TRUE(reader.ok());
  auto nodes = reader.value()->copc_hierarchy();
  ASSERT_TRUE(nodes.ok());
  std::uint64_t root_points = 0;
  for (const CopcNode& n : nodes.value()) {
    if (n.depth == 0) root_points += n.points;
  }
  PointReadOptions options;
  options.copc_max_depth = 0;
  auto root = LasReader::open(copc_file(), options);
  ASSERT_TRUE(root.ok()) << root.error().message;
  EXPECT_EQ(all_points(*root.value()).size(), root_points);
}

TEST(Copc, BrokenHierarchiesAreNamedErrors) {
  SKIP_WITHOUT_COPC();
  const auto original = file_bytes(copc_file());
  auto reader = LasReader::open(copc_file());
  ASSERT_TRUE(reader.ok());
  std::uint64_t info_at = 0;
  for (const LasRecord& r : reader.value()->vlrs()) {
    if (r.user_id == "copc" && r.record_id == 1) info_at = r.payload_offset;
  }
  ASSERT_NE(info_at, 0u);
  const auto root = *reader.value()->copc();
  PointReadOptions options;
  options.copc_max_depth = 3;
  auto open_patched = [&](const std::function<void(std::vector<std::uint8_t>&)>& patch) {
    auto bytes = original;
    patch(bytes);
    std::uint64_t read = 0;
    return LasReader::open_source(std::make_unique<CountingSource>(std::move(bytes), &read),
                                  options);
  };
  auto put_u64 = [](std::vector<std::uint8_t>& b, std::uint64_t at, std::uint64_t v) {
    std::memcpy(b.data() + at, &v, 8);
  };
  auto put_i32 = [](std::vector<std::uint8_t>& b, std::uint64_t at, std::int32_t v) {
    std::memcpy(b.data() + at, &v, 4);
  };
  struct Case {
    const char* what;
    std::function<void(std::vector<std::uint8_t>&)> patch;
    const char* message;
  };
  const std::uint64_t page = root.root_hierarchy_offset;
  const std::vector<Case> cases = {
      {"root page size not whole entries",
       [&](auto& b) { put_u64(b, info_at + 48, root.root_hierarchy_size - 5); }, "whole entries"},
      {"root page past the end", [&](auto& b) { put_u64(b, info_at + 40, b.size() + 100); },
       "inside the file"},
      {"zero half size", [&](auto& b) { put_u64(b, info_at + 24, 0); }, "root cube"},
      {"depth out of range", [&](auto& b) { put_i32(b, page, 99); }, "depth"},
      {"cell outside its level", [&](auto& b) { put_i32(b, page + 4, 5); }, "cell index"},
      {"node data past the end", [&](auto& b) { put_u64(b, page + 16, b.size() + 1); },
       "not inside the file"},
      {"node not in the chunk table", [&](auto& b) { put_u64(b, page + 16, 400); },
       "no chunk of the chunk table"},
      {"a page referring to itself",
       [&](auto& b) {
         put_u64(b, page + 16, page);
         put_i32(b, page + 24, static_cast<std::int32_t>(root.root_hierarchy_size));
         put_i32(b, page + 28, -1);
       },
       "loop"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    auto opened = open_patched(c.patch);
    ASSERT_FALSE(opened.ok());
    EXPECT_EQ(opened.error().code, kernel::ErrorCode::CorruptData) << opened.error().message;
    EXPECT_NE(opened.error().message.find("COPC"), std::string::npos) << opened.error().message;
    EXPECT_NE(opened.error().message.find(c.message), std::string::npos) << opened.error().message;
  }
}

}  // namespace
}  // namespace csgtile::geo
