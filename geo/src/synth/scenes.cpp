// The scenes `csgtile synth` scans. Dimensions are in metres and meant to be plausible: a
// person looking at the scan should recognise a timber pavilion or a city block.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "csgtile/geo/synth.h"
#include "synth/random.h"
#include "synth/ray_internal.h"

namespace csgtile::geo {

namespace {

using kernel::Location;
using kernel::PrimitiveSpec;
using kernel::PrimitiveType;
using kernel::Vec2;
using kernel::Vec3;

constexpr double kPi = std::numbers::pi;

// The placement as reading its matrix back gives it. Location::from_matrix re-orthonormalises
// the rotation, which may move the last bits; repeating until nothing moves makes the truth
// file's text stable under read → write.
Location settled(const Location& placement) {
  Location current = placement;
  for (int round = 0; round < 8; ++round) {
    auto next = Location::from_matrix(current.matrix());
    if (!next.ok() || next.value().matrix() == current.matrix()) break;
    current = next.value();
  }
  return current;
}

// Collects primitives with their ids and classes.
class SceneBuilder {
 public:
  SceneBuilder(std::string name, std::uint64_t seed) {
    out_.scene.name = std::move(name);
    out_.scene.seed = seed;
  }

  void add(std::string id, PrimitiveSpec spec, std::uint8_t classification = kClassBuilding) {
    ScenePrimitive p;
    p.spec = std::move(spec);
    p.spec.placement = settled(p.spec.placement);
    p.id = std::move(id);
    out_.scene.primitives.push_back(std::move(p));
    out_.classes.push_back(classification);
  }

  SynthScene finish() {
    for (const auto& p : out_.scene.primitives) {
      out_.extent.add(detail::prepare_primitive(p.spec).world_bounds);
    }
    return std::move(out_);
  }

