// Prints JSON: the size of each native model given (CSG-BRep with its CSG tree) against the
// same model as a glTF binary (the 3D Tiles content csgtile publishes) and as a binary STL,
// both tessellated at a chordal tolerance (default 1 mm). Sizes are deterministic; no timing.
// Run (issue #9's size figures; tests/bench/model_sizes.sh makes the models):
//   build/tests/bench/model_sizes [--chordal 0.001] MODEL.csgt...

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/native_format.h"
#include "csgtile/kernel/tessellation.h"
#include "export/tile_content.h"

using namespace csgtile;

int main(int argc, char** argv) {
  double chordal = 0.001;
  std::vector<std::string> files;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--chordal") == 0 && i + 1 < argc) {
      chordal = std::atof(argv[++i]);
    } else {
      files.emplace_back(argv[i]);
    }
  }
  if (files.empty() || !(chordal > 0)) {
    std::fprintf(stderr, "usage: model_sizes [--chordal METRES] MODEL.csgt...\n");
    return 64;
  }
  std::printf("{\"chordal_tolerance\": %g, \"models\": [\n", chordal);
  for (std::size_t f = 0; f < files.size(); ++f) {
    std::ifstream in(files[f], std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    auto model = kernel::read_native_model(bytes);
    if (!model.ok()) {
      std::fprintf(stderr, "%s: %s\n", files[f].c_str(), model.error().message.c_str());
      return 65;
    }
    kernel::TessellationOptions options;
    options.chordal_tolerance = chordal;
    auto mesh = kernel::tessellate(model->shape, options);
    if (!mesh.ok()) {
      std::fprintf(stderr, "%s: %s\n", files[f].c_str(), mesh.error().message.c_str());
      return 65;
    }
    const std::size_t stl = kernel::to_binary_stl(mesh.value()).size();
    // The glb: one feature per solid, as the exporter writes a cell.
    std::vector<worker::IndexObject> objects;
    const kernel::ShapeIndex solids =
        kernel::map_child_shapes(model->shape, kernel::ShapeKind::Solid);
    for (std::size_t s = 0; s < solids.size(); ++s) {
      worker::IndexObject o;
      o.id = "solid-" + std::to_string(s);
      o.model.shape = solids[s];
      objects.push_back(std::move(o));
    }
    worker::TileContentOptions glb_options;
    glb_options.chordal_tolerance = chordal;
    auto glb = worker::tile_content(objects, glb_options);
    if (!glb.ok()) {
      std::fprintf(stderr, "%s: glb: %s\n", files[f].c_str(), glb.error().message.c_str());
      return 65;
    }
    std::printf(
        "  {\"model\": \"%s\", \"solids\": %zu, \"csg_nodes\": %zu, \"native_bytes\": %zu, "
        "\"glb_bytes\": %zu, \"stl_bytes\": %zu, \"triangles\": %zu, \"native_over_stl\": %.4f, "
        "\"native_over_glb\": %.4f}%s\n",
        files[f].c_str(), solids.size(), model->nodes.size(), bytes.size(), glb->glb.size(), stl,
        mesh->triangles.size(), static_cast<double>(bytes.size()) / static_cast<double>(stl),
        static_cast<double>(bytes.size()) / static_cast<double>(glb->glb.size()),
        f + 1 < files.size() ? "," : "");
  }
  std::printf("]}\n");
  return 0;
}
