#include "escalation.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace csgtile::assembly::detail {

double thinnest_extent(const kernel::PrimitiveSpec& s) {
  auto profile_width = [](const std::vector<kernel::Vec2>& profile) {
    if (profile.empty()) return 0.0;
    kernel::Vec2 low = profile.front(), high = profile.front();
    for (const kernel::Vec2& q : profile) {
      low = low.cwiseMin(q);
      high = high.cwiseMax(q);
    }
    return (high - low).minCoeff();
  };
  double t = 0.0;
  switch (s.type) {
    case kernel::PrimitiveType::Box:
      t = s.size.minCoeff();
      break;
    case kernel::PrimitiveType::Cylinder:
      t = std::min(2.0 * s.radius, s.height);
      break;
    case kernel::PrimitiveType::Cone:
      t = std::min(2.0 * std::max(s.radius, s.radius2), s.height);
      break;
    case kernel::PrimitiveType::Sphere:
      t = 2.0 * s.radius;
      break;
    case kernel::PrimitiveType::Torus:
      t = 2.0 * s.radius2;
      break;
    case kernel::PrimitiveType::Extrusion:
      t = std::min(s.height, profile_width(s.profile));
      break;
    case kernel::PrimitiveType::Revolution:
      t = profile_width(s.profile);
      break;
  }
  return t * s.placement.scale();
}

std::optional<Escalated> escalate_fuse(const std::vector<AssemblyPrimitive>& group,
                                       const AssemblyOptions& options,
                                       const kernel::Interrupt& interrupt) {
  if (!(options.escalate_to > 0.0) || group.size() < 2) return std::nullopt;
  double bound = options.escalate_to;
  std::vector<kernel::PrimitiveSpec> specs;
  for (const AssemblyPrimitive& p : group) {
    specs.push_back(p.spec);
    bound = std::min(bound, 0.1 * thinnest_extent(p.spec));
  }
  constexpr double kSteps[] = {0.001, 0.002, 0.005, 0.01, 0.02, 0.05, 0.1};
  constexpr double kDegree = std::numbers::pi / 180.0;
  kernel::BooleanOptions bopt;
  bopt.tolerance = options.tolerance;
  bopt.interrupt = interrupt;
  for (const double d : kSteps) {
    if (interrupt.fired()) break;
    if (d <= options.snap.distance) continue;
    if (d > bound) break;
    kernel::SnapOptions snap;
    snap.distance = d;
    snap.angle = std::min(2.0 * kDegree, std::max(options.snap.angle, 0.5 * kDegree * d / 0.005));
    auto moved = kernel::snap_primitives(specs, snap);
    if (!moved.ok()) continue;
    std::vector<kernel::CsgModel> leaves;
    bool built = true;
    for (std::size_t i = 0; i < group.size() && built; ++i) {
      auto leaf = kernel::csg_primitive(moved.value()[i], group[i].label, options.tolerance);
      built = leaf.ok();
      if (built) leaves.push_back(std::move(leaf).value());
    }
    if (!built) continue;
    auto fused = kernel::csg_combine(leaves, kernel::BooleanOp::Fuse, bopt);
    if (fused.ok()) return Escalated{std::move(fused).value(), snap};
  }
  return std::nullopt;
}

}  // namespace csgtile::assembly::detail