 private:
  SynthScene out_;
};

// An id such as "column-03-07".
std::string id(const char* pattern, int a, int b = 0) {
  char buf[64];
  std::snprintf(buf, sizeof buf, pattern, a, b);
  return buf;
}

PrimitiveSpec box(const Vec3& size, const Location& placement) {
  PrimitiveSpec s;
  s.type = PrimitiveType::Box;
  s.size = size;
  s.placement = placement;
  return s;
}

// An axis-aligned box from its lowest corner.
PrimitiveSpec box_at(const Vec3& corner, const Vec3& size) {
  return box(size, Location::translation(corner));
}

PrimitiveSpec cylinder(const Vec3& base, double r, double h) {
  PrimitiveSpec s;
  s.type = PrimitiveType::Cylinder;
  s.radius = r;
  s.height = h;
  s.placement = Location::translation(base);
  return s;
}

PrimitiveSpec cone(const Location& placement, double r1, double r2, double h) {
  PrimitiveSpec s;
  s.type = PrimitiveType::Cone;
  s.radius = r1;
  s.radius2 = r2;
  s.height = h;
  s.placement = placement;
  return s;
}

PrimitiveSpec sphere(const Location& placement, double r) {
  PrimitiveSpec s;
  s.type = PrimitiveType::Sphere;
  s.radius = r;
  s.placement = placement;
  return s;
}

PrimitiveSpec torus(const Location& placement, double major, double minor) {
  PrimitiveSpec s;
  s.type = PrimitiveType::Torus;
  s.radius = major;
  s.radius2 = minor;
  s.placement = placement;
  return s;
}

PrimitiveSpec extrusion(std::vector<Vec2> profile, std::vector<std::vector<Vec2>> holes, double h,
                        const Location& placement) {
  PrimitiveSpec s;
  s.type = PrimitiveType::Extrusion;
  s.profile = std::move(profile);
  s.holes = std::move(holes);
  s.height = h;
  s.placement = placement;
  return s;
}

PrimitiveSpec revolution(std::vector<Vec2> profile, double angle, const Location& placement) {
  PrimitiveSpec s;
  s.type = PrimitiveType::Revolution;
  s.profile = std::move(profile);
  s.angle = angle;
  s.placement = placement;
  return s;
}

Location rotation_z(double angle) { return Location::rotation(Vec3::Zero(), Vec3::UnitZ(), angle); }
Location rotation_y(double angle) { return Location::rotation(Vec3::Zero(), Vec3::UnitY(), angle); }
Location rotation_x(double angle) { return Location::rotation(Vec3::Zero(), Vec3::UnitX(), angle); }

// The timber gate: a 9 × 9 grid of columns 3 m apart carrying a grid of top beams, stiffened
// by a knee brace at each corner. 81 cylinders and 72 + 72 + 4 = 148 boxes.
SynthScene gate_scene(std::uint64_t seed) {
  SceneBuilder b("gate", seed);
  constexpr int kColumns = 9;
  constexpr double kSpacing = 3.0;
  constexpr double kRadius = 0.15;
  constexpr double kHeight = 4.0;
  constexpr double kBeamWidth = 0.2;
  constexpr double kBeamDepth = 0.3;
  constexpr int kMiddle = (kColumns - 1) / 2;
  auto position = [&](int i) { return (i - kMiddle) * kSpacing; };
  for (int i = 0; i < kColumns; ++i) {
    for (int j = 0; j < kColumns; ++j) {
      b.add(id("column-%02d-%02d", i, j),
            cylinder(Vec3(position(i), position(j), 0.0), kRadius, kHeight));
    }
  }
  // Beams run from column axis to column axis, flush with the column tops.
  const double beam_bottom = kHeight - kBeamDepth;
  for (int j = 0; j < kColumns; ++j) {
    for (int i = 0; i + 1 < kColumns; ++i) {
      b.add(id("beam-x-%02d-%02d", i, j),
            box_at(Vec3(position(i), position(j) - kBeamWidth / 2, beam_bottom),
                   Vec3(kSpacing, kBeamWidth, kBeamDepth)));
    }
  }
  for (int i = 0; i < kColumns; ++i) {
    for (int j = 0; j + 1 < kColumns; ++j) {
      b.add(id("beam-y-%02d-%02d", i, j),
            box_at(Vec3(position(i) - kBeamWidth / 2, position(j), beam_bottom),
                   Vec3(kBeamWidth, kSpacing, kBeamDepth)));
    }
  }
  // Knee braces in the front and back frames, at 45° from the column into the beam.
  constexpr double kBraceLength = 1.5;
  constexpr double kBraceSection = 0.12;
  const double edge = position(kColumns - 1);
  for (int corner = 0; corner < 4; ++corner) {
    const double x = (corner % 2 == 0) ? -edge : edge;
    const double y = (corner < 2) ? -edge : edge;
    const double heading = (corner % 2 == 0) ? 0.0 : kPi;  // towards the middle of the frame
    const Location placement =
        Location::translation(Vec3(x, y, 2.75)) * rotation_z(heading) * rotation_y(-kPi / 4) *
        Location::translation(Vec3(0.0, -kBraceSection / 2, -kBraceSection / 2));
    b.add(id("brace-%d", corner), box(Vec3(kBraceLength, kBraceSection, kBraceSection), placement));
  }
  return b.finish();
}

// Another frame, so that nothing fitted to the gate passes unseen (issue #21): a 6 × 5 grid
// of columns 2.1 m apart (radius 0.12, 3.6 m high), turned 23° about z, carrying top beams of
// 0.12 × 0.30 along both rows flush with the column tops, and ties of the same section at two
// heights (along x at 1.5 m, along y at 2.4 m). 30 cylinders, 25 + 24 top beams and as many
// ties: 98 boxes.
SynthScene frame_scene(std::uint64_t seed) {
  SceneBuilder b("frame", seed);
  constexpr int kAlongX = 6, kAlongY = 5;
  constexpr double kSpacing = 2.1;
  constexpr double kRadius = 0.12;
  constexpr double kHeight = 3.6;
  constexpr double kWidth = 0.12;
  constexpr double kDepth = 0.30;
  const Location turn = rotation_z(23.0 * kPi / 180.0);
  const Vec3 middle(0.5 * (kAlongX - 1) * kSpacing, 0.5 * (kAlongY - 1) * kSpacing, 0.0);
  auto at = [&](int i, int j) -> Vec3 { return Vec3(i * kSpacing, j * kSpacing, 0.0) - middle; };
  for (int i = 0; i < kAlongX; ++i) {
    for (int j = 0; j < kAlongY; ++j) {
      b.add(id("column-%02d-%02d", i, j), cylinder(turn.apply_point(at(i, j)), kRadius, kHeight));
    }
  }
  // Members from column axis to column axis: along x, then along y, at a height of their
  // underside.
  auto member_x = [&](int i, int j, double bottom) {
    return box(Vec3(kSpacing, kWidth, kDepth),
               turn * Location::translation(at(i, j) + Vec3(0.0, -kWidth / 2, bottom)));
  };
  auto member_y = [&](int i, int j, double bottom) {
    return box(Vec3(kWidth, kSpacing, kDepth),
               turn * Location::translation(at(i, j) + Vec3(-kWidth / 2, 0.0, bottom)));
  };
  for (int j = 0; j < kAlongY; ++j) {
    for (int i = 0; i + 1 < kAlongX; ++i) {
      b.add(id("beam-x-%02d-%02d", i, j), member_x(i, j, kHeight - kDepth));
      b.add(id("tie-x-%02d-%02d", i, j), member_x(i, j, 1.5));
    }
  }
  for (int i = 0; i < kAlongX; ++i) {
    for (int j = 0; j + 1 < kAlongY; ++j) {
      b.add(id("beam-y-%02d-%02d", i, j), member_y(i, j, kHeight - kDepth));
      b.add(id("tie-y-%02d-%02d", i, j), member_y(i, j, 2.4));
    }
  }
  return b.finish();
}

// A city block of about 100 m × 100 m: four quarters around a plaza crossing.
SynthScene city_block_scene(std::uint64_t seed) {
  SceneBuilder b("city-block", seed);
  detail::Random random(seed);
  auto vary = [&](double h) { return h * random.uniform(0.85, 1.15); };

  // North-west: an L-shaped block with a stair housing on its roof.
  const double l_height = vary(15.0);
  b.add("l-block", extrusion({{-46, 10}, {-10, 10}, {-10, 22}, {-34, 22}, {-34, 46}, {-46, 46}}, {},
                             l_height, Location()));
  b.add("l-block-stair-housing", box_at(Vec3(-42, 30, l_height - 0.5), Vec3(5, 4, 3.5)));

  // North-east: a block around a courtyard.
  b.add("courtyard-block",
        extrusion({{10, 10}, {46, 10}, {46, 40}, {30, 47}, {10, 40}},
                  {{{20, 18}, {20, 32}, {36, 32}, {36, 18}}}, vary(12.0), Location()));

  // South-west: a domed hall with a portico of six columns under an entablature.
  const Vec2 hall(-30, -28);
  const double drum = vary(8.0);
  b.add("hall-drum", cylinder(Vec3(hall.x(), hall.y(), 0), 9.0, drum));
  b.add("hall-dome", sphere(Location::translation(Vec3(hall.x(), hall.y(), drum)), 9.0));
  for (int i = 0; i < 6; ++i) {
    b.add(id("portico-column-%d", i), cylinder(Vec3(-18.0, -33.0 + 2.0 * i, 0), 0.45, 7.0));
  }
  b.add("portico-entablature", box_at(Vec3(-22.0, -34.0, 7.0), Vec3(4.8, 12.0, 1.0)));

  // South-east: a round tower with a cone roof, an office block with a frustum chimney, a
  // gabled house (a house-section profile swept along x) and a semicircular wall.
  const double tower = vary(22.0);
  b.add("tower", cylinder(Vec3(18, -40, 0), 4.0, tower));
  b.add("tower-roof", cone(Location::translation(Vec3(18, -40, tower)), 5.0, 0.0, 7.0));
  const double office = vary(10.0);
  b.add("office", box_at(Vec3(10, -28, 0), Vec3(20, 14, office)));
  b.add("office-chimney", cone(Location::translation(Vec3(26, -17, office - 0.5)), 1.2, 0.7, 4.0));
  kernel::Matrix34 to_x;  // local z along world x, local y up
  to_x << 0, 0, 1, 30,    //
      1, 0, 0, -46,       //
      0, 1, 0, 0;
  b.add("gabled-house", extrusion({{0, 0}, {10, 0}, {10, 6}, {5, vary(9.5)}, {0, 6}}, {}, 16.0,
                                  Location::from_matrix(to_x).value()));
  b.add("curved-wall", revolution({{5.6, 0}, {6.0, 0}, {6.0, 3.0}, {5.6, 3.0}}, kPi,
                                  Location::translation(Vec3(38, -18, 0)) * rotation_z(kPi / 2)));

  // The plaza: a ring sculpture standing on a plinth, a fountain, and street lamps.
  b.add("sculpture-plinth", box_at(Vec3(-4.8, 3.5, 0), Vec3(1.6, 1.0, 0.8)), kClassUnclassified);
  b.add("sculpture-ring",
        torus(Location::translation(Vec3(-4.0, 4.0, 3.45)) * rotation_x(kPi / 2), 2.5, 0.35),
        kClassUnclassified);
  b.add("fountain",
        revolution({{0, 0},
                    {4, 0},
                    {4, 0.8},
                    {3.7, 0.8},
                    {3.7, 0.3},
                    {0.4, 0.3},
                    {0.4, 1.8},
                    {1.2, 2.2},
                    {1.2, 2.35},
                    {0, 2.35}},
                   2 * kPi, Location::translation(Vec3(3.5, -3.5, 0))),
        kClassUnclassified);
  for (int i = 0; i < 6; ++i) {
    const double along = -40.0 + 16.0 * i;
    b.add(id("lamp-%d", i), cylinder(Vec3(along, i % 2 == 0 ? -7.0 : 7.0, 0), 0.1, 5.0),
          kClassUnclassified);
  }
  return b.finish();
}

// A rotation drawn uniformly (a normalised Gaussian quaternion).
Eigen::Matrix3d random_rotation(detail::Random& random) {
  Eigen::Quaterniond q;
  double norm = 0.0;
  do {
    q = Eigen::Quaterniond(random.normal(), random.normal(), random.normal(), random.normal());
    norm = q.norm();
  } while (norm < 1e-6);
  return q.normalized().toRotationMatrix();
}

PrimitiveSpec random_primitive(PrimitiveType type, detail::Random& r) {
  PrimitiveSpec s;
  s.type = type;
  switch (type) {
    case PrimitiveType::Box:
      s.size = Vec3(r.uniform(0.5, 5), r.uniform(0.5, 5), r.uniform(0.5, 5));
      break;
    case PrimitiveType::Cylinder:
      s.radius = r.uniform(0.3, 2.0);
      s.height = r.uniform(0.5, 6.0);
      break;
    case PrimitiveType::Cone:
      s.radius = r.uniform(0.3, 2.5);
      s.radius2 = r.uniform() < 0.5 ? 0.0 : r.uniform(0.2, 2.0);
      s.height = r.uniform(0.5, 5.0);
      break;
    case PrimitiveType::Sphere:
      s.radius = r.uniform(0.5, 3.0);
      break;
    case PrimitiveType::Torus:
      s.radius = r.uniform(1.0, 3.0);
      s.radius2 = s.radius * r.uniform(0.15, 0.45);
      break;
    case PrimitiveType::Extrusion: {
      // A star-shaped polygon: vertices at jittered, evenly spaced angles. With at least five
      // vertices no angular gap reaches π, so it contains a disc of radius 0.6 about the
      // origin, room for a small hole.
      const int n = 5 + static_cast<int>(r.below(5));
      for (int i = 0; i < n; ++i) {
        const double angle = (i + r.uniform(-0.2, 0.2)) * 2 * kPi / n;
        const double radius = r.uniform(1.0, 3.0);
        s.profile.emplace_back(radius * std::cos(angle), radius * std::sin(angle));
      }
      if (r.uniform() < 0.4) {
        const double a = r.uniform(0.15, 0.35);
        s.holes.push_back({{-a, -a}, {-a, a}, {a, a}, {a, -a}});
      }
      s.height = r.uniform(0.5, 5.0);
      break;
    }
    case PrimitiveType::Revolution: {
      // A profile monotone in z, closed along the axis: always a simple polygon.
      const int levels = 2 + static_cast<int>(r.below(4));
      double z = 0.0;
      s.profile.emplace_back(0.0, z);
      for (int i = 0; i < levels; ++i) {
        s.profile.emplace_back(r.uniform(0.3, 2.5), z);
        z += r.uniform(0.3, 1.5);
      }
      s.profile.emplace_back(r.uniform(0.3, 2.5), z);
      s.profile.emplace_back(0.0, z);
      s.angle = r.uniform() < 0.3 ? r.uniform(kPi / 2, 3 * kPi / 2) : 2 * kPi;
      break;
    }
  }
  return s;
}

// `count` primitives, the first seven one of each type, over 60 m × 60 m.
SynthScene random_scene(std::uint64_t seed, int count) {
  SceneBuilder b("random", seed);
  detail::Random random(seed);
  for (int i = 0; i < count; ++i) {
    const auto type = static_cast<PrimitiveType>(
        i < kernel::kPrimitiveTypeCount
            ? i
            : static_cast<int>(random.below(kernel::kPrimitiveTypeCount)));
    PrimitiveSpec s = random_primitive(type, random);
    const Eigen::Matrix3d rotation = random_rotation(random);
    const double scale = random.uniform(0.5, 2.0);
    const Vec3 t(random.uniform(-30, 30), random.uniform(-30, 30), random.uniform(0.5, 8.0));
    kernel::Matrix34 m;
    m.leftCols<3>() = scale * rotation;
    m.col(3) = t;
    s.placement = Location::from_matrix(m).value();
    char name[48];
    std::snprintf(name, sizeof name, "%s-%03d", kernel::primitive_type_name(type), i);
    b.add(name, std::move(s));
  }
  return b.finish();
}

}  // namespace

const std::vector<std::string>& synth_scene_names() {
  static const std::vector<std::string> names{"gate", "frame", "city-block", "random"};
  return names;
}

kernel::Result<SynthScene> make_synth_scene(std::string_view name, std::uint64_t seed,
                                            int random_count) {
  if (name == "gate") return gate_scene(seed);
  if (name == "frame") return frame_scene(seed);
  if (name == "city-block") return city_block_scene(seed);
  if (name == "random") {
    if (random_count < 1 || random_count > 100000) {
      return kernel::Error{kernel::ErrorCode::InvalidArgument, "random scene: primitive count " +
                                                                   std::to_string(random_count) +
                                                                   " is not in [1, 100000]"};
    }
    return random_scene(seed, random_count);
  }
  std::string names;
  for (const auto& n : synth_scene_names()) names += (names.empty() ? "" : ", ") + n;
  return kernel::Error{kernel::ErrorCode::InvalidArgument,
                       "unknown scene \"" + std::string(name) + "\"; valid scenes: " + names};
}

}  // namespace csgtile::geo
