// The one broad phase (csgtile/kernel/broad_phase.h): exactly the intersecting pairs, sorted.

#include "csgtile/kernel/broad_phase.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>

namespace csgtile::kernel {
namespace {

TEST(BroadPhase, FindsExactlyTheOverlappingBoxes) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0, 100), s(0, 8);
  std::vector<BoundingBox> boxes(400);
  for (auto& b : boxes) {
    const Vec3 p(u(rng), u(rng), u(rng) / 10);
    b.add(p);
    b.add(p + Vec3(s(rng), s(rng), s(rng)));
  }
  boxes[7] = BoundingBox{};  // empty: meets nothing
  boxes[9] = boxes[8];       // equal boxes meet
  std::set<std::pair<std::size_t, std::size_t>> brute;
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    for (std::size_t j = i + 1; j < boxes.size(); ++j) {
      if (boxes[i].intersects(boxes[j])) brute.insert({i, j});
    }
  }
  const auto pairs = overlapping_boxes(boxes);
  const std::set<std::pair<std::size_t, std::size_t>> found(pairs.begin(), pairs.end());
  EXPECT_EQ(found, brute);
  EXPECT_EQ(found.size(), pairs.size());  // each pair once
  EXPECT_TRUE(std::is_sorted(pairs.begin(), pairs.end()));
  EXPECT_TRUE(found.count({8, 9}));
  EXPECT_GT(brute.size(), 50u);
}

TEST(BroadPhase, BoxesThatOnlyTouchMeet) {
  BoundingBox a, b, c;
  a.add(Vec3(0, 0, 0));
  a.add(Vec3(1, 1, 1));
  b.add(Vec3(1, 0, 0));  // shares a's face x = 1
  b.add(Vec3(2, 1, 1));
  c.add(Vec3(2.5, 0, 0));
  c.add(Vec3(3, 1, 1));
  const std::vector<BoundingBox> boxes{a, b, c};
  EXPECT_EQ(overlapping_boxes(boxes), (std::vector<std::pair<std::size_t, std::size_t>>{{0, 1}}));
  EXPECT_TRUE(overlapping_boxes({}).empty());
}

}  // namespace
}  // namespace csgtile::kernel
