// Relations classified once (city/relation_records.h, IndexOptions::cell_relations):
// pairs inside a cell come from the cell's record, pairs across cells are classified by the
// run's index, and the record round-trips whichever way its ids come.

#include "city/relation_records.h"

#include <gtest/gtest.h>

#include "index_object_builder.h"
#include "model_builders.h"
#include "test_support.h"

namespace csgtile::worker::city::detail {
namespace {

using kernel::Vec3;

// Three unit boxes in a row along x, each touching the next on a 1 m² face: a and b in cell
// c0, c in cell c1.
std::vector<IndexObject> row_of_three() {
  std::vector<IndexObject> out;
  const char* cells[] = {"c0", "c0", "c1"};
  for (int i = 0; i < 3; ++i) {
    const std::string id(1, static_cast<char>('a' + i));
    out.push_back(test::index_object(
        id, test::leaf(test::box_at(Vec3(i, 0, 0), Vec3(1, 1, 1)), id + "-box")));
    out.back().cell = cells[i];
  }
  return out;
}

std::map<std::string, double> touching(const std::filesystem::path& index, const char* id) {
  auto reader = TopologyIndexReader::open(index);
  EXPECT_TRUE(reader.ok());
  std::map<std::string, double> out;
  auto rows = reader.value()->relations(id);
  EXPECT_TRUE(rows.ok());
  for (const RelationRow& r : rows.value()) {
    EXPECT_EQ(r.relation, "touches");
    out[r.other_id] = r.shared_area.value_or(-1.0);
  }
  return out;
}

TEST(CellRelations, PairsInsideACellAreTakenPairsAcrossCellsAreClassified) {
  test::TempDir dir("csgtile_cell_relations_");
  const std::vector<IndexObject> objects = row_of_three();

  IndexOptions classify_all;
  IndexStats stats;
  ASSERT_TRUE(write_topology_index(dir.path() / "all.gpkg", objects, classify_all, &stats).ok());
  ASSERT_EQ(stats.relation_pairs.size(), 2u);
  EXPECT_NEAR(touching(dir.path() / "all.gpkg", "b")["a"], 1.0, 1e-9);
  EXPECT_NEAR(touching(dir.path() / "all.gpkg", "b")["c"], 1.0, 1e-9);

  // The cell's record says a–b share 0.75 m² (a marker no Boolean of these boxes gives): the
  // index takes it as given, and classifies b–c itself.
  ObjectRelation ab;
  ab.a = 0;
  ab.b = 1;
  ab.kind = RelationKind::Touches;
  ab.shared_area = 0.75;
  const ordered_json record = {{"cell", "c0"}, {"relations", relations_json({ab}, objects)}};
  std::map<std::string, std::size_t> index_of;
  // The run holds the objects in another order: the record's ids decide.
  const std::vector<IndexObject> run = {objects[2], objects[1], objects[0]};
  for (std::size_t i = 0; i < run.size(); ++i) index_of[run[i].id] = i;
  std::vector<ObjectRelation> known;
  bool found = false;
  ASSERT_TRUE(read_relations(record, index_of, known, found).ok());
  ASSERT_TRUE(found);
  ASSERT_EQ(known.size(), 1u);
  EXPECT_EQ(known[0].a, 1u);  // b, then a: a < b in the run's order
  EXPECT_EQ(known[0].b, 2u);

  IndexOptions reuse;
  reuse.cell_relations = known;
  ASSERT_TRUE(write_topology_index(dir.path() / "reuse.gpkg", run, reuse, &stats).ok());
  ASSERT_EQ(stats.relation_pairs.size(), 2u);
  EXPECT_LT(std::pair(stats.relation_pairs[0].a, stats.relation_pairs[0].b),
            std::pair(stats.relation_pairs[1].a, stats.relation_pairs[1].b));
  const auto of_b = touching(dir.path() / "reuse.gpkg", "b");
  EXPECT_EQ(of_b.at("a"), 0.75);
  EXPECT_NEAR(of_b.at("c"), 1.0, 1e-9);

  // A record without relations (an older worker) says so; a malformed one fails by name.
  const ordered_json older = {{"cell", "c0"}};
  ASSERT_TRUE(read_relations(older, index_of, known, found).ok());
  EXPECT_FALSE(found);
  ordered_json broken = record;
  broken["relations"][0]["a"] = "nobody";
  const Failure f = read_relations(broken, index_of, known, found);
  EXPECT_EQ(f.code, ErrorCode::Internal);
  EXPECT_NE(f.message.find("nobody"), std::string::npos) << f.message;
}

}  // namespace
}  // namespace csgtile::worker::city::detail
