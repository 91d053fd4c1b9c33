// Cooperative cancellation of the Booleans (kernel/interrupt.h): a fired interrupt stops an
// operation with Cancelled, naming why and where; an unfired one changes nothing.

#include "csgtile/kernel/interrupt.h"

#include <gtest/gtest.h>

#include <stop_token>
#include <vector>

#include "csgtile/kernel/boolean.h"
#include "csgtile/kernel/csg.h"
#include "csgtile/kernel/mass_properties.h"
#include "model_builders.h"

namespace csgtile::kernel {
namespace {

// A row of overlapping boxes: a fuse of several steps.
std::vector<Shape> row_of_boxes(int n) {
  std::vector<Shape> out;
  for (int i = 0; i < n; ++i) {
    out.push_back(build_primitive(test::box_at({0.6 * i, 0.1 * (i % 3), 0}, {1, 1, 1})).value());
  }
  return out;
}

TEST(Interrupt, ADefaultOneNeverFires) {
  const Interrupt never;
  EXPECT_FALSE(never.fired());
  EXPECT_TRUE(never.check("anywhere").ok());
  EXPECT_FALSE(never.within(0).deadline.has_value());
  EXPECT_FALSE(never.within(-1).deadline.has_value());
}

TEST(Interrupt, AStopRequestCancelsABooleanAndNamesIt) {
  std::stop_source source;
  BooleanOptions options;
  options.interrupt.stop = source.get_token();
  const auto boxes = row_of_boxes(2);
  auto before = boolean_operation(boxes[0], boxes[1], BooleanOp::Fuse, options);
  ASSERT_TRUE(before.ok()) << before.error().message;  // not fired: the operation as ever
  source.request_stop();
  auto after = boolean_operation(boxes[0], boxes[1], BooleanOp::Fuse, options);
  ASSERT_FALSE(after.ok());
  EXPECT_EQ(after.error().code, ErrorCode::Cancelled);
  EXPECT_STREQ(error_code_name(after.error().code), "cancelled");
  EXPECT_NE(after.error().message.find("stopped on request"), std::string::npos)
      << after.error().message;
  EXPECT_NE(after.error().message.find("boolean fuse"), std::string::npos) << after.error().message;
  auto interference = solid_interference(boxes[0], boxes[1], options);
  ASSERT_FALSE(interference.ok());
  EXPECT_EQ(interference.error().code, ErrorCode::Cancelled);
}

// A deadline already passed: the n-ary fuse stops at its first pair instead of retrying the
// tree's halves one by one (each would be cancelled again).
TEST(Interrupt, APassedDeadlineCancelsTheNaryFuseAtOnce) {
  BooleanOptions options;
  options.interrupt = Interrupt{}.within(1e-9);
  EXPECT_DOUBLE_EQ(options.interrupt.limit_seconds, 1e-9);
  const auto boxes = row_of_boxes(16);
  auto fused = boolean_fuse_all(boxes, options);
  ASSERT_FALSE(fused.ok());
  EXPECT_EQ(fused.error().code, ErrorCode::Cancelled);
  EXPECT_NE(fused.error().message.find("time limit of 1e-09 s reached"), std::string::npos)
      << fused.error().message;
  std::vector<CsgModel> leaves;
  for (int i = 0; i < 4; ++i) {
    leaves.push_back(test::leaf(test::box_at({0.6 * i, 0, 0}, {1, 1, 1}), "b" + std::to_string(i)));
  }
  auto combined = csg_combine(leaves, BooleanOp::Fuse, options);
  ASSERT_FALSE(combined.ok());
  EXPECT_EQ(combined.error().code, ErrorCode::Cancelled);
  // A generous limit: the same fuse, the same volume as without one.
  options.interrupt = Interrupt{}.within(3600);
  auto limited = boolean_fuse_all(boxes, options);
  auto free = boolean_fuse_all(boxes, BooleanOptions{});
  ASSERT_TRUE(limited.ok() && free.ok());
  EXPECT_DOUBLE_EQ(mass_properties(limited.value()).volume, mass_properties(free.value()).volume);
}

// The earlier deadline holds when limits are combined.
TEST(Interrupt, WithinKeepsTheEarlierDeadline) {
  const Interrupt outer = Interrupt{}.within(10);
  const Interrupt inner = outer.within(3600);
  ASSERT_TRUE(inner.deadline.has_value());
  EXPECT_EQ(*inner.deadline, *outer.deadline);
  EXPECT_DOUBLE_EQ(inner.limit_seconds, 10);
  const Interrupt shorter = outer.within(1);
  EXPECT_LT(*shorter.deadline, *outer.deadline);
  EXPECT_DOUBLE_EQ(shorter.limit_seconds, 1);
}

}  // namespace
}  // namespace csgtile::kernel
