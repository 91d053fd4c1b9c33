// Boolean operations: orchestration (see csgtile/kernel/boolean.h for the method).

#include "csgtile/kernel/boolean.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <numbers>
#include <numeric>
#include <set>
#include <string>

#include "boolean/arguments.h"
#include "boolean/classifier.h"
#include "boolean/engine.h"
#include "boolean/fuse_groups.h"
#include "boolean/fuse_tree.h"
#include "boolean/model.h"
#include "csgtile/kernel/broad_phase.h"
#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/mass_properties.h"

namespace csgtile::kernel {

const char* boolean_op_name(BooleanOp op) {
  switch (op) {
    case BooleanOp::Fuse:
      return "fuse";
    case BooleanOp::Common:
      return "common";
    case BooleanOp::Cut:
      return "cut";
  }
  return "unknown";
}

const char* interference_name(Interference i) {
  switch (i) {
    case Interference::Disjoint:
      return "disjoint";
    case Interference::BoundariesMeet:
      return "boundaries_meet";
    case Interference::Nested:
      return "nested";
  }
  return "?";
}

Result<Interference> solid_interference(const Shape& a, const Shape& b,
                                        const BooleanOptions& options) {
  if (a.is_null() || b.is_null())
    return Error{ErrorCode::InvalidArgument, "solid_interference: null shape"};
  BoundingBox ba = bounding_box(a), bb = bounding_box(b);
  ba.enlarge(options.tolerance);
  if (!ba.intersects(bb)) return Interference::Disjoint;
  auto pa = detail::prepare_argument(a, options);
  if (!pa.ok()) return pa.error();
  auto pb = detail::prepare_argument(b, options);
  if (!pb.ok()) return pb.error();
  return detail::run_interference(pa.value().shape, pb.value().shape, options);
}

namespace detail {

Result<Interference> run_interference(const Shape& a, const Shape& b,
                                      const BooleanOptions& options) {
  return BooleanEngine(a, b, BooleanOp::Common, options).interference();
}

Result<Shape> run_engine(const Shape& a, const Shape& b, BooleanOp op,
                         const BooleanOptions& options,
                         std::vector<std::vector<FaceOrigin>>* origins) {
  BooleanEngine engine(a, b, op, options);
  auto shape = engine.run();
  if (shape.ok() && origins != nullptr) *origins = engine.take_origins();
  return shape;
}

}  // namespace detail

Result<Shape> boolean_operation(const Shape& a, const Shape& b, BooleanOp op,
                                const BooleanOptions& options) {
  auto pa = detail::prepare_argument(a, options);
  if (!pa.ok()) return pa.error();
  auto pb = detail::prepare_argument(b, options);
  if (!pb.ok()) return pb.error();
  return detail::run_engine(pa.value().shape, pb.value().shape, op, options, nullptr);
}

Result<BooleanResult> boolean_operation_with_history(const Shape& a, const Shape& b, BooleanOp op,
                                                     const BooleanOptions& options) {
  auto pa = detail::prepare_argument(a, options);
  if (!pa.ok()) return pa.error();
  auto pb = detail::prepare_argument(b, options);
  if (!pb.ok()) return pb.error();
  BooleanResult out;
  auto shape = detail::run_engine(pa.value().shape, pb.value().shape, op, options, &out.origins);
  if (!shape.ok()) return shape.error();
  out.shape = shape.value();
  detail::restate_origins(out.origins, pa.value(), pb.value());
  return out;
}

namespace detail {

std::vector<std::vector<std::size_t>> fuse_groups(const std::vector<Shape>& shapes,
                                                  double tolerance) {
  const std::size_t n = shapes.size();
  std::vector<BoundingBox> boxes(n);
  for (std::size_t i = 0; i < n; ++i) {
    boxes[i] = bounding_box(shapes[i]);
    boxes[i].enlarge(tolerance);
  }
  // Components of the broad phase's pairs; a component's root is its smallest member.
  std::vector<std::size_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  std::function<std::size_t(std::size_t)> root = [&](std::size_t x) {
    return parent[x] == x ? x : parent[x] = root(parent[x]);
  };
  for (const auto& [a, b] : overlapping_boxes(boxes)) {
    const std::size_t ra = root(a), rb = root(b);
    parent[std::max(ra, rb)] = std::min(ra, rb);
  }
  std::map<std::size_t, std::vector<std::size_t>> groups;  // keyed by smallest member: input order
  for (std::size_t i = 0; i < n; ++i) groups[root(i)].push_back(i);
  std::vector<std::vector<std::size_t>> out;
  out.reserve(groups.size());
  for (auto& [r, members] : groups) out.push_back(std::move(members));
  return out;
}

}  // namespace detail

Result<Shape> boolean_fuse_all(const std::vector<Shape>& inputs, const BooleanOptions& options) {
  // Arguments prepared once; partial results are engine results, ready as they are.
  std::vector<Shape> shapes;
  shapes.reserve(inputs.size());
  for (const Shape& s : inputs) {
    auto p = detail::prepare_argument(s, options);
    if (!p.ok()) return p.error();
    shapes.push_back(p.value().shape);
  }
  std::vector<Shape> out;
  for (const auto& members : detail::fuse_groups(shapes, options.tolerance)) {
    std::vector<Shape> group;
    for (std::size_t i : members) group.push_back(shapes[i]);
    if (group.size() == 1) {
      for (const Shape& s : Explorer(group[0], ShapeKind::Solid)) out.push_back(s);
      continue;
    }
    // A balanced tree of fuses (boolean/fuse_tree.h).
    auto fused = detail::fuse_tree(group, [&](const Shape& x, const Shape& y) {
      return detail::run_engine(x, y, BooleanOp::Fuse, options, nullptr);
    });
    if (!fused.ok()) return fused;
    for (const Shape& s : Explorer(fused.value(), ShapeKind::Solid)) out.push_back(s);
  }
  return ShapeFactory::compound(std::move(out));
}

Result<Shape> boolean_fold(const std::vector<Shape>& shapes, BooleanOp op,
                           const BooleanOptions& options) {
  if (shapes.empty()) return ShapeFactory::compound({});
  auto first = detail::prepare_argument(shapes.front(), options);
  if (!first.ok()) return first.error();
  Shape acc = first.value().shape;
  for (std::size_t i = 1; i < shapes.size(); ++i) {
    auto next = detail::prepare_argument(shapes[i], options);
    if (!next.ok()) return next.error();
    // An empty intermediate result: common stays empty, cut stays empty.
    if (map_child_shapes(acc, ShapeKind::Solid).size() == 0) {
      if (op != BooleanOp::Fuse) return acc;
      acc = next.value().shape;
      continue;
    }
    auto r = detail::run_engine(acc, next.value().shape, op, options, nullptr);
    if (!r.ok()) return r;
    acc = r.value();
  }
  if (acc.kind() != ShapeKind::Compound) return ShapeFactory::compound({acc});
  return acc;
}

}  // namespace csgtile::kernel
