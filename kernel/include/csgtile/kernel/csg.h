#pragma once
/// \file
/// CSG history (paper §4): a solid together with the tree of Boolean operations over
/// primitive leaves that made it, and for each of its faces the primitive faces it comes
/// from. Built leaf by leaf (csg_primitive) and operation by operation (csg_boolean,
/// csg_fuse_all, csg_fold); kept in the native format (native_format.h, write_native_model).
///
/// Numbering: nodes are in post-order (every child before its parent; the root is the last
/// node). A face source names a Primitive node and a face of that primitive's solid by its
/// index in map_child_shapes(build_primitive(spec), ShapeKind::Face): stable, since builders
/// are deterministic.

#include <cstdint>
#include <string>
#include <vector>

#include "csgtile/kernel/boolean.h"
#include "csgtile/kernel/primitives.h"

namespace csgtile::kernel {

enum class CsgNodeKind : std::uint8_t { Primitive = 0, Fuse = 1, Common = 2, Cut = 3 };

/// "primitive", "fuse", "common", "cut".
const char* csg_node_kind_name(CsgNodeKind kind);

/// One node of a CSG tree: a primitive leaf, or an operation over earlier nodes (fuse and
/// common: all children; cut: the first child minus the others).
struct CsgNode {
  CsgNodeKind kind = CsgNodeKind::Primitive;
  PrimitiveSpec primitive;    ///< Primitive nodes only
  std::string label;          ///< e.g. the scene primitive's id; may be empty
  std::vector<int> children;  ///< operations only: indices of earlier nodes
};

/// A face of a primitive leaf: node index and face index (see the file comment).
struct FaceSource {
  int node = 0;
  int face = 0;
  friend bool operator==(const FaceSource&, const FaceSource&) = default;
  // NOLINTNEXTLINE(modernize-use-nullptr): clang-tidy 14 misreads a defaulted <=>
  friend auto operator<=>(const FaceSource&, const FaceSource&) = default;
};

/// A solid (or compound of solids) with its CSG tree and face history.
struct CsgModel {
  Shape shape;
  std::vector<CsgNode> nodes;  ///< post-order; nodes.back() is the root (empty: no history)
  /// Per face of map_child_shapes(shape, ShapeKind::Face): its sources, sorted, unique.
  std::vector<std::vector<FaceSource>> face_sources;

  int root() const { return static_cast<int>(nodes.size()) - 1; }
};

/// A primitive leaf: the built solid, one Primitive node, each face its own source.
/// Errors as build_primitive.
Result<CsgModel> csg_primitive(const PrimitiveSpec& spec, std::string label = {},
                               double tolerance = kDefaultTolerance);

/// a op b: the Boolean result, a's nodes then b's (renumbered) then the operation node, and
/// the result faces' sources composed through both arguments' histories.
/// Errors as boolean_operation.
Result<CsgModel> csg_boolean(const CsgModel& a, const CsgModel& b, BooleanOp op,
                             const BooleanOptions& options = {});

/// fuse (union of all), common (intersection of all) or cut (the first minus the others) of
/// many models, recorded as ONE n-ary operation node over their trees. The solids are
/// combined as boolean_fuse_all / boolean_fold do (fuse: groups by bounding boxes, solids
/// that touch nothing pass through). Errors as boolean_operation; InvalidArgument when empty.
Result<CsgModel> csg_combine(const std::vector<CsgModel>& models, BooleanOp op,
                             const BooleanOptions& options = {});

/// Consistency of a model's history: nodes in post-order with valid children (operations
/// have at least one, primitives none), one root reaching every node, one source list per
/// face of the shape, sources naming Primitive nodes and faces within their primitive's face
/// count. Error: CorruptData naming the first problem.
Status check_csg(const CsgModel& model);

}  // namespace csgtile::kernel
