// Heights and LoD1.2 / LoD1.3 block models of the objects an export writes (topology_index.h).

#include <tbb/parallel_for.h>

#include "csgtile/kernel/explorer.h"
#include "export/topology_index.h"

namespace csgtile::worker {

void add_building_lods(std::vector<IndexObject>& objects, double chordal_tolerance,
                       double linear_tolerance) {
  assembly::BlockModelOptions options;
  options.chordal_tolerance = chordal_tolerance;
  options.tolerance = linear_tolerance;
  tbb::parallel_for(std::size_t{0}, objects.size(), [&](std::size_t i) {
    IndexObject& o = objects[i];
    o.heights.reset();
    o.lod12.reset();
    o.lod12_error.clear();
    o.lod13.reset();
    o.lod13_error.clear();
    auto blocks = assembly::building_blocks(o.model, options, shared_mesh(o, chordal_tolerance));
    if (blocks.ok()) {
      assembly::BuildingBlocks& b = blocks.value();
      o.heights = b.heights;
      o.lod12 = std::move(b.lod12);
      o.lod13 = std::move(b.lod13);
      if (b.lod13_error) {
        o.lod13_error = kernel::error_code_name(b.lod13_error->code) + std::string(": ") +
                        b.lod13_error->message;
      }
      return;
    }
    // Not a building (another primitive among its leaves): no block, its heights still.
    if (blocks.error().code != kernel::ErrorCode::InvalidArgument) {
      o.lod12_error =
          kernel::error_code_name(blocks.error().code) + std::string(": ") + blocks.error().message;
    }
    auto heights = assembly::building_heights(o.model.shape, chordal_tolerance,
                                              shared_mesh(o, chordal_tolerance));
    if (heights.ok()) o.heights = heights.value();
  });
}

void move_model(kernel::CsgModel& model, const kernel::Location& by) {
  model.shape = model.shape.moved(by);
  for (kernel::CsgNode& node : model.nodes) {
    if (node.kind == kernel::CsgNodeKind::Primitive)
      node.primitive.placement = by * node.primitive.placement;
  }
}

bool is_building(const IndexObject& object) {
  return object.lod12.has_value() || !object.lod12_error.empty();
}

std::string lod_reached(const IndexObject& object) {
  if (!is_building(object)) return {};
  const bool one_solid =
      object.fuse_error.empty() &&
      kernel::map_child_shapes(object.model.shape, kernel::ShapeKind::Solid).size() == 1;
  if (one_solid) return "2.2";
  return object.lod13 ? "1.3" : object.lod12 ? "1.2" : "";
}

std::string lod22_failure(const IndexObject& object) {
  return object.fuse_error.empty() ? std::string("the model is in several solids")
                                   : object.fuse_error;
}

std::string building_problem(const IndexObject& object) {
  std::string out;
  if (is_building(object) && lod_reached(object) != "2.2") {
    out = "LoD2.2: " + lod22_failure(object);
  }
  if (!object.lod12_error.empty()) {
    out += (out.empty() ? "" : "; ") + std::string("LoD1.2: ") + object.lod12_error;
  }
  if (!object.lod13_error.empty()) {
    out += (out.empty() ? "" : "; ") + std::string("LoD1.3: ") + object.lod13_error;
  }
  return out;
}

}  // namespace csgtile::worker
