// A scene as a CSG model (csgtile/geo/scene_model.h).

#include "csgtile/geo/scene_model.h"

#include <string>

namespace csgtile::geo {

kernel::Result<std::vector<kernel::CsgModel>> scene_leaves(const Scene& scene,
                                                           const SceneModelOptions& options) {
  std::vector<kernel::CsgModel> leaves;
  leaves.reserve(scene.primitives.size());
  for (std::size_t i = 0; i < scene.primitives.size(); ++i) {
    const ScenePrimitive& p = scene.primitives[i];
    auto leaf = kernel::csg_primitive(p.spec, p.id.empty() ? "p" + std::to_string(i) : p.id,
                                      options.tolerance);
    if (!leaf.ok()) {
      return kernel::Error{leaf.error().code, "primitives[" + std::to_string(i) + "] (" +
                                                  kernel::primitive_type_name(p.spec.type) +
                                                  "): " + leaf.error().message};
    }
    leaves.push_back(std::move(leaf).value());
  }
  return leaves;
}

kernel::Result<kernel::CsgModel> combine_scene(BooleanOp op,
                                               const std::vector<kernel::CsgModel>& leaves,
                                               const SceneModelOptions& options) {
  if (op == BooleanOp::None) {
    std::vector<kernel::Shape> solids;
    solids.reserve(leaves.size());
    for (const kernel::CsgModel& leaf : leaves) solids.push_back(leaf.shape);
    auto set = kernel::ShapeFactory::compound(std::move(solids));
    if (!set.ok()) return set.error();
    kernel::CsgModel model;
    model.shape = std::move(set).value();
    return model;
  }
  kernel::BooleanOptions boolean;
  boolean.tolerance = options.tolerance;
  boolean.interrupt = options.interrupt;
  return kernel::csg_combine(leaves,
                             op == BooleanOp::Fuse     ? kernel::BooleanOp::Fuse
                             : op == BooleanOp::Common ? kernel::BooleanOp::Common
                                                       : kernel::BooleanOp::Cut,
                             boolean);
}

}  // namespace csgtile::geo
