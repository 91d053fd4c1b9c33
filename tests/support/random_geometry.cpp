#include "random_geometry.h"

#include <Eigen/Geometry>

namespace csgtile::test {

using kernel::Vec3;

Vec3 random_unit(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Vec3 v;
  do {
    const double z = n(rng), y = n(rng), x = n(rng);
    v = Vec3(x, y, z);
  } while (v.norm() < 1e-3);
  return v.normalized();
}

Vec3 random_point(std::mt19937& rng, double extent) {
  std::uniform_real_distribution<double> d(-extent, extent);
  // Drawn in a fixed sequence, never as function arguments (unspecified evaluation order).
  const double x = d(rng), y = d(rng), z = d(rng);
  return {x, y, z};
}

kernel::Frame random_frame(std::mt19937& rng) {
  const Vec3 x = random_unit(rng);
  const Vec3 z = random_unit(rng);
  const Vec3 origin = random_point(rng, 5.0);
  return kernel::Frame::from_z(origin, z, x);
}

kernel::Location random_similarity(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  const double z = n(rng), y = n(rng), x = n(rng), w = n(rng);
  const Eigen::Quaterniond q = Eigen::Quaterniond(w, x, y, z).normalized();
  std::uniform_real_distribution<double> scale(0.3, 3.0);
  kernel::Matrix34 m;
  m.leftCols<3>() = scale(rng) * q.toRotationMatrix();
  m.col(3) = random_point(rng, 10.0);
  const kernel::Result<kernel::Location> loc = kernel::Location::from_matrix(m);
  EXPECT_TRUE(loc.ok());
  return loc.ok() ? loc.value() : kernel::Location();
}

void expect_near(const Vec3& a, const Vec3& b, double tolerance) {
  EXPECT_LE((a - b).norm(), tolerance) << "a = " << a.transpose() << "\nb = " << b.transpose();
}

}  // namespace csgtile::test
