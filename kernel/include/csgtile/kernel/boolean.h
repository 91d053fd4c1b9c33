#pragma once
/// \file
/// Exact Boolean operations on CSG-BRep solids (paper §4.2, completed with face–face
/// intersection curves and the degenerate configurations).
///
/// Method: every face of one operand is intersected with every face of the other whose
/// bounding boxes meet (analytic section curves with exact trig-linear pcurves); edges are
/// split where section curves end on them, faces are split along the section curves in
/// their (u, v) planes, each piece is classified in / out / on the other solid (exact ray
/// casting), kept or dropped per operation, and the kept pieces are sewn into shells and
/// solids that share their edges and vertices. Faces on one plane that meet along an edge
/// bounding nothing are merged. Every result is checked; an operation that cannot produce a
/// valid solid returns a named error and never a silently wrong shape.

#include <compare>
#include <vector>

#include "csgtile/kernel/interrupt.h"
#include "csgtile/kernel/shape.h"

namespace csgtile::kernel {

enum class BooleanOp { Fuse, Common, Cut };
const char* boolean_op_name(BooleanOp op);  ///< "fuse", "common", "cut"

struct BooleanOptions {
  double tolerance = 1e-7;   ///< linear tolerance (world units) of every decision and new edge
  bool check_result = true;  ///< run the validity checker on the result (InvalidShape if bad)
  /// Looked at between the operation's steps: once it fires, the call returns Cancelled.
  Interrupt interrupt{};
};

/// a ∪ b, a ∩ b or a − b. Arguments: solids, or compounds/compsolids of solids (treated as
/// the union of their solids' interiors). The result is a compound of solids (empty when the
/// result has no volume). Errors: InvalidArgument (not solids), Unsupported (a surface pair
/// whose intersection this version cannot compute exactly, named), InvalidShape (the result
/// failed the checker — a bug to report), Cancelled (options.interrupt fired).
Result<Shape> boolean_operation(const Shape& a, const Shape& b, BooleanOp op,
                                const BooleanOptions& options = {});

/// Where a face of a Boolean result comes from: face `face` (its index in
/// map_child_shapes(argument, ShapeKind::Face)) of argument `operand` (0 = a, 1 = b).
struct FaceOrigin {
  int operand = 0;
  int face = 0;
  friend bool operator==(const FaceOrigin&, const FaceOrigin&) = default;
  // NOLINTNEXTLINE(modernize-use-nullptr): clang-tidy 14 misreads a defaulted <=>
  friend auto operator<=>(const FaceOrigin&, const FaceOrigin&) = default;
};

/// A Boolean result with its face history: origins[i] lists, sorted, the argument faces that
/// face i of map_child_shapes(shape, ShapeKind::Face) comes from — one for a split or kept
/// face, several where faces on one surface were merged (the top of two fused boxes).
struct BooleanResult {
  Shape shape;
  std::vector<std::vector<FaceOrigin>> origins;
};

/// boolean_operation, with the history of every result face.
Result<BooleanResult> boolean_operation_with_history(const Shape& a, const Shape& b, BooleanOp op,
                                                     const BooleanOptions& options = {});

/// How two solids' point sets relate, decided with the operation's own intersection stage
/// (exact section curves and shared vertices, then exact ray casting).
enum class Interference {
  Disjoint,        ///< no common point (beyond the tolerance)
  BoundariesMeet,  ///< the boundaries share points: the solids overlap or touch
  Nested,          ///< one solid lies inside the other, their boundaries apart
};
const char* interference_name(Interference i);  ///< "disjoint", "boundaries_meet", "nested"

/// Whether solids a and b (solids or compounds of solids) overlap or touch: the first half
/// of boolean_operation (face–face sections, touching vertices and edges), stopped at the
/// first contact, then a containment test of one vertex of each in the other. Point contact
/// between two smooth faces (a sphere on a plane) reads as Disjoint. Errors as
/// boolean_operation (Unsupported for a surface pair without a section).
Result<Interference> solid_interference(const Shape& a, const Shape& b,
                                        const BooleanOptions& options = {});

/// The union of many solids in one call: a sweep over their bounding boxes finds the groups
/// of solids that can touch (connected components of the box-overlap graph); each group is
/// fused as a balanced tree of pairwise fuses (neighbours in input order first, so each solid
/// takes part in about log2(n) operations; where the fuse of two partial results fails, the
/// second one's halves are fused into the first one in turn, down to single solids) and the
/// groups are gathered in one compound. Solids that touch nothing pass through unchanged (an
/// input compound whose own solids meet is first replaced by their union, as in
/// boolean_operation). Deterministic. Errors as boolean_operation.
Result<Shape> boolean_fuse_all(const std::vector<Shape>& shapes,
                               const BooleanOptions& options = {});

/// fuse: union of all; common: intersection of all; cut: the first minus all the others.
Result<Shape> boolean_fold(const std::vector<Shape>& shapes, BooleanOp op,
                           const BooleanOptions& options = {});

}  // namespace csgtile::kernel
