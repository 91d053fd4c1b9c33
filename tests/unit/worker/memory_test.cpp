// The process's resident memory as the work loop reads it (worker/src/ops/memory.h): the peak
// recorded per job and the bound queue.job_memory_mib.

#include "ops/memory.h"

#include <gtest/gtest.h>

#include <cstddef>
#include <cstdint>
#include <memory>

namespace csgtile::worker::ops {
namespace {

constexpr std::uint64_t kMiB = 1024 * 1024;

TEST(Memory, ResidentAndPeakAreReadAndThePeakFollowsAllocations) {
  const auto resident = resident_bytes();
  const auto peak = peak_resident_bytes();
  ASSERT_TRUE(resident && peak) << "no /proc/self/status";
  EXPECT_GT(*resident, 1 * kMiB);
  EXPECT_GE(*peak, *resident);

  // 256 MiB touched page by page: the peak rises by about as much.
  constexpr std::size_t kSize = 256 * kMiB;
  auto block = std::make_unique<volatile char[]>(kSize);
  for (std::size_t i = 0; i < kSize; i += 4096) block[i] = static_cast<char>(i);
  const auto grown = peak_resident_bytes();
  ASSERT_TRUE(grown);
  EXPECT_GE(*grown, *resident + 200 * kMiB);
  block.reset();

  // A reset starts the peak at the resident size of that moment (the job's own peak).
  ASSERT_TRUE(reset_peak_resident());
  const auto after = peak_resident_bytes();
  const auto now = resident_bytes();
  ASSERT_TRUE(after && now);
  EXPECT_LE(*after, *now + 16 * kMiB);
}

}  // namespace
}  // namespace csgtile::worker::ops
