#include "csgtile/kernel/primitives.h"

#include <cmath>

#include "csgtile/kernel/boolean.h"
#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/mass_properties.h"

namespace csgtile::kernel {

namespace {

// `solid` ∩ {n·p <= d} for each clip: a box standing for the half-space (its top face on the
// plane, the rest well outside the solid's bounding box), intersected exactly.
Result<Shape> apply_clips(Shape solid, const std::vector<Eigen::Vector4d>& clips,
                          double tolerance) {
  for (std::size_t k = 0; k < clips.size(); ++k) {
    const std::string which = "clip " + std::to_string(k);
    const Vec3 n = clips[k].head<3>();
    const double d = clips[k].w();
    if (!n.allFinite() || !std::isfinite(d) || std::abs(n.norm() - 1.0) > 1e-9) {
      return Error{ErrorCode::DegenerateGeometry,
                   which + ": not a unit normal and a finite offset"};
    }
    Vec3 e1 = std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
    e1 = (e1 - e1.dot(n) * n).normalized();
    const Vec3 e2 = n.cross(e1);
    const BoundingBox box = bounding_box(solid);
    if (box.empty() || !(box.max - box.min).allFinite() || (box.max - box.min).maxCoeff() > 1e9) {
      return Error{ErrorCode::DegenerateGeometry, which + ": the solid is too large to clip"};
    }
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int c = 0; c < 8; ++c) {
      const Vec3 p((c & 1) ? box.max.x() : box.min.x(), (c & 2) ? box.max.y() : box.min.y(),
                   (c & 4) ? box.max.z() : box.min.z());
      const double q[3] = {p.dot(e1), p.dot(e2), p.dot(n)};
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min(lo[a], q[a]);
        hi[a] = std::max(hi[a], q[a]);
      }
    }
    const double margin = 1.0 + 0.1 * (box.max - box.min).norm();
    if (d >= hi[2] + tolerance) continue;  // the plane is above the whole solid
    if (d <= lo[2] + tolerance) {
      return Error{ErrorCode::DegenerateGeometry, which + ": removes the whole primitive"};
    }
    Eigen::Matrix3d r;
    r.col(0) = e1;
    r.col(1) = e2;
    r.col(2) = n;
    const Vec3 corner = (lo[0] - margin) * e1 + (lo[1] - margin) * e2 + (lo[2] - margin) * n;
    auto half = make_box(hi[0] - lo[0] + 2 * margin, hi[1] - lo[1] + 2 * margin,
                         d - (lo[2] - margin), tolerance);
    if (!half.ok()) return half.error();
    auto at = Location::from_parts(r, 1.0, corner);
    if (!at.ok()) return at.error();
    BooleanOptions options;
    options.tolerance = tolerance;
    auto cut = boolean_operation(solid, half.value().moved(at.value()), BooleanOp::Common, options);
    if (!cut.ok()) return Error{cut.error().code, which + ": " + cut.error().message};
    const auto solids = map_child_shapes(cut.value(), ShapeKind::Solid);
    if (solids.size() != 1) {
      return Error{ErrorCode::DegenerateGeometry,
                   which + ": leaves " + std::to_string(solids.size()) + " solids, not one"};
    }
    solid = solids[0];
  }
  return solid;
}

}  // namespace

const char* primitive_type_name(PrimitiveType type) {
  switch (type) {
    case PrimitiveType::Box:
      return "box";
    case PrimitiveType::Cylinder:
      return "cylinder";
    case PrimitiveType::Cone:
      return "cone";
    case PrimitiveType::Sphere:
      return "sphere";
    case PrimitiveType::Torus:
      return "torus";
    case PrimitiveType::Extrusion:
      return "extrusion";
    case PrimitiveType::Revolution:
      return "revolution";
  }
  return "unknown";
}

Result<Shape> build_primitive(const PrimitiveSpec& spec, double tolerance) {
  Result<Shape> local = [&]() -> Result<Shape> {
    switch (spec.type) {
      case PrimitiveType::Box:
        return make_box(spec.size.x(), spec.size.y(), spec.size.z(), tolerance);
      case PrimitiveType::Cylinder:
        return make_cylinder(spec.radius, spec.height, tolerance);
      case PrimitiveType::Cone:
        return make_cone(spec.radius, spec.radius2, spec.height, tolerance);
      case PrimitiveType::Sphere:
        return make_sphere(spec.radius, tolerance);
      case PrimitiveType::Torus:
        return make_torus(spec.radius, spec.radius2, tolerance);
      case PrimitiveType::Extrusion:
        return make_extrusion(spec.profile, spec.holes, spec.height, tolerance);
      case PrimitiveType::Revolution:
        return make_revolution(spec.profile, spec.angle, tolerance);
    }
    return Error{ErrorCode::InvalidArgument, "unknown primitive type"};
  }();
  if (!local.ok()) return local;
  if (!spec.clips.empty()) {
    local = apply_clips(local.value(), spec.clips, tolerance);
    if (!local.ok()) return local;
  }
  if (spec.placement.is_identity()) return local;
  return local.value().moved(spec.placement);
}

}  // namespace csgtile::kernel
