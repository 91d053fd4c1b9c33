// Booleans on fitted primitives (issue #20): pairs as the airborne fit makes them, with the
// fit's small tilts and offsets, each a named regression with its numbers as found.

#include <gtest/gtest.h>

#include <numbers>

#include "csgtile/kernel/boolean.h"
#include "csgtile/kernel/check.h"
#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/mass_properties.h"
#include "csgtile/kernel/primitives.h"

namespace csgtile::kernel {
namespace {

// A building's block fitted upside down (its frame's z down, tilted by 5e-5 rad) and a dome's
// drum standing on the terrain through it, its base disc a millimetre inside the block's
// bottom face, its top 0.2 m above the block's top: found fitting a dome on a flat roof.
TEST(BooleanFitted, DrumThroughAFittedBlock) {
  PrimitiveSpec box;
  box.type = PrimitiveType::Box;
  box.size = Vec3(29.9748480244196, 19.97663219324625, 9.9988568294183295);
  Eigen::Matrix3d r;
  r << -0.9999999606151716, -0.0002780654925031989, -3.8068840859828423e-05,
      -0.00027806737983832042, 0.99999996011014802, 4.9580582303532239e-05, 3.805505269218454e-05,
      4.959116605373594e-05, -0.99999999804626438;
  Matrix34 q;
  q << r, Vec3(39.98669440973908, 10.003895965662151, 9.9979221075827613);
  box.placement = Location::from_matrix(q).value();
  PrimitiveSpec drum;
  drum.type = PrimitiveType::Cylinder;
  drum.radius = 3.9989129024205954;
  drum.height = 10.201863070013735;
  drum.placement = Location::translation(Vec3(25.000177159694839, 19.99786986336342, 0));
  const Shape a = build_primitive(box).value(), b = build_primitive(drum).value();
  const double va = mass_properties(a).volume, vb = mass_properties(b).volume;
  const auto fused = boolean_operation(a, b, BooleanOp::Fuse);
  ASSERT_TRUE(fused.ok()) << fused.error().message;
  EXPECT_TRUE(check_shape(fused.value()).valid());
  const auto common = boolean_operation(a, b, BooleanOp::Common);
  ASSERT_TRUE(common.ok()) << common.error().message;
  EXPECT_NEAR(mass_properties(fused.value()).volume + mass_properties(common.value()).volume,
              va + vb, 1e-9 * (va + vb));
}

}  // namespace
}  // namespace csgtile::kernel
