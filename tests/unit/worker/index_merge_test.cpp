// A run's topology index merged from its cells' indexes (merge_topology_indexes) holds what
// write_topology_index writes for all the objects at once: every table row for row, ids
// offset, the primitives' placements moved into the run's frame, coordinates in the SRS equal
// to rounding.

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "csgtile/kernel/boolean.h"
#include "csgtile/kernel/csg.h"
#include "export/index_rows.h"
#include "export/topology_index.h"
#include "index_object_builder.h"
#include "model_builders.h"
#include "test_commands.h"
#include "test_support.h"

namespace csgtile::worker {
namespace {

using kernel::Vec3;
namespace fs = std::filesystem;

const Vec3 kOrigin(155000, 463000, 0);  // the run frame's origin in the SRS
const Vec3 kCellB(50, 0, 0);            // cell b's frame origin in the run frame

// Objects in the run frame, in cells a and b: a row of two houses on the border (touching),
// a drilled block and a post in a, a box in a box in b.
std::vector<IndexObject> run_objects() {
  using test::box_at;
  using test::leaf;
  std::vector<IndexObject> out;
  auto add = [&out](const std::string& id, const std::string& cell, kernel::CsgModel m) {
    out.push_back(test::index_object(id, std::move(m)));
    out.back().cell = cell;
  };
  auto drilled = kernel::csg_boolean(leaf(box_at({5, 0, 0}, {3, 2, 2}), "block"),
                                     leaf(test::cylinder_at({6.5, 1, -1}, 0.5, 4), "hole"),
                                     kernel::BooleanOp::Cut);
  EXPECT_TRUE(drilled.ok());
  add("drilled", "a", std::move(drilled).value());
  add("post", "a", leaf(test::cylinder_at({20, 1, 0}, 0.5, 3), "post"));
  add("west", "a", leaf(box_at({46, 0, 0}, {4, 6, 5}), "west"));
  add("east", "b", leaf(box_at({50, 0, 0}, {4, 6, 7}), "east"));
  add("big", "b", leaf(box_at({60, 0, 0}, {4, 4, 4}), "big"));
  add("small", "b", leaf(box_at({61, 1, 1}, {1, 1, 1}), "small"));
  return out;
}

IndexOptions options_with_origin(const Vec3& origin) {
  IndexOptions options;
  options.srs = {28992, "EPSG", 28992, "Amersfoort / RD New", "PROJCS[\"Amersfoort / RD New\"]"};
  options.to_srs = [origin](const Vec3& p) { return Vec3(p + origin); };
  return options;
}

struct Db {
  sqlite3* db = nullptr;
  explicit Db(const fs::path& path) {
    EXPECT_EQ(sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr), SQLITE_OK);
  }
  ~Db() { sqlite3_close(db); }
  Db(const Db&) = delete;
  Db& operator=(const Db&) = delete;
};

std::vector<std::string> tables(sqlite3* db) {
  std::vector<std::string> out;
  sqlite3_stmt* st = nullptr;
  sqlite3_prepare_v2(db, "SELECT name FROM sqlite_master WHERE type = 'table' ORDER BY name", -1,
                     &st, nullptr);
  while (sqlite3_step(st) == SQLITE_ROW) {
    out.emplace_back(reinterpret_cast<const char*>(sqlite3_column_text(st, 0)));
  }
  sqlite3_finalize(st);
  return out;
}

// Every row of every table equal: integers, text and blob sizes exactly, reals (and the
// envelopes of geometry blobs) to 1e-9 of their size. `rows`: the rows compared.
void expect_same_tables(const fs::path& expected, const fs::path& merged, std::size_t& rows) {
  Db a(expected), b(merged);
  const auto names = tables(a.db);
  EXPECT_EQ(names, tables(b.db));
  rows = 0;
  for (const std::string& t : names) {
    if (t.rfind("rtree_", 0) == 0 && t.find("_geom_") != std::string::npos) continue;  // shadow
    const std::string sql = "SELECT * FROM \"" + t + "\" ORDER BY rowid";
    sqlite3_stmt* sa = nullptr;
    sqlite3_stmt* sb = nullptr;
    ASSERT_EQ(sqlite3_prepare_v2(a.db, sql.c_str(), -1, &sa, nullptr), SQLITE_OK) << t;
    EXPECT_EQ(sqlite3_prepare_v2(b.db, sql.c_str(), -1, &sb, nullptr), SQLITE_OK) << t;
    for (;;) {
      const int ra = sqlite3_step(sa), rb = sqlite3_step(sb);
      EXPECT_EQ(ra, rb) << t;
      if (ra != SQLITE_ROW || rb != SQLITE_ROW) break;
      ++rows;
      for (int c = 0; c < sqlite3_column_count(sa); ++c) {
        const int type = sqlite3_column_type(sa, c);
        ASSERT_EQ(type, sqlite3_column_type(sb, c)) << t << " column " << c;
        if (type == SQLITE_FLOAT || (t.rfind("rtree_", 0) == 0 && c > 0)) {
          const double x = sqlite3_column_double(sa, c), y = sqlite3_column_double(sb, c);
          EXPECT_NEAR(x, y, 1e-9 * std::max(1.0, std::abs(x))) << t << " column " << c;
        } else if (type == SQLITE_BLOB) {
          const int n = sqlite3_column_bytes(sa, c);
          ASSERT_EQ(n, sqlite3_column_bytes(sb, c)) << t;
          ASSERT_GE(n, 56) << t;
          const auto* pa = static_cast<const unsigned char*>(sqlite3_column_blob(sa, c));
          const auto* pb = static_cast<const unsigned char*>(sqlite3_column_blob(sb, c));
          EXPECT_EQ(std::memcmp(pa, pb, 8), 0) << t;  // "GP", version, flags, srs_id
          for (int k = 0; k < 6; ++k) {               // the envelope
            double x = 0.0, y = 0.0;
            std::memcpy(&x, pa + 8 + 8 * k, 8);
            std::memcpy(&y, pb + 8 + 8 * k, 8);
            EXPECT_NEAR(x, y, 1e-9 * std::max(1.0, std::abs(x))) << t;
          }
        } else if (type != SQLITE_NULL) {
          const std::string x = reinterpret_cast<const char*>(sqlite3_column_text(sa, c));
          const std::string y = reinterpret_cast<const char*>(sqlite3_column_text(sb, c));
          EXPECT_EQ(x, y) << t << " column " << c;
        }
      }
    }
    sqlite3_finalize(sa);
    sqlite3_finalize(sb);
  }
}

TEST(IndexMerge, CellsMergedHoldWhatTheRunsIndexBuiltAgainHolds) {
  const test::TempDir dir("csgtile-index-merge-");
  const std::vector<IndexObject> objects = run_objects();

  // The run's index built from all objects at once.
  IndexStats built_stats;
  ASSERT_TRUE(
      write_topology_index(dir / "built.gpkg", objects, options_with_origin(kOrigin), &built_stats)
          .ok());
  // Each cell's index, written in the cell's frame (b's objects moved by -kCellB).
  std::vector<IndexObject> a(objects.begin(), objects.begin() + 3);
  std::vector<IndexObject> b(objects.begin() + 3, objects.end());
  for (IndexObject& o : b) move_model(o.model, kernel::Location::translation(-kCellB));
  ASSERT_TRUE(write_topology_index(dir / "a.gpkg", a, options_with_origin(kOrigin)).ok());
  ASSERT_TRUE(write_topology_index(dir / "b.gpkg", b, options_with_origin(kOrigin + kCellB)).ok());

  IndexStats merged_stats;
  const Failure merged = merge_topology_indexes(
      dir / "merged.gpkg", {{dir / "a.gpkg", Vec3::Zero()}, {dir / "b.gpkg", kCellB}}, objects,
      options_with_origin(kOrigin), &merged_stats);
  ASSERT_TRUE(merged.ok()) << merged.message;
  std::size_t rows = 0;
  expect_same_tables(dir / "built.gpkg", dir / "merged.gpkg", rows);
  EXPECT_GT(rows, 500u);  // every table compared, not an empty one
  EXPECT_EQ(merged_stats.objects, built_stats.objects);
  EXPECT_EQ(merged_stats.shapes, built_stats.shapes);
  EXPECT_EQ(merged_stats.children, built_stats.children);
  EXPECT_EQ(merged_stats.ancestors, built_stats.ancestors);
  EXPECT_EQ(merged_stats.csg_nodes, built_stats.csg_nodes);
  EXPECT_EQ(merged_stats.primitives, built_stats.primitives);
  // The party wall across the cells and the box in the box.
  EXPECT_EQ(merged_stats.relations, 2u);
  EXPECT_EQ(merged_stats.relations, built_stats.relations);

  // GDAL's own GeoPackage validator on the merged file (deploy/setup.sh installs it).
  const char* validator = "/usr/lib/python3/dist-packages/osgeo_utils/samples/validate_gpkg.py";
  if (fs::exists(validator)) {
    const test::CommandResult r = test::run_command(
        std::string("/usr/bin/python3 ") + validator + " " + test::quoted(dir / "merged.gpkg"),
        false);
    EXPECT_EQ(r.exit_code, 0) << r.out;
  } else if (const char* require = std::getenv("CSGTILE_REQUIRE_GDAL");
             require != nullptr && std::string(require) == "1") {
    ADD_FAILURE() << validator << " not installed; run deploy/setup.sh";
  }
}

// write_topology_index streams: each object's rows built on the threads and written in
// order as they come. The file holds what all the rows written at once hold, and its bytes
// do not depend on the thread count.
TEST(IndexStream, StreamedIndexHoldsTheRowsWrittenAtOnceForAnyThreadCount) {
  const test::TempDir dir("csgtile-index-stream-");
  const std::vector<IndexObject> objects = run_objects();
  IndexOptions options = options_with_origin(kOrigin);
  IndexStats all_stats;
  const auto rows = detail::build_index_rows(objects, options, all_stats);
  ASSERT_TRUE(rows.ok()) << rows.error().message;
  ASSERT_TRUE(detail::write_gpkg((dir / "at_once.gpkg").string(), rows.value(), options).ok());
  std::string first;
  for (int threads : {1, 2, 4}) {
    options.threads = threads;
    const fs::path streamed = dir / ("streamed_" + std::to_string(threads) + ".gpkg");
    IndexStats stats;
    ASSERT_TRUE(write_topology_index(streamed, objects, options, &stats).ok());
    std::size_t compared = 0;
    expect_same_tables(dir / "at_once.gpkg", streamed, compared);
    EXPECT_GT(compared, 500u);
    EXPECT_EQ(stats.shapes, rows.value().shapes.size());
    EXPECT_EQ(stats.children, rows.value().children.size());
    EXPECT_EQ(stats.ancestors, rows.value().ancestors.size());
    EXPECT_EQ(stats.relations, rows.value().relations.size() / 2);
    const std::string bytes = test::read_file(streamed);
    if (first.empty()) first = bytes;
    EXPECT_EQ(bytes, first) << threads << " threads";
  }
}

TEST(IndexMerge, PartsThatDoNotHoldTheObjectsAreRefusedAndNothingIsWritten) {
  const test::TempDir dir("csgtile-index-merge-");
  const std::vector<IndexObject> objects = run_objects();
  std::vector<IndexObject> a(objects.begin(), objects.begin() + 3);
  ASSERT_TRUE(write_topology_index(dir / "a.gpkg", a, options_with_origin(kOrigin)).ok());
  // The run has six objects; the part holds three.
  const Failure fewer = merge_topology_indexes(
      dir / "merged.gpkg", {{dir / "a.gpkg", Vec3::Zero()}}, objects, options_with_origin(kOrigin));
  EXPECT_EQ(fewer.code, ErrorCode::InputInvalid);
  EXPECT_NE(fewer.message.find("3 objects"), std::string::npos) << fewer.message;
  EXPECT_FALSE(fs::exists(dir / "merged.gpkg"));
  // The same part twice: a duplicate object id.
  const Failure twice = merge_topology_indexes(
      dir / "merged.gpkg", {{dir / "a.gpkg", Vec3::Zero()}, {dir / "a.gpkg", Vec3::Zero()}},
      objects, options_with_origin(kOrigin));
  EXPECT_FALSE(twice.ok());
  EXPECT_FALSE(fs::exists(dir / "merged.gpkg"));
  // A part that is no index.
  {
    std::ofstream junk(dir / "junk.gpkg");
    junk << "not a database";
  }
  const Failure junk = merge_topology_indexes(
      dir / "merged.gpkg", {{dir / "junk.gpkg", Vec3::Zero()}}, a, options_with_origin(kOrigin));
  EXPECT_EQ(junk.code, ErrorCode::Io);
  EXPECT_FALSE(fs::exists(dir / "merged.gpkg"));
  // No temporary left beside the target.
  for (const auto& entry : fs::directory_iterator(dir.path())) {
    EXPECT_EQ(entry.path().filename().string().find("tmp"), std::string::npos) << entry.path();
  }
}

}  // namespace
}  // namespace csgtile::worker
