#include "csgtile/kernel/primitives.h"

namespace csgtile::kernel {

const char* primitive_type_name(PrimitiveType type) {
  switch (type) {
    case PrimitiveType::Box: return "box";
    case PrimitiveType::Cylinder: return "cylinder";
    case PrimitiveType::Cone: return "cone";
    case PrimitiveType::Sphere: return "sphere";
    case PrimitiveType::Torus: return "torus";
    case PrimitiveType::Extrusion: return "extrusion";
    case PrimitiveType::Revolution: return "revolution";
  }
  return "unknown";
}

Result<Shape> build_primitive(const PrimitiveSpec& spec, double tolerance) {
  Result<Shape> local = [&]() -> Result<Shape> {
    switch (spec.type) {
      case PrimitiveType::Box: return make_box(spec.size.x(), spec.size.y(), spec.size.z(), tolerance);
      case PrimitiveType::Cylinder: return make_cylinder(spec.radius, spec.height, tolerance);
      case PrimitiveType::Cone: return make_cone(spec.radius, spec.radius2, spec.height, tolerance);
      case PrimitiveType::Sphere: return make_sphere(spec.radius, tolerance);
      case PrimitiveType::Torus: return make_torus(spec.radius, spec.radius2, tolerance);
      case PrimitiveType::Extrusion:
        return make_extrusion(spec.profile, spec.holes, spec.height, tolerance);
      case PrimitiveType::Revolution: return make_revolution(spec.profile, spec.angle, tolerance);
    }
    return Error{ErrorCode::InvalidArgument, "unknown primitive type"};
  }();
  if (!local.ok()) return local;
  if (spec.placement.is_identity()) return local;
  return local.value().moved(spec.placement);
}

}  // namespace csgtile::kernel
