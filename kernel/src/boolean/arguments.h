#pragma once
// Boolean arguments made of several solids (compounds, compsolids) stand for the union of
// their solids' interiors. The engine (boolean.cpp) needs arguments whose solids meet at
// most along edges or at vertices, as its own results do; an argument whose solids overlap
// or share faces is first replaced by the union of its solids, each face of which keeps the
// argument faces it comes from, so that the operation's face history still names faces of
// the argument as given.

#include <vector>

#include "csgtile/kernel/boolean.h"

namespace csgtile::kernel::detail {

/// The engine on arguments that are already prepared (primitives, Boolean results, and
/// whatever prepare_argument returns). `origins` is filled when not null.
Result<Shape> run_engine(const Shape& a, const Shape& b, BooleanOp op,
                         const BooleanOptions& options,
                         std::vector<std::vector<FaceOrigin>>* origins);

/// The engine's contact test of two prepared shapes (solid_interference without the box test).
Result<Interference> run_interference(const Shape& a, const Shape& b,
                                      const BooleanOptions& options);

/// An argument ready for the engine.
struct PreparedArgument {
  Shape shape;  ///< the argument itself, or the union of its solids
  /// Empty when `shape` is the argument itself. Otherwise, for face i of
  /// map_child_shapes(shape, ShapeKind::Face), the argument's faces it comes from (ascending).
  std::vector<std::vector<int>> faces;
};

/// The argument itself when no two of its solids meet (boxes grown by the tolerance apart, or
/// the engine's contact test says disjoint: a Boolean result's solids, for one, never need
/// it); otherwise the union of its solids, each group of solids that meet (directly or through
/// others) fused as a balanced tree. Errors: those of the contact test and of the fuse.
Result<PreparedArgument> prepare_argument(const Shape& argument, const BooleanOptions& options);

/// Restates origins that name faces of the prepared arguments as origins naming faces of
/// the arguments as given (sorted, each once).
void restate_origins(std::vector<std::vector<FaceOrigin>>& origins, const PreparedArgument& a,
                     const PreparedArgument& b);

}  // namespace csgtile::kernel::detail
