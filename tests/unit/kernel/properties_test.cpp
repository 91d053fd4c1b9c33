// Seeded property tests: placement invariance of primitives and agreement of the access
// algorithms with a brute-force walk.

#include <gtest/gtest.h>

#include <map>

#include "csgtile/kernel/check.h"
#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/mass_properties.h"
#include "random_shapes.h"

namespace csgtile::kernel {
namespace {

constexpr std::uint64_t kSeed = 20261122;

// All (sub-shape, ancestor) pairs by recursion over the whole tree, without any index.
void brute_walk(const Shape& s, std::vector<Shape>& path,
                std::vector<std::pair<Shape, std::vector<Shape>>>& out) {
  out.emplace_back(s, path);
  path.push_back(s);
  for (const Shape& c : s.children()) brute_walk(c, path, out);
  path.pop_back();
}

TEST(Property, SimilarityScalesVolumeByCubeAndKeepsCounts) {
  std::mt19937_64 rng(kSeed);
  for (int i = 0; i < 300; ++i) {
    const auto type = static_cast<PrimitiveType>(i % kPrimitiveTypeCount);
    PrimitiveSpec spec = test::random_primitive(rng, type);
    auto local = build_primitive(spec);
    ASSERT_TRUE(local.ok()) << "case " << i << ": " << local.error().message;
    spec.placement = test::random_similarity(rng);
    auto placed = build_primitive(spec);
    ASSERT_TRUE(placed.ok());
    const double s = spec.placement.scale();
    const MassProperties a = mass_properties(local.value()), b = mass_properties(placed.value());
    EXPECT_NEAR(b.volume, a.volume * s * s * s, 1e-11 * b.volume) << "case " << i;
    EXPECT_NEAR(b.area, a.area * s * s, 1e-11 * b.area) << "case " << i;
    EXPECT_TRUE(b.centroid.isApprox(spec.placement.apply_point(a.centroid), 1e-9)) << "case " << i;
    EXPECT_EQ(count_shapes(local.value()), count_shapes(placed.value())) << "case " << i;
    const CheckReport report = check_shape(placed.value());
    EXPECT_TRUE(report.valid()) << "case " << i << " (" << primitive_type_name(type)
                                << "): " << (report.valid() ? "" : report.issues.front().message);
  }
}

TEST(Property, ExplorerChildMapAndAncestorsAgreeWithBruteForce) {
  std::mt19937_64 rng(kSeed + 1);
  for (int i = 0; i < 40; ++i) {
    std::vector<Shape> solids;
    for (int k = 0; k < 3; ++k) {
      PrimitiveSpec spec =
          test::random_primitive(rng, static_cast<PrimitiveType>((i + k) % kPrimitiveTypeCount));
      spec.placement = test::random_similarity(rng);
      solids.push_back(build_primitive(spec).value());
    }
    solids.push_back(solids[0]);  // the same solid twice: shared, counted once
    const Shape root = ShapeFactory::compound(solids).value();
    std::vector<Shape> path;
    std::vector<std::pair<Shape, std::vector<Shape>>> all;
    brute_walk(root, path, all);
    for (int kind = 0; kind < kShapeKindCount; ++kind) {
      const auto k = static_cast<ShapeKind>(kind);
      std::vector<Shape> expected;
      for (const auto& [s, p] : all) {
        if (s.kind() == k) expected.push_back(s);
      }
      // The explorer does not descend below a found shape; no kind nests in itself here
      // except the root compound, so the brute-force list equals the explorer's.
      std::vector<Shape> explored;
      for (const Shape& s : Explorer(root, k)) explored.push_back(s);
      ASSERT_EQ(explored.size(), expected.size()) << shape_kind_name(k);
      for (std::size_t j = 0; j < explored.size(); ++j) EXPECT_EQ(explored[j], expected[j]);
      const ShapeIndex map = map_child_shapes(root, k);
      std::size_t distinct = 0;
      for (std::size_t j = 0; j < expected.size(); ++j) {
        bool seen = false;
        for (std::size_t m = 0; m < j && !seen; ++m) seen = expected[m].is_same(expected[j]);
        distinct += !seen;
        EXPECT_NE(map.find(expected[j]), ShapeIndex::npos);
      }
      EXPECT_EQ(map.size(), distinct) << shape_kind_name(k);
    }
    // Ancestor index vertex -> faces against the brute-force paths.
    AncestorIndex index(root, ShapeKind::Vertex, ShapeKind::Face);
    std::map<std::size_t, std::vector<Shape>> expected;
    for (const auto& [s, p] : all) {
      if (s.kind() != ShapeKind::Vertex) continue;
      for (const Shape& a : p) {
        if (a.kind() != ShapeKind::Face) continue;
        auto& list = expected[index.keys().find(s)];
        bool dup = false;
        for (const Shape& e : list) dup = dup || e.is_same(a);
        if (!dup) list.push_back(a);
      }
    }
    ASSERT_EQ(expected.size(), index.size());
    for (const auto& [key, list] : expected) {
      ASSERT_NE(key, ShapeIndex::npos);
      ASSERT_EQ(index.ancestors(key).size(), list.size());
      for (const Shape& a : list) {
        bool found = false;
        for (const Shape& b : index.ancestors(key)) found = found || b.is_same(a);
        EXPECT_TRUE(found);
      }
    }
  }
}

}  // namespace
}  // namespace csgtile::kernel
