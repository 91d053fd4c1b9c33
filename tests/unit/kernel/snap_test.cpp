// The fuzzy mode for fitted primitives (kernel/snap.h): near-coincidences snapped, nothing
// else moved.

#include "csgtile/kernel/snap.h"

#include <gtest/gtest.h>

#include <array>
#include <numbers>

#include "csgtile/kernel/boolean.h"
#include "csgtile/kernel/check.h"
#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/mass_properties.h"
#include "model_builders.h"

namespace csgtile::kernel {
namespace {

using test::box;
using test::cylinder;
using test::placement_rows;

Location turned(const Vec3& t, const Vec3& axis, double angle) {
  return Location::translation(t) * Location::rotation(Vec3::Zero(), axis, angle);
}

// A fitted column (0.7 mrad off vertical) and a fitted beam whose top lies 0.1 mm under the
// column's top: the two planes cross inside the column's top disc, and the exact fuse meets
// a sliver 0.1 mm thin, its ends crossing the column's rim at grazing angles. The exact fuse
// holds (it failed with free edges until such crossings reused one vertex), its volumes
// adding up; snapped with 5 mm and 0.5°: one direction up, one plane on top, and the fuse is
// one valid solid too.
TEST(Snap, FittedColumnAndBeamFuseOnceSnapped) {
  const auto [column, beam] = test::fitted_column_and_beam();
  const Shape sa = build_primitive(column).value(), sb = build_primitive(beam).value();
  auto exact = boolean_operation(sa, sb, BooleanOp::Fuse);
  ASSERT_TRUE(exact.ok()) << exact.error().message;
  EXPECT_TRUE(check_shape(exact.value()).valid());
  auto common = boolean_operation(sa, sb, BooleanOp::Common);
  ASSERT_TRUE(common.ok()) << common.error().message;
  const double va = mass_properties(sa).volume, vb = mass_properties(sb).volume;
  EXPECT_NEAR(mass_properties(exact.value()).volume + mass_properties(common.value()).volume,
              va + vb, 1e-9 * (va + vb));

  SnapReport report;
  auto snapped = snap_primitives({column, beam}, {0.005, 0.5 * std::numbers::pi / 180}, &report);
  ASSERT_TRUE(snapped.ok()) << snapped.error().message;
  const PrimitiveSpec& c = snapped.value()[0];
  const PrimitiveSpec& b = snapped.value()[1];
  const Vec3 up_c = c.placement.rotation().col(2), up_b = b.placement.rotation().col(2);
  EXPECT_EQ(up_c, Vec3::UnitZ());  // both plumb
  EXPECT_EQ(up_b, Vec3::UnitZ());
  const double top_c = up_c.dot(c.placement.translation()) + c.height;
  const double top_b = up_b.dot(b.placement.translation()) + b.size.z();
  EXPECT_NEAR(top_c, top_b, 1e-12);
  EXPECT_EQ(report.planes, 1);
  EXPECT_LE(report.max_move, 0.005);
  EXPECT_LE(report.max_turn, 0.5 * std::numbers::pi / 180);

  auto fused =
      boolean_operation(build_primitive(c).value(), build_primitive(b).value(), BooleanOp::Fuse);
  ASSERT_TRUE(fused.ok()) << fused.error().message;
  EXPECT_TRUE(check_shape(fused.value()).valid());
  EXPECT_EQ(map_child_shapes(fused.value(), ShapeKind::Solid).size(), 1u);
  // Within what the snap moved: the volume of the union changes by at most a few cm³.
  const double before = mass_properties(build_primitive(column).value()).volume +
                        mass_properties(build_primitive(beam).value()).volume;
  EXPECT_LT(mass_properties(fused.value()).volume, before);
  EXPECT_GT(mass_properties(fused.value()).volume, before - 0.05);
}

// A column fitted in two pieces (axes 1 µm and 0.1 mrad apart, radii equal) and a beam at its
// top: the exact fuse of the pieces fails (their sides cross at grazing angles); snapped, the
// pieces share one axis line and the three fuse into one valid solid.
TEST(Snap, ColumnFittedInTwoPiecesIsOneColumn) {
  const std::vector<PrimitiveSpec> pieces = test::fitted_column_in_two_pieces();
  auto exact = boolean_operation(build_primitive(pieces[0]).value(),
                                 build_primitive(pieces[1]).value(), BooleanOp::Fuse);
  EXPECT_FALSE(exact.ok() && check_shape(exact.value()).valid()) << "the exact fuse now holds";
  SnapReport report;
  auto snapped = snap_primitives(pieces, {0.005, 0.5 * std::numbers::pi / 180}, &report);
  ASSERT_TRUE(snapped.ok()) << snapped.error().message;
  const PrimitiveSpec& lower = snapped.value()[0];
  const PrimitiveSpec& upper = snapped.value()[1];
  EXPECT_EQ(report.lines, 1);
  EXPECT_EQ(report.axes_moved, 2);
  EXPECT_EQ(report.radii_snapped, 0);  // equal already
  EXPECT_EQ(upper.placement.rotation().col(2), Vec3::UnitZ());
  EXPECT_EQ(lower.placement.translation().head<2>(), upper.placement.translation().head<2>());
  EXPECT_LE(report.max_move, 0.005);
  std::vector<Shape> solids;
  for (const PrimitiveSpec& p : snapped.value()) solids.push_back(build_primitive(p).value());
  auto fused = boolean_fuse_all(solids);
  ASSERT_TRUE(fused.ok()) << fused.error().message;
  EXPECT_TRUE(check_shape(fused.value()).valid());
  EXPECT_EQ(map_child_shapes(fused.value(), ShapeKind::Solid).size(), 1u);
}

// Coaxial cylinders whose radii differ by less than the distance get one radius; farther
// radii, or axes farther apart than the distance, stay.
TEST(Snap, NearlyEqualCoaxialRadiiBecomeOne) {
  const Location up = Location::translation(Vec3(0, 0, 1));
  const std::vector<PrimitiveSpec> specs = {
      test::cylinder(1.0, 2.0, Location()), test::cylinder(1.0004, 2.0, up),
      test::cylinder(1.5, 2.0, Location::translation(Vec3(0, 0, 2))),
      test::cylinder(1.0, 2.0, Location::translation(Vec3(0.01, 0, 3)))};
  SnapReport report;
  auto snapped = snap_primitives(specs, {0.001, 0.0}, &report);
  ASSERT_TRUE(snapped.ok()) << snapped.error().message;
  EXPECT_EQ(report.lines, 1);
  EXPECT_EQ(report.radii_snapped, 2);
  EXPECT_DOUBLE_EQ(snapped.value()[0].radius, 1.0002);
  EXPECT_DOUBLE_EQ(snapped.value()[1].radius, 1.0002);
  EXPECT_EQ(snapped.value()[2].radius, 1.5);
  EXPECT_EQ(snapped.value()[3].radius, 1.0);
  EXPECT_EQ(snapped.value()[3].placement.translation(), Vec3(0.01, 0, 3));
}

// Beyond the distance or the angle, nothing moves; the two faces of a box thinner than the
// distance stay two faces; a sphere has no axis.
TEST(Snap, LeavesWhatIsNotNearlyCoincident) {
  const double angle = 0.5 * std::numbers::pi / 180;
  const PrimitiveSpec a = box(Vec3(1, 1, 1), Location());
  const PrimitiveSpec far = box(Vec3(1, 1, 1), Location::translation(Vec3(0.5, 0.5, 1.006)));
  const PrimitiveSpec steep = box(Vec3(1, 1, 1), turned(Vec3(3, 0, 0), Vec3::UnitX(), 0.02));
  const PrimitiveSpec thin = box(Vec3(1, 1, 0.003), Location::translation(Vec3(0, 3, 0)));
  PrimitiveSpec ball;
  ball.type = PrimitiveType::Sphere;
  ball.radius = 1;
  ball.placement = Location::translation(Vec3(5, 5, 5));
  auto snapped = snap_primitives({a, far, steep, thin, ball}, {0.005, angle});
  ASSERT_TRUE(snapped.ok());
  const auto& s = snapped.value();
  // `far`'s bottom is 6 mm over a's top: apart. Its x and y faces meet none of a's either.
  EXPECT_EQ(s[1].placement, far.placement);
  EXPECT_EQ(s[1].size, far.size);
  EXPECT_EQ(s[2].placement, steep.placement);  // 1.1° off: its own directions
  EXPECT_NEAR(s[3].size.z(), 0.003, 1e-15);    // thin: its two faces never merge
  EXPECT_EQ(s[4].placement, ball.placement);
  EXPECT_FALSE(snap_primitives({a}, {-1.0, 0.0}).ok());
  EXPECT_FALSE(snap_primitives({a}, {0.0, std::nan("")}).ok());
}

// Five beams fitted from a terrestrial scan of the timber gate (seed 2, issue #20): two end to
// end along x, two along y, one far away. Their directions do not orthogonalise consistently
// (the x beams' axis is made orthogonal to two directions 2.2 degrees apart), so a box's x axis
// lies 0.6 mrad off its direction's mean. The faces' offsets were measured along the mean and
// their moves made along it, so moving the second x beam's end by 15 µm moved its top 9.7 nm
// off its twin's: two faces within the tolerance of each other whose edges had no pcurve on
// the other, and the fuse failed ("the section of a plane and a plane has no exact pcurve").
// Offsets are now measured and moved along each box's own axes.
TEST(Snap, FacesMoveAlongTheirOwnNormals) {
  struct Beam {
    Vec3 size;
    std::array<double, 12> placement;
  };
  const std::vector<Beam> beams = {
      {{3.002442384241886, 0.3356203379960196, 0.19889996029213206},
       {0.00041925383263461324, 0.04387416633757082, 0.9990369771707187, -0.10576068941950476,
        -0.9999995428419282, 0.0008769517069444699, 0.00038114516740632366, 2.9997289160361067,
        -0.0008593847559569589, -0.9990366802494727, 0.04387451394550569, 4.005108621181909}},
      {{2.997236548598229, 0.3066128747038491, 0.20075667191216537},
       {0.9999884560142889, -0.004794153444287578, -0.0003223831748000684, 0.0013143152348438093,
        -0.0002518103336072734, 0.014713929969157387, -0.9998917125651252, 3.0980220462507586,
        0.004798377821165942, 0.9998802510088973, 0.014712552894381895, 3.6914215197412434}},
      {{2.9971863754472783, 0.32635550959796256, 0.20163542120979372},
       {0.0004192538326346131, 0.04387416239036986, 0.9990369773440659, -0.1076979637297317,
        -0.9999995428419277, 0.0008769517054385624, 0.00038114517087116503, -0.002716910736082381,
        -0.0008593847559569586, -0.9990366804228212, 0.04387450999830593, 4.007011073083593}},
      {{3.0015281624587757, 0.29431668572232517, 0.2005671399926436},
       {0.9999884560142891, -0.004794153744173491, -0.00032237871517195877, 2.9984916639912105,
        -0.00025181033360727564, 0.014712999847680793, -0.9998917262519169, 3.097757795582435,
        0.004798377821165942, 0.9998802646944082, 0.014711622783567024, 3.695293945575491}},
      {{2.997743260712004, 0.306569442001463, 0.21555402543604918},
       {0.0004192538326346132, 0.004922349156575578, 0.999987797278049, -12.101160729736808,
        -0.999999542841928, 0.0008614381333479835, 0.0004150184060544253, -9.000391183915454,
        -0.0008593847559569589, -0.9999875141236128, 0.004922708067522985, 4.00142945982584}},
  };
  std::vector<PrimitiveSpec> fitted;
  for (const Beam& b : beams) fitted.push_back(box(b.size, placement_rows(b.placement)));
  auto snapped = snap_primitives(fitted, {0.005, 0.5 * std::numbers::pi / 180});
  ASSERT_TRUE(snapped.ok()) << snapped.error().message;
  const PrimitiveSpec& first = snapped.value()[1];
  const PrimitiveSpec& second = snapped.value()[3];
  // The two x beams: one rotation; their ends meet and their tops are one plane.
  ASSERT_EQ(first.placement.rotation(), second.placement.rotation());
  const Eigen::Matrix3d& r = first.placement.rotation();
  const Vec3 d = second.placement.translation() - first.placement.translation();
  EXPECT_NEAR(d.dot(r.col(0)), first.size.x(), 1e-12);
  EXPECT_NEAR(d.dot(r.col(1)), 0.0, 1e-12);
  EXPECT_NEAR(d.dot(r.col(2)), 0.0, 1e-12);
  std::vector<Shape> solids;
  for (const PrimitiveSpec& p : snapped.value()) solids.push_back(build_primitive(p).value());
  auto fused = boolean_fuse_all({solids[0], solids[1], solids[2], solids[3]});
  ASSERT_TRUE(fused.ok()) << fused.error().message;
  EXPECT_TRUE(check_shape(fused.value()).valid());
}

// Two beams end to end and a beam fitted as a slender cone running into their node (the
// fitted gate, seed 4): snapped, the beams' end faces are one plane. Fused with one beam
// first, the cone then meets the other beam's coincident end face along the edge it has just
// made, which the fuse does not yet survive ("face pieces' boundaries cross"); fused with both
// beams first it meets no end face. A section piece lying along a boundary edge of one face
// is now that edge in the other; and the n-ary fuse takes the left partial result apart into
// the right one where the other way round fails.
TEST(Snap, ConeIntoTwoBeamsEndToEndFusesInEveryOrder) {
  PrimitiveSpec cone;
  cone.type = PrimitiveType::Cone;
  cone.radius = 0.10017057544401194;
  cone.radius2 = 0.2405488152928099;
  cone.height = 2.0301267281829576;
  cone.placement = placement_rows({-0.9974979925731589, -0.0010528628091642836, 0.0706869598470857,
                                   -9.003787101861061, -0.0706948004631064, 0.014855810211168134,
                                   -0.9973873621068452, -9.879500322509044, 0.0,
                                   -0.9998890920411496, -0.014893072789896942, 3.8166311922937064});
  const PrimitiveSpec first =
      box(Vec3(2.99715097763713, 0.3813512881283503, 0.19837187206383017),
          placement_rows({0.9999988558607431, 0.0014566956497593746, 0.0004078173473007829,
                          -12.002166481115653, -0.00048654506860725373, 0.05446054933658837,
                          0.9985158045017881, -12.106184513293204, 0.0014323236718707462,
                          -0.9985148604821767, 0.05446119577422078, 3.9976078899442653}));
  const PrimitiveSpec second =
      box(Vec3(3.0065828244493904, 0.2931178585683478, 0.20392432507596028),
          placement_rows({0.999998855860743, -0.0014580483568770316, -0.00040295433214636235,
                          -9.004522833804597, -0.0004865450686072534, -0.057792122946088376,
                          -0.9983285199769066, -11.886018099682834, 0.0014323236718707462,
                          0.9983275738054987, -0.0577927662300896, 3.7161607597206148}));
  // In every order: the section along the edge is that edge (sections.cpp), and where a fuse
  // still fails, the other order is tried (fuse_tree.h).
  for (const auto& order : {std::vector{first, cone, second}, std::vector{cone, second, first},
                            std::vector{cone, first, second}}) {
    auto snapped = snap_primitives(order, {0.005, 0.5 * std::numbers::pi / 180});
    ASSERT_TRUE(snapped.ok()) << snapped.error().message;
    std::vector<Shape> solids;
    for (const PrimitiveSpec& p : snapped.value()) solids.push_back(build_primitive(p).value());
    auto fused = boolean_fuse_all(solids);
    ASSERT_TRUE(fused.ok()) << fused.error().message;
    EXPECT_TRUE(check_shape(fused.value()).valid());
    EXPECT_EQ(map_child_shapes(fused.value(), ShapeKind::Solid).size(), 1u);
  }
}

// A clip plane (a roof) stays where it is in the world while its extrusion turns plumb and its
// base and the ground's top meet.
TEST(Snap, ClipPlanesStayInTheWorld) {
  PrimitiveSpec part;
  part.type = PrimitiveType::Extrusion;
  part.profile = {{0, 0}, {6, 0}, {6, 4}, {0, 4}};
  part.height = 12;
  const Vec3 n = Vec3(0.3, 0.1, 1).normalized();
  part.clips.push_back(Eigen::Vector4d(n.x(), n.y(), n.z(), n.dot(Vec3(3, 2, 8))));
  part.placement = turned(Vec3(10, 0, 0.002), Vec3(1, 1, 0), 0.001);
  const PrimitiveSpec ground = box(Vec3(30, 30, 1), Location::translation(Vec3(0, -10, -1)));
  auto snapped = snap_primitives({part, ground}, {0.005, 0.5 * std::numbers::pi / 180});
  ASSERT_TRUE(snapped.ok());
  const PrimitiveSpec& p = snapped.value()[0];
  const PrimitiveSpec& g = snapped.value()[1];
  EXPECT_EQ(p.placement.rotation().col(2), Vec3::UnitZ());  // plumb: the vertical itself
  EXPECT_EQ(g.placement.rotation(), ground.placement.rotation());
  // The base (after the turn about the part's centre) and the ground's top meet halfway.
  EXPECT_NEAR(p.placement.translation().z(), g.placement.translation().z() + g.size.z(), 1e-12);
  EXPECT_LT(std::abs(p.placement.translation().z()), 0.005);
  EXPECT_NE(p.placement.translation().z(), 0.0);
  // Points of the original roof plane (in the world) lie on the snapped one.
  auto world_plane = [](const PrimitiveSpec& s) {
    const Vec3 normal = s.placement.rotation() * s.clips[0].head<3>();
    return std::pair{normal, s.clips[0].w() + normal.dot(s.placement.translation())};
  };
  const auto [n0, d0] = world_plane(part);
  const auto [n1, d1] = world_plane(p);
  EXPECT_LT((n0 - n1).norm(), 1e-12);
  EXPECT_NEAR(d0, d1, 1e-12);
}

// Three roof parts of a building fitted from points: a tall L-shaped part whose wall runs
// straight from its outer corner to its inner one, and two lower parts beside it whose shared
// corner lies 3 mm outside that wall. Together they leave a slot 3 mm wide through the lower
// parts' height, open to the outside only at the slot's pinched end: the exact union's faces
// touch themselves there. Snapped, the corner is inserted into the tall part's wall, the slot
// closes and the union is one valid solid holding the three parts' volumes.
TEST(Snap, ExtrusionWallsShareTheCornerBesideThem) {
  auto part = [](std::vector<Vec2> profile, double h) {
    PrimitiveSpec p;
    p.type = PrimitiveType::Extrusion;
    p.profile = std::move(profile);
    p.height = h;
    // Turned and moved, so that the parts' corners meet only through their placements.
    p.placement = turned(Vec3(85012.5, 447461.25, 1.38), Vec3::UnitZ(), 0.7224);
    return p;
  };
  const std::vector<PrimitiveSpec> parts{
      part({{0, 0}, {10, 0}, {10, 10}, {14, 10}, {14, 14}, {0, 14}}, 10.0),
      part({{10, 0}, {20, 0}, {20, 5}, {10.003, 5}}, 8.0),
      part({{10.003, 5}, {20, 5}, {20, 10}, {10, 10}}, 9.0)};
  auto fuse = [](const std::vector<PrimitiveSpec>& specs) {
    std::vector<Shape> shapes;
    for (const PrimitiveSpec& p : specs) shapes.push_back(build_primitive(p).value());
    return boolean_fuse_all(shapes);
  };
  auto exact = fuse(parts);
  EXPECT_TRUE(!exact.ok() || !check_shape(exact.value()).valid())
      << "the slot's pinched end makes the exact union's faces touch themselves";

  SnapReport report;
  auto snapped = snap_primitives(parts, {0.005, 0.5 * std::numbers::pi / 180}, &report);
  ASSERT_TRUE(snapped.ok()) << snapped.error().message;
  EXPECT_EQ(snapped.value()[0].profile.size(), 7u);  // the corner inserted into its wall
  EXPECT_EQ(snapped.value()[1].profile, parts[1].profile);
  // The tall part's inner corner, on the third part's edge, is inserted there too.
  EXPECT_EQ(snapped.value()[2].profile.size(), 5u);
  EXPECT_EQ(report.walls_shared, 2);
  EXPECT_NEAR(report.max_move, 0.003, 1e-9);  // the corner's distance to the straight wall
  auto fused = fuse(snapped.value());
  ASSERT_TRUE(fused.ok()) << fused.error().message;
  const auto check = check_shape(fused.value());
  EXPECT_TRUE(check.valid()) << (check.valid() ? "" : check.issues[0].message);
  // The parts now only touch: the union holds their volumes (the tall one grown by the slot,
  // half of 3 mm by 10 m, 10 m high).
  double parts_volume = 0.0;
  for (const PrimitiveSpec& p : snapped.value()) {
    parts_volume += mass_properties(build_primitive(p).value()).volume;
  }
  EXPECT_NEAR(parts_volume, 1560.15 + 8 * (50 - 0.0075) + 9 * (50 - 0.0075), 1e-6);
  // (Walls placed within the Booleans' tolerance, 1e-7, of 400 m² of walls: 1e-4.)
  EXPECT_NEAR(mass_properties(fused.value()).volume, parts_volume, 1e-4);
}

// A vertex near another extrusion's vertex becomes it; extrusions at other heights, farther
// than the distance, or near a wall only close to its corner keep their profiles bit for bit.
TEST(Snap, ExtrusionWallsLeaveWhatDoesNotMeet) {
  auto part = [](std::vector<Vec2> profile, double z, double h) {
    PrimitiveSpec p;
    p.type = PrimitiveType::Extrusion;
    p.profile = std::move(profile);
    p.height = h;
    p.placement = Location::translation(Vec3(0, 0, z));
    return p;
  };
  const PrimitiveSpec a = part({{0, 0}, {4, 0}, {4, 4}, {0, 4}}, 0, 3);
  const PrimitiveSpec near = part({{4.002, 0.001}, {8, 0}, {8, 4}, {4, 4}}, 0, 3);
  const PrimitiveSpec above = part({{4.002, 0}, {8, 0}, {8, 4}, {4, 4}}, 3.5, 3);
  const PrimitiveSpec far = part({{-4, 0}, {-0.02, 0}, {-0.02, 4}, {-4, 4}}, 0, 3);
  // 3 mm off a's wall but 15 mm from its corner: inserted there, it would leave a 15 mm edge
  // (four snap distances at least are kept).
  const PrimitiveSpec by_corner = part({{4.003, 0.015}, {5, -1}, {5, 1}}, 0, 3);
  SnapReport report;
  auto snapped = snap_primitives({a, near, above, far, by_corner}, {0.005, 0.0}, &report);
  ASSERT_TRUE(snapped.ok()) << snapped.error().message;
  EXPECT_EQ(snapped.value()[0].profile, a.profile);
  EXPECT_EQ(snapped.value()[1].profile[0], Vec2(4, 0));  // onto a's corner
  EXPECT_EQ(snapped.value()[2].profile, above.profile);
  EXPECT_EQ(snapped.value()[3].profile, far.profile);
  EXPECT_EQ(snapped.value()[4].profile, by_corner.profile);
  EXPECT_EQ(report.walls_shared, 1);
}

}  // namespace
}  // namespace csgtile::kernel
