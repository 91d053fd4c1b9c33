#include "stacked_model.h"

#include "csgtile/kernel/explorer.h"

namespace csgtile::assembly::detail {

using kernel::CsgModel;
using kernel::ShapeKind;

kernel::Result<CsgModel> stacked_model(const std::vector<const CsgModel*>& models) {
  CsgModel out;
  kernel::CsgNode root;
  root.kind = kernel::CsgNodeKind::Fuse;
  std::vector<kernel::Shape> shapes;
  kernel::ShapeIndex known;  // faces of the parts, with their (renumbered) sources
  std::vector<std::vector<kernel::FaceSource>> sources;
  for (const CsgModel* m : models) {
    const int offset = static_cast<int>(out.nodes.size());
    for (kernel::CsgNode node : m->nodes) {
      for (int& c : node.children) c += offset;
      out.nodes.push_back(std::move(node));
    }
    root.children.push_back(static_cast<int>(out.nodes.size()) - 1);
    shapes.push_back(m->shape);
    const kernel::ShapeIndex faces = kernel::map_child_shapes(m->shape, ShapeKind::Face);
    for (std::size_t f = 0; f < faces.size(); ++f) {
      const std::size_t before = known.size();
      if (known.add(faces[f]) != before) continue;
      std::vector<kernel::FaceSource> list =
          f < m->face_sources.size() ? m->face_sources[f] : std::vector<kernel::FaceSource>{};
      for (kernel::FaceSource& s : list) s.node += offset;
      sources.push_back(std::move(list));
    }
  }
  out.nodes.push_back(std::move(root));
  auto compound = kernel::ShapeFactory::compound(std::move(shapes));
  if (!compound.ok()) return compound.error();
  out.shape = compound.value();
  const kernel::ShapeIndex faces = kernel::map_child_shapes(out.shape, ShapeKind::Face);
  out.face_sources.resize(faces.size());
  for (std::size_t f = 0; f < faces.size(); ++f) {
    const std::size_t at = known.find(faces[f]);
    if (at != kernel::ShapeIndex::npos) out.face_sources[f] = sources[at];
  }
  return out;
}

}  // namespace csgtile::assembly::detail
