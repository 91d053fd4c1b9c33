#include "random_shapes.h"

#include <Eigen/Geometry>
#include <numbers>

namespace csgtile::test {

using kernel::Vec2;
using kernel::Vec3;

kernel::Location random_similarity(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_real_distribution<double> angle(0.0, 2 * std::numbers::pi);
  std::uniform_real_distribution<double> log_scale(std::log(0.2), std::log(5.0));
  Vec3 axis(unit(rng), unit(rng), unit(rng));
  if (axis.norm() < 1e-3) axis = Vec3::UnitZ();
  const Vec3 t(100 * unit(rng), 100 * unit(rng), 100 * unit(rng));
  return kernel::Location::translation(t) *
         kernel::Location::rotation(Vec3::Zero(), axis, angle(rng)) *
         kernel::Location::scaling(std::exp(log_scale(rng)));
}

kernel::PrimitiveSpec random_primitive(std::mt19937_64& rng, kernel::PrimitiveType type) {
  std::uniform_real_distribution<double> size(0.1, 10.0);
  kernel::PrimitiveSpec s;
  s.type = type;
  switch (type) {
    case kernel::PrimitiveType::Box:
      s.size = Vec3(size(rng), size(rng), size(rng));
      break;
    case kernel::PrimitiveType::Cylinder:
      s.radius = size(rng);
      s.height = size(rng);
      break;
    case kernel::PrimitiveType::Cone:
      s.radius = size(rng);
      s.radius2 = std::bernoulli_distribution(0.3)(rng) ? 0.0 : size(rng);
      s.height = size(rng);
      break;
    case kernel::PrimitiveType::Sphere:
      s.radius = size(rng);
      break;
    case kernel::PrimitiveType::Torus: {
      s.radius2 = size(rng);
      s.radius = s.radius2 * (1.1 + std::uniform_real_distribution<double>(0, 3)(rng));
      break;
    }
    case kernel::PrimitiveType::Extrusion: {
      // A star-shaped polygon around the origin: simple by construction.
      const int n = std::uniform_int_distribution<int>(3, 12)(rng);
      for (int i = 0; i < n; ++i) {
        const double a = 2 * std::numbers::pi * i / n;
        const double r = size(rng);
        s.profile.push_back(Vec2(r * std::cos(a), r * std::sin(a)));
      }
      s.height = size(rng);
      break;
    }
    case kernel::PrimitiveType::Revolution: {
      // A convex-ish profile in rho > 0, sometimes touching the axis.
      const double r0 = std::bernoulli_distribution(0.3)(rng) ? 0.0 : size(rng) * 0.5;
      const double w = size(rng), h = size(rng);
      s.profile = {Vec2(r0, 0), Vec2(r0 + w, 0), Vec2(r0 + 0.5 * w, h), Vec2(r0, h)};
      s.angle = std::bernoulli_distribution(0.5)(rng)
                    ? 2 * std::numbers::pi
                    : std::uniform_real_distribution<double>(0.3, 6.0)(rng);
      break;
    }
  }
  return s;
}

}  // namespace csgtile::test
