// close_point_contacts (geo/fit/src/part_contacts.h): roof partition parts A and B meeting at
// one vertex only, with a part C between them there, fuse into one valid solid once C stands
// over every height both stand at by that vertex (the ISPRS Stuttgart site had four buildings
// whose parts' fuse failed with an edge of four faces this way).

#include <gtest/gtest.h>

#include <vector>

#include "csgtile/kernel/boolean.h"
#include "csgtile/kernel/check.h"
#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/primitives.h"
#include "part_contacts.h"

namespace csgtile::fit {
namespace {

using kernel::Vec2;
using kernel::Vec3;

// An upright extrusion of `ring` from `base` up to `top`, placed at (10, 20) turned by 0.3 rad
// (the ring in the placement's frame).
detail::Proposal part(std::vector<Vec2> ring, double base, double top) {
  detail::Proposal p;
  p.spec.type = kernel::PrimitiveType::Extrusion;
  p.spec.profile = std::move(ring);
  p.spec.height = top - base;
  p.spec.placement = kernel::Location::translation(Vec3(10.0, 20.0, base)) *
                     kernel::Location::rotation(Vec3::Zero(), Vec3::UnitZ(), 0.3);
  return p;
}

// A over [0, 1]², C over [−1, 0] × [0, 1] (sharing the edge x = 0 with A), B over [−1, 0]²
// (sharing y = 0 with C): A and B meet at the origin only, the quarter x > 0, y < 0 is outside.
std::vector<detail::Proposal> wedge(double a_base, double c_base, double c_top) {
  std::vector<detail::Proposal> parts;
  parts.push_back(part({{0, 0}, {1, 0}, {1, 1}, {0, 1}}, a_base, 5.0));      // A
  parts.push_back(part({{0, 0}, {0, 1}, {-1, 1}, {-1, 0}}, c_base, c_top));  // C
  parts.push_back(part({{0, 0}, {-1, 0}, {-1, -1}, {0, -1}}, 0.0, 5.0));     // B
  return parts;
}

// Whether the parts fuse into one valid solid.
bool fuse_valid(const std::vector<detail::Proposal>& parts) {
  std::vector<kernel::Shape> solids;
  for (const auto& p : parts) {
    auto solid = kernel::build_primitive(p.spec, 1e-7);
    if (!solid.ok()) return false;
    solids.push_back(solid.value());
  }
  auto fused = kernel::boolean_fuse_all(solids);
  return fused.ok() && kernel::check_shape(fused.value()).valid() &&
         kernel::map_child_shapes(fused.value(), kernel::ShapeKind::Solid).size() == 1U;
}

TEST(FitPartContacts, APartBetweenTwoMeetingAtAPointReachesDownToTheirBases) {
  // C's base 0.4 above A's and B's: between 0 and 0.4 only A and B stand by the origin.
  auto parts = wedge(0.0, 0.4, 5.0);
  EXPECT_FALSE(fuse_valid(parts));
  EXPECT_EQ(detail::close_point_contacts(parts, 0.4, 0.1), 1);
  EXPECT_NEAR(parts[1].spec.placement.translation().z(), 0.0, 1e-12);
  EXPECT_NEAR(parts[1].spec.height, 5.0, 1e-12);
  EXPECT_TRUE(fuse_valid(parts));
  // Already closed: nothing more to do.
  EXPECT_EQ(detail::close_point_contacts(parts, 0.4, 0.1), 0);
}

TEST(FitPartContacts, AFlatRoofAStepBelowTwoMeetingAtAPointIsRaisedToThem) {
  // C's flat roof 3 cm under theirs: raised.
  auto close = wedge(0.0, 0.0, 4.97);
  EXPECT_FALSE(fuse_valid(close));
  EXPECT_EQ(detail::close_point_contacts(close, 0.4, 0.1), 1);
  EXPECT_NEAR(close[1].spec.height, 5.0, 1e-12);
  EXPECT_TRUE(fuse_valid(close));
  EXPECT_EQ(close[0].spec.profile.size(), 4U);  // no corner cut
}

TEST(FitPartContacts, TwoMeetingAtAPointOverAStoreyBetweenThemNoLongerMeet) {
  // C's flat roof 2 m under theirs: a storey, kept; A's corner at the origin (A and B tie,
  // A comes first) is cut off by 10 cm, and the fuse is one valid solid.
  auto storey = wedge(0.0, 0.0, 3.0);
  EXPECT_FALSE(fuse_valid(storey));
  EXPECT_EQ(detail::close_point_contacts(storey, 0.4, 0.1), 1);
  EXPECT_NEAR(storey[1].spec.height, 3.0, 1e-12);
  const std::vector<Vec2> cut{{0, 0.1}, {0.1, 0}, {1, 0}, {1, 1}, {0, 1}};
  ASSERT_EQ(storey[0].spec.profile.size(), cut.size());
  for (std::size_t i = 0; i < cut.size(); ++i) {
    EXPECT_LT((storey[0].spec.profile[i] - cut[i]).norm(), 1e-15) << i;
  }
  EXPECT_EQ(storey[2].spec.profile.size(), 4U);
  EXPECT_TRUE(fuse_valid(storey));
  EXPECT_EQ(detail::close_point_contacts(storey, 0.4, 0.1), 0);
  // B lower than A at the origin: B's corner is cut instead.
  auto lower_b = wedge(0.0, 0.0, 3.0);
  lower_b[2].spec.height = 4.0;
  EXPECT_EQ(detail::close_point_contacts(lower_b, 0.4, 0.1), 1);
  EXPECT_EQ(lower_b[0].spec.profile.size(), 4U);
  EXPECT_EQ(lower_b[2].spec.profile.size(), 5U);
  EXPECT_TRUE(fuse_valid(lower_b));
}

TEST(FitPartContacts, ClipPlanesStayInPlaceWhenABaseIsLowered) {
  // C cut by the plane z = 4 + 0.1 x (world frame, through the placement): lowering its base
  // keeps the roof where it was.
  auto parts = wedge(0.0, 0.5, 6.0);
  kernel::PrimitiveSpec& c = parts[1].spec;
  const Vec3 n_world = Vec3(-0.1, 0.0, 1.0).normalized();
  const double d_world = n_world.dot(Vec3(10.0, 20.0, 4.0 + 0.1 * 10.0));
  const Vec3 n_local = c.placement.rotation().transpose() * n_world;
  c.clips.push_back(Eigen::Vector4d(n_local.x(), n_local.y(), n_local.z(),
                                    d_world - n_world.dot(c.placement.translation())));
  auto roof_at = [&](const kernel::PrimitiveSpec& s, const Vec3& w) {
    const Vec3 nl(s.clips[0].x(), s.clips[0].y(), s.clips[0].z());
    const Vec3 nw = s.placement.rotation() * nl;
    const double dw = s.clips[0].w() + nw.dot(s.placement.translation());
    return (dw - nw.x() * w.x() - nw.y() * w.y()) / nw.z();
  };
  const Vec3 probe(9.5, 20.5, 0.0);
  const double before = roof_at(c, probe);
  EXPECT_EQ(detail::close_point_contacts(parts, 0.4, 0.1), 1);
  EXPECT_NEAR(c.placement.translation().z(), 0.0, 1e-12);
  EXPECT_NEAR(roof_at(c, probe), before, 1e-9);
}

}  // namespace
}  // namespace csgtile::fit
