#pragma once
// An IndexObject for the exporters' tests: the model with one PrimitiveInfo per primitive
// leaf of its CSG tree (node, label as id, type name).

#include <string>
#include <utility>

#include "export/topology_index.h"

namespace csgtile::test {

inline worker::IndexObject index_object(const std::string& id, kernel::CsgModel model) {
  worker::IndexObject o;
  o.id = id;
  o.model = std::move(model);
  for (std::size_t n = 0; n < o.model.nodes.size(); ++n) {
    const kernel::CsgNode& node = o.model.nodes[n];
    if (node.kind != kernel::CsgNodeKind::Primitive) continue;
    worker::PrimitiveInfo p;
    p.node = static_cast<int>(n);
    p.id = node.label;
    p.type = kernel::primitive_type_name(node.primitive.type);
    o.primitives.push_back(p);
  }
  return o;
}

}  // namespace csgtile::test
