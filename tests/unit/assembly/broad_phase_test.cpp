// The broad phase on TBB (csgtile/assembly/broad_phase.h): the kernel sweep's pairs, whatever
// the number of threads.

#include "csgtile/assembly/broad_phase.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <random>

namespace csgtile::assembly {
namespace {

using kernel::BoundingBox;
using kernel::Vec3;

std::vector<BoundingBox> random_boxes(std::size_t n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 400), s(0, 6);
  std::vector<BoundingBox> boxes(n);
  for (auto& b : boxes) {
    const Vec3 p(u(rng), u(rng), u(rng) / 20);
    b.add(p);
    b.add(p + Vec3(s(rng), s(rng), s(rng)));
  }
  return boxes;
}

TEST(ParallelBroadPhase, SamePairsAsTheSweepOnOneTwoAndEightThreads) {
  // Several blocks of sweep positions, equal minimum x across a block boundary, empty boxes.
  std::vector<BoundingBox> boxes = random_boxes(5000, 3);
  for (std::size_t i = 1500; i < 1540; ++i) boxes[i] = boxes[1499];
  boxes[17] = BoundingBox{};
  boxes[4000] = BoundingBox{};
  const auto serial = kernel::overlapping_boxes(boxes);
  ASSERT_GT(serial.size(), 1000u);
  for (int threads : {1, 2, 8}) {
    tbb::task_arena arena(threads);
    std::vector<kernel::BoxPair> parallel;
    arena.execute([&] { parallel = parallel_overlapping_boxes(boxes); });
    EXPECT_EQ(parallel, serial) << threads << " threads";
  }
}

TEST(ParallelBroadPhase, NoBoxesAndFewerBoxesThanABlock) {
  EXPECT_TRUE(parallel_overlapping_boxes({}).empty());
  const std::vector<BoundingBox> boxes = random_boxes(30, 5);
  EXPECT_EQ(parallel_overlapping_boxes(boxes), kernel::overlapping_boxes(boxes));
}

}  // namespace
}  // namespace csgtile::assembly
