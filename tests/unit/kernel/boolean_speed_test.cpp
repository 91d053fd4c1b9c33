// The shortcuts the Boolean engine takes for speed give the answers of the long way: the
// volume-only integration (closed forms in u on planes and cylinders) is mass_properties'
// volume to rounding, and two pcurves whose crossing boxes are apart have no crossing (so
// skipping intersect_pcurves changes nothing).

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "boolean/pcurve_fit.h"
#include "boolean/uv_geometry.h"
#include "csgtile/kernel/boolean.h"
#include "csgtile/kernel/mass_properties.h"
#include "csgtile/kernel/primitives.h"
#include "mass/mass_internal.h"
#include "random_shapes.h"

namespace csgtile::kernel::detail {
namespace {

constexpr std::uint64_t kSeed = 20261122;

// Equal to rounding: relative to the volume, or to the size cubed for a volume near zero.
bool same_volume(double a, double b, double size) {
  return std::abs(a - b) <= 1e-12 * std::max(std::abs(b), size * size * size);
}

TEST(SpeedShortcuts, SolidVolumeIsTheMassPropertiesVolumeToRounding) {
  std::mt19937_64 rng(kSeed);
  int checked = 0;
  for (int type = 0; type < kPrimitiveTypeCount; ++type) {
    for (int k = 0; k < 12; ++k) {
      const PrimitiveSpec spec = test::random_primitive(rng, static_cast<PrimitiveType>(type));
      auto solid = build_primitive(spec);
      ASSERT_TRUE(solid.ok()) << solid.error().message;
      // The identity location (the engine's results) and a random similarity.
      for (const Shape& s : {solid.value(), solid.value().moved(test::random_similarity(rng))}) {
        const MassProperties mp = mass_properties(s);
        const double expected = mp.volume;
        EXPECT_TRUE(same_volume(solid_volume(s), expected, mp.bounds.size().norm()))
            << primitive_type_name(static_cast<PrimitiveType>(type)) << " " << k << ": "
            << solid_volume(s) << " vs " << expected;
        ++checked;
      }
    }
  }
  // Boolean results: trimmed planes and cylinders with section pcurves.
  auto box = make_box(4, 3, 2);
  auto column = make_cylinder(0.7, 5);
  ASSERT_TRUE(box.ok() && column.ok());
  for (const BooleanOp op : {BooleanOp::Fuse, BooleanOp::Common, BooleanOp::Cut}) {
    auto r = boolean_operation(box.value(),
                               column.value().moved(Location::translation(Vec3(1.5, 1.2, -1))), op);
    ASSERT_TRUE(r.ok()) << r.error().message;
    const MassProperties mp = mass_properties(r.value());
    EXPECT_TRUE(same_volume(solid_volume(r.value()), mp.volume, mp.bounds.size().norm()))
        << boolean_op_name(op);
    ++checked;
  }
  EXPECT_EQ(checked, kPrimitiveTypeCount * 24 + 3);
}

// A random pcurve of each kind over a parameter range, near the unit square.
struct TestCurve {
  Curve2dPtr curve;
  double t0, t1;
};

TestCurve random_curve(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  auto point = [&] { return Vec2(u(rng), u(rng)); };
  switch (rng() % 4) {
    case 0:
      return {std::make_shared<Line2d>(point(), point()), 0.0, 1.0 + u(rng) * 0.5};
    case 1: {
      const double a = std::numbers::pi * u(rng);
      return {std::make_shared<Circle2d>(point(), 0.1 + 0.5 * std::abs(u(rng)), rng() % 2 ? 1 : -1),
              a, a + 0.3 + 2.0 * std::abs(u(rng))};
    }
    case 2: {
      const double a = std::numbers::pi * u(rng);
      return {std::make_shared<Trig2d>(point(), 0.4 * point(), 0.4 * point(), 0.1 * point()), a,
              a + 0.3 + 2.0 * std::abs(u(rng))};
    }
    default: {
      std::vector<Vec2> points{point()};
      const int n = 2 + static_cast<int>(rng() % 20);
      for (int i = 0; i < n; ++i) points.push_back(points.back() + 0.2 * point());
      return {std::make_shared<Polyline2d>(std::move(points)), 0.0, static_cast<double>(n)};
    }
  }
}

TEST(SpeedShortcuts, CurvesWhoseCrossingBoxesAreApartDoNotCross) {
  std::mt19937_64 rng(kSeed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int apart = 0, near = 0, crossing = 0;
  for (int k = 0; k < 4000; ++k) {
    const TestCurve a = random_curve(rng), b = random_curve(rng);
    // Shifts from far away down to the boxes just touching (where the cull must hold back),
    // some by whole periods as the engine shifts boundary uses.
    const double reach =
        std::array<double, 4>{3.0, 1.0, 0.3, 1e-6}[static_cast<std::size_t>(k % 4)];
    const Vec2 shift = k % 8 == 0 ? Vec2(2 * std::numbers::pi * std::round(2 * u(rng)), 0.0)
                                  : Vec2(reach * u(rng), reach * u(rng));
    const double tolerance = k % 3 == 0 ? 1e-3 : 1e-9;
    const CrossingBox box_a = crossing_box(*a.curve, a.t0, a.t1);
    const CrossingBox box_b = crossing_box(*b.curve, b.t0, b.t1);
    const Curve2dPtr shifted = shift_pcurve(b.curve, shift);
    const auto crossings = intersect_pcurves(*a.curve, a.t0, a.t1, *shifted, b.t0, b.t1, tolerance);
    if (crossing_boxes_apart(box_a, box_b, shift, tolerance)) {
      ++apart;
      EXPECT_TRUE(crossings.empty())
          << "case " << k << ": culled, yet " << crossings.size() << " crossings";
    } else {
      ++near;
      if (!crossings.empty()) ++crossing;
    }
  }
  // The cull is exercised on both sides.
  EXPECT_GT(apart, 500);
  EXPECT_GT(near, 500);
  EXPECT_GT(crossing, 100);
}

TEST(SpeedShortcuts, TwoLinesAreNeverCulled) {
  // A near miss at a line's end is a crossing within the parameter slack; the cull leaves
  // line pairs to intersect_pcurves whatever their boxes.
  const CrossingBox a = crossing_box(Line2d(Vec2(0, 0), Vec2(1, 0)), 0.0, 1.0);
  const CrossingBox b = crossing_box(Line2d(Vec2(5, -1), Vec2(0, 1)), 0.0, 2.0);
  EXPECT_FALSE(crossing_boxes_apart(a, b, Vec2::Zero(), 1e-9));
  const CrossingBox c = crossing_box(Circle2d(Vec2(5, 0), 0.5), 0.0, 2 * std::numbers::pi);
  EXPECT_TRUE(crossing_boxes_apart(a, c, Vec2::Zero(), 1e-9));
  EXPECT_FALSE(crossing_boxes_apart(a, c, Vec2(-4.4, 0), 1e-9));
}

}  // namespace
}  // namespace csgtile::kernel::detail
