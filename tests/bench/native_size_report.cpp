// Prints JSON: native-format bytes per primitive against a binary STL of the same primitive
// tessellated at 1 cm chordal tolerance (sizes are deterministic; no timing involved).
// Run: build/tests/bench/native_size_report

#include <cstdio>

#include "csgtile/kernel/native_format.h"
#include "csgtile/kernel/primitives.h"
#include "csgtile/kernel/tessellation.h"

using namespace csgtile::kernel;

int main() {
  struct Item {
    const char* name;
    Result<Shape> shape;
  };
  Item items[] = {
      {"box 1x2x3", make_box(1, 2, 3)},
      {"cylinder r=0.3 h=4 (column)", make_cylinder(0.3, 4)},
      {"cone r=5 h=2.5 (roof)", make_cone(5, 0, 2.5)},
      {"sphere r=1", make_sphere(1)},
      {"torus R=2 r=0.4", make_torus(2, 0.4)},
      {"extrusion L-shape h=12",
       make_extrusion({{0, 0}, {30, 0}, {30, 10}, {10, 10}, {10, 20}, {0, 20}}, {}, 12)},
      {"revolution tower",
       make_revolution({{0, 0}, {4, 0}, {4, 18}, {3, 20}, {0, 21}}, 6.283185307179586)},
  };
  std::printf("{\"chordal_tolerance\": 0.01, \"primitives\": [\n");
  bool first = true;
  for (Item& item : items) {
    if (!item.shape.ok()) return 1;
    const std::string native = write_native(item.shape.value());
    TessellationOptions options;
    options.chordal_tolerance = 0.01;
    auto mesh = tessellate(item.shape.value(), options);
    if (!mesh.ok()) return 1;
    const std::size_t stl = to_binary_stl(mesh.value()).size();
    std::printf(
        "%s  {\"name\": \"%s\", \"native_bytes\": %zu, \"stl_bytes\": %zu, "
        "\"triangles\": %zu, \"stl_over_native\": %.2f}",
        first ? "" : ",\n", item.name, native.size(), stl, mesh->triangles.size(),
        static_cast<double>(stl) / static_cast<double>(native.size()));
    first = false;
  }
  std::printf("\n]}\n");
  return 0;
}
