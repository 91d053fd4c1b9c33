// Scene primitives from one length unit to another (see scene_units.h).

#include "csgtile/geo/scene_units.h"

#include <cmath>
#include <string>

namespace csgtile::geo {

namespace {

using kernel::ErrorCode;
using kernel::PrimitiveType;
using kernel::Vec2;
using kernel::Vec3;

std::string named(const ScenePrimitive& p) {
  std::string out = kernel::primitive_type_name(p.spec.type);
  if (!p.id.empty()) out += " " + p.id;
  return out;
}

// Whether the rotation maps the local z axis onto the world's (up or down): then it commutes
// with diag(h, h, v). Fitted placements are orthonormal to rounding.
bool keeps_vertical(const Eigen::Matrix3d& r) { return std::abs(std::abs(r(2, 2)) - 1.0) <= 1e-12; }

bool kept_by_non_uniform(PrimitiveType type) {
  switch (type) {
    case PrimitiveType::Box:
    case PrimitiveType::Cylinder:
    case PrimitiveType::Cone:
    case PrimitiveType::Extrusion:
    case PrimitiveType::Revolution:
      return true;
    case PrimitiveType::Sphere:
    case PrimitiveType::Torus:
      return false;
  }
  return false;
}

}  // namespace

kernel::Result<ScenePrimitive> scaled_primitive(const ScenePrimitive& primitive,
                                                const UnitScale& scale) {
  const double h = scale.horizontal, v = scale.vertical;
  if (!(h > 0.0) || !(v > 0.0) || !std::isfinite(h) || !std::isfinite(v)) {
    return kernel::Error{ErrorCode::InvalidArgument, "a unit scale must be positive and finite"};
  }
  ScenePrimitive out = primitive;
  if (scale.identity()) return out;
  kernel::PrimitiveSpec& s = out.spec;
  const kernel::Location& at = primitive.spec.placement;
  if (!scale.uniform()) {
    if (!kept_by_non_uniform(s.type)) {
      return kernel::Error{ErrorCode::Unsupported,
                           "the " + named(primitive) +
                               " has no exact form in a CRS whose heights are in another unit "
                               "than its horizontal coordinates (it would be an ellipsoid)"};
    }
    if (!keeps_vertical(at.rotation())) {
      return kernel::Error{ErrorCode::Unsupported,
                           "the " + named(primitive) +
                               " is tilted: it has no exact form in a CRS whose heights are in "
                               "another unit than its horizontal coordinates"};
    }
  }
  // World p = σ R q + t. With D = diag(h, h, v) commuting with R (uniform, or R about z):
  // D p = σ R (D q) + D t: the local geometry maps by D, the translation by D.
  const Vec3 d(h, h, v);
  switch (s.type) {
    case PrimitiveType::Box:
      s.size = s.size.cwiseProduct(d);
      break;
    case PrimitiveType::Cylinder:
    case PrimitiveType::Cone:
      s.radius *= h;
      s.radius2 *= h;
      s.height *= v;
      break;
    case PrimitiveType::Sphere:
    case PrimitiveType::Torus:
      s.radius *= h;
      s.radius2 *= h;
      break;
    case PrimitiveType::Extrusion:
      for (Vec2& q : s.profile) q *= h;
      for (auto& hole : s.holes) {
        for (Vec2& q : hole) q *= h;
      }
      s.height *= v;
      break;
    case PrimitiveType::Revolution:
      for (Vec2& q : s.profile) q = Vec2(q.x() * h, q.y() * v);
      break;
  }
  // A clip n·q <= w keeps D q' with (D⁻¹ n)·q' <= w: renormalised.
  for (Eigen::Vector4d& c : s.clips) {
    const Vec3 n = Vec3(c.x(), c.y(), c.z()).cwiseQuotient(d);
    const double len = n.norm();
    if (!(len > 0.0)) continue;  // not a unit normal: build_primitive reports it
    c = Eigen::Vector4d(n.x() / len, n.y() / len, n.z() / len, c.w() / len);
  }
  auto placed =
      kernel::Location::from_parts(at.rotation(), at.scale(), at.translation().cwiseProduct(d));
  if (!placed.ok()) return placed.error();
  s.placement = std::move(placed).value();
  if (out.quality) {
    out.quality->rms *= h;
    if (out.quality->sigma) *out.quality->sigma *= h;
  }
  return out;
}

}  // namespace csgtile::geo
