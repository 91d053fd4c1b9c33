#pragma once
// Escalation of a failed fuse (AssemblyOptions::escalate_to): the object's primitives snapped
// at growing distances until they fuse.

#include <optional>
#include <vector>

#include "csgtile/assembly/assembly.h"

namespace csgtile::assembly::detail {

/// The thinnest extent of a primitive (world units): a box's smallest side, a cylinder's
/// smaller of diameter and height, a torus's tube diameter, an extrusion's smaller of height
/// and profile width, a revolution's profile width.
double thinnest_extent(const kernel::PrimitiveSpec& spec);

struct Escalated {
  kernel::CsgModel model;
  kernel::SnapOptions snap;
};

/// Fuses `group` (the object's primitives as given to the assembly) snapped at each step of
/// AssemblyOptions::escalate_to in turn; the first fuse that holds, or nullopt when none does
/// within the bound or before `interrupt` fires. Deterministic (when it does not fire).
std::optional<Escalated> escalate_fuse(const std::vector<AssemblyPrimitive>& group,
                                       const AssemblyOptions& options,
                                       const kernel::Interrupt& interrupt);

}  // namespace csgtile::assembly::detail
