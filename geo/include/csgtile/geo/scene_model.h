#pragma once
/// \file
/// A scene (scene.h) as a CSG model: its primitives built as leaves, then combined by its
/// operation. The one path from the scene format to the kernel's CsgModel (`csgtile bool`,
/// the scene build job).

#include <vector>

#include "csgtile/geo/scene.h"
#include "csgtile/kernel/boolean.h"
#include "csgtile/kernel/csg.h"

namespace csgtile::geo {

struct SceneModelOptions {
  double tolerance = kernel::kDefaultTolerance;  ///< linear tolerance of leaves and Booleans
  kernel::Interrupt interrupt{};                 ///< Booleans return Cancelled once it fires
};

/// Each primitive of `scene` as a CSG leaf (kernel::csg_primitive at options.tolerance),
/// labelled with its id, "p<i>" when it has none. Errors: the kernel's code, the message
/// naming the primitive ("primitives[i] (type): …").
kernel::Result<std::vector<kernel::CsgModel>> scene_leaves(const Scene& scene,
                                                           const SceneModelOptions& options = {});

/// The leaves combined by `op` as one n-ary operation node (kernel::csg_combine: history kept);
/// BooleanOp::None gives the compound of their solids without history. Errors as csg_combine
/// and compound building.
kernel::Result<kernel::CsgModel> combine_scene(BooleanOp op,
                                               const std::vector<kernel::CsgModel>& leaves,
                                               const SceneModelOptions& options = {});

}  // namespace csgtile::geo
