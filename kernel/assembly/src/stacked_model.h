#pragma once
// Models side by side: a compound of their shapes under one n-ary fuse node.

#include <vector>

#include "csgtile/kernel/csg.h"

namespace csgtile::assembly::detail {

/// The compound of the models' shapes (each model's shape one child), its tree one Fuse
/// node over the models' trees, face sources carried over. Meant for models that do not
/// meet (then the compound is their union) and for unfused objects (flagged by the caller).
kernel::Result<kernel::CsgModel> stacked_model(const std::vector<const kernel::CsgModel*>& models);

}  // namespace csgtile::assembly::detail
