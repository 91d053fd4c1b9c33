#include "model_builders.h"

#include "csgtile/kernel/check.h"

#include <cmath>

#include <gtest/gtest.h>

namespace csgtile::test {

kernel::PrimitiveSpec box(const kernel::Vec3& size, const kernel::Location& at) {
  kernel::PrimitiveSpec s;
  s.type = kernel::PrimitiveType::Box;
  s.size = size;
  s.placement = at;
  return s;
}

kernel::PrimitiveSpec cylinder(double r, double h, const kernel::Location& at) {
  kernel::PrimitiveSpec s;
  s.type = kernel::PrimitiveType::Cylinder;
  s.radius = r;
  s.height = h;
  s.placement = at;
  return s;
}

kernel::Location placement_rows(const std::array<double, 12>& rows) {
  kernel::Matrix34 q;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 4; ++j) q(i, j) = rows[static_cast<std::size_t>(4 * i + j)];
  }
  auto at = kernel::Location::from_matrix(q);
  EXPECT_TRUE(at.ok()) << at.error().message;
  return at.ok() ? at.value() : kernel::Location();
}

std::pair<kernel::PrimitiveSpec, kernel::PrimitiveSpec> fitted_column_and_beam() {
  const kernel::PrimitiveSpec column =
      cylinder(0.1518848301127851, 3.9995294132512806,
               placement_rows({1, 0, 0, 9.001867204626194, 0, 0.9999997536395747,
                               0.000701940731047384, 0.0007465168148400713, 0,
                               -0.000701940731047384, 0.9999997536395747, -0.001671966867296138}));
  const kernel::PrimitiveSpec beam =
      box(kernel::Vec3(0.19956792023612407, 3.0006137219093287, 0.2987809655545449),
          placement_rows({0.999999999930532, 0, 1.1787107160086285e-05, 8.898801008141323, 0, 1, 0,
                          -0.00022804077599155735, -1.1787107160086285e-05, 0, 0.999999999930532,
                          3.698972081854656}));
  return {column, beam};
}

std::vector<kernel::PrimitiveSpec> fitted_column_in_two_pieces() {
  const kernel::PrimitiveSpec lower = cylinder(0.15, 4.0, kernel::Location());
  const kernel::PrimitiveSpec upper =
      cylinder(0.15, 3.0,
               kernel::Location::translation(kernel::Vec3(1e-6, 0, 2.5)) *
                   kernel::Location::rotation(kernel::Vec3::Zero(), kernel::Vec3::UnitX(), 1e-4));
  const double top = 2.5 + 3.0 * std::cos(1e-4);
  const kernel::PrimitiveSpec beam =
      box(kernel::Vec3(3.0, 0.2, 0.3),
          kernel::Location::translation(kernel::Vec3(-0.1, -0.1, top - 1e-4 - 0.3)));
  return {lower, upper, beam};
}

kernel::Shape valid_solid(const kernel::Result<kernel::Shape>& r, const std::string& what) {
  EXPECT_TRUE(r.ok()) << what << ": " << (r.ok() ? "" : r.error().message);
  if (!r.ok()) return kernel::Shape();
  const kernel::CheckReport report = kernel::check_shape(r.value());
  EXPECT_TRUE(report.valid()) << what << ": "
                              << (report.valid() ? "" : report.issues.front().message);
  return r.value();
}

kernel::PrimitiveSpec box_at(const kernel::Vec3& at, const kernel::Vec3& size) {
  return box(size, kernel::Location::translation(at));
}

kernel::PrimitiveSpec cylinder_at(const kernel::Vec3& at, double r, double h) {
  return cylinder(r, h, kernel::Location::translation(at));
}

kernel::PrimitiveSpec extrusion_at(std::vector<kernel::Vec2> profile, double base, double height) {
  kernel::PrimitiveSpec s;
  s.type = kernel::PrimitiveType::Extrusion;
  s.profile = std::move(profile);
  s.height = height;
  s.placement = kernel::Location::translation(kernel::Vec3(0.0, 0.0, base));
  return s;
}

std::vector<kernel::Vec2> rectangle(double x0, double y0, double x1, double y1) {
  return {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
}

kernel::PrimitiveSpec gable_house() {
  kernel::PrimitiveSpec s = extrusion_at(rectangle(0, 0, 10, 6), 0.0, 10.0);
  const double r = 1.0 / std::sqrt(2.0);
  s.clips.emplace_back(0.0, -r, r, 5.0 * r);  // z <= 5 + y
  s.clips.emplace_back(0.0, r, r, 11.0 * r);  // z <= 11 - y
  return s;
}

kernel::CsgModel leaf(const kernel::PrimitiveSpec& spec, const std::string& label) {
  auto m = kernel::csg_primitive(spec, label);
  EXPECT_TRUE(m.ok()) << m.error().message;
  return std::move(m).value();
}

}  // namespace csgtile::test
