#include "model_builders.h"

#include <gtest/gtest.h>

namespace csgtile::test {

kernel::PrimitiveSpec box_at(const kernel::Vec3& at, const kernel::Vec3& size) {
  kernel::PrimitiveSpec s;
  s.type = kernel::PrimitiveType::Box;
  s.size = size;
  s.placement = kernel::Location::translation(at);
  return s;
}

kernel::PrimitiveSpec cylinder_at(const kernel::Vec3& at, double r, double h) {
  kernel::PrimitiveSpec s;
  s.type = kernel::PrimitiveType::Cylinder;
  s.radius = r;
  s.height = h;
  s.placement = kernel::Location::translation(at);
  return s;
}

kernel::CsgModel leaf(const kernel::PrimitiveSpec& spec, const std::string& label) {
  auto m = kernel::csg_primitive(spec, label);
  EXPECT_TRUE(m.ok()) << m.error().message;
  return std::move(m).value();
}

}  // namespace csgtile::test
