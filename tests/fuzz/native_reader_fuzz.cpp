// libFuzzer target for the native format reader (CSGTILE_FUZZ=ON, clang).
//
// Every input is parsed twice: as given (magic, version and checksum checks) and re-sealed
// with a correct checksum, so that mutations reach the section and record parsers. Besides
// "no crash, no sanitizer report", whatever parses must survive a round trip:
// write → read gives a structurally equal shape and writing that again gives the same bytes.
// The same holds for models with a CSG history section (read_native_model / write_native_model).
//
// Built a second time with CSGTILE_NATIVE_SEED_GENERATOR defined, the same file is a small
// program that writes a seed corpus of valid files (ctest runs it before the fuzzer).

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "csgtile/kernel/csg.h"
#include "csgtile/kernel/native_format.h"
#include "csgtile/kernel/primitives.h"

namespace {

using namespace csgtile::kernel;

void check_round_trip(std::string_view bytes) {
  auto shape = read_native(bytes);
  if (!shape.ok()) return;
  const std::string written = write_native(shape.value());
  auto again = read_native(written);
  if (!again.ok()) {
    std::fprintf(stderr, "re-read failed: %s\n", again.error().message.c_str());
    __builtin_trap();
  }
  if (!structurally_equal(shape.value(), again.value()) || write_native(again.value()) != written) {
    std::fprintf(stderr, "round trip of an accepted input is not lossless\n");
    __builtin_trap();
  }
}

void check_model_round_trip(std::string_view bytes) {
  auto model = read_native_model(bytes);
  if (!model.ok()) return;
  const std::string written = write_native_model(model.value());
  auto again = read_native_model(written);
  if (!again.ok()) {
    std::fprintf(stderr, "model re-read failed: %s\n", again.error().message.c_str());
    __builtin_trap();
  }
  if (!structurally_equal(model->shape, again->shape) ||
      model->face_sources != again->face_sources || model->nodes.size() != again->nodes.size() ||
      write_native_model(again.value()) != written) {
    std::fprintf(stderr, "round trip of an accepted model is not lossless\n");
    __builtin_trap();
  }
}

}  // namespace

#ifndef CSGTILE_NATIVE_SEED_GENERATOR

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  check_round_trip(bytes);
  check_model_round_trip(bytes);
  if (size >= 4) {
    std::string sealed(bytes);
    const std::uint32_t crc = crc32c(std::string_view(sealed).substr(0, size - 4));
    for (int i = 0; i < 4; ++i) sealed[size - 4 + i] = static_cast<char>(crc >> (8 * i));
    check_round_trip(sealed);
    check_model_round_trip(sealed);
  }
  return 0;
}

#else

namespace {

Shape must(Result<Shape> r) {
  if (!r.ok()) {
    std::fprintf(stderr, "seed model failed: %s\n", r.error().message.c_str());
    std::exit(1);
  }
  return std::move(r).value();
}

}  // namespace

/// Writes one valid file per model into the directory given as the only argument.
int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s <corpus directory>\n", argv[0]);
    return 2;
  }
  const std::filesystem::path dir = argv[1];
  std::filesystem::create_directories(dir);
  const Location placement = Location::translation({1000.5, -20.25, 3}) *
                             Location::rotation({1, 2, 3}, {0.2, -0.4, 1}, 0.7) *
                             Location::scaling(1.5);
  const Shape box = must(make_box(2, 3, 4));
  auto line = std::make_shared<LineCurve>(Vec3(0, 0, 0), Vec3(1, 2, 2));
  const Shape v0 = must(ShapeFactory::vertex({0, 0, 0}, 1e-7));
  const Shape v1 = must(ShapeFactory::vertex(line->point(3), 1e-7));
  const Shape edge = must(ShapeFactory::edge(line, 0, 3, v0, v1, 1e-7));
  auto ellipse = std::make_shared<EllipseCurve>(Frame(), 2.0, 1.0);
  auto polyline =
      std::make_shared<PolylineCurve>(std::vector<Vec3>{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}}, 1e-4);
  const Shape pv0 = must(ShapeFactory::vertex(polyline->point(0), 1e-4));
  const Shape pv1 = must(ShapeFactory::vertex(polyline->point(2), 1e-4));
  const Shape polyline_edge = must(ShapeFactory::edge(polyline, 0, 2, pv0, pv1, 1e-4));
  const Shape wire = must(ShapeFactory::wire({polyline_edge, edge.reversed()}));
  const Shape face = must(
      ShapeFactory::face(std::make_shared<ExtrusionSurface>(ellipse, Vec3(0, 0.3, 1)), {wire},
                         {{std::make_shared<Polyline2d>(std::vector<Vec2>{{0, 0}, {1, 1}, {2, 0}}),
                           std::make_shared<Circle2d>(Vec2(0, 0), 1.0, -1)}},
                         1e-8));
  auto trig = std::make_shared<TrigCurve>(Vec3(1, 0, 0), Vec3(2, 0, 0), Vec3(0, 1, 0.5));
  const Shape tv0 = must(ShapeFactory::vertex(trig->point(0.0), 1e-7));
  const Shape tv1 = must(ShapeFactory::vertex(trig->point(2.0), 1e-7));
  const struct {
    const char* name;
    Shape shape;
  } seeds[] = {
      {"null", Shape()},
      {"vertex", v0},
      {"edge", edge.moved(placement)},
      {"box", box},
      {"box_placed", box.moved(placement)},
      {"box_twice", must(ShapeFactory::compound({box, box.moved(placement).reversed()}))},
      {"cylinder", must(make_cylinder(1, 2)).moved(placement)},
      {"cone", must(make_cone(1, 0, 2))},
      {"sphere", must(make_sphere(1))},
      {"torus", must(make_torus(2, 0.5))},
      {"extrusion",
       must(make_extrusion({{0, 0}, {4, 0}, {4, 3}, {0, 3}}, {{{1, 1}, {2, 1}, {2, 2}}}, 5))},
      {"revolution", must(make_revolution({{1, 0}, {2, 0}, {2, 1}, {1, 1}}, 1.0))},
      {"exotic_face", face},
      {"trig_edge", must(ShapeFactory::edge(trig, 0.0, 2.0, tv0, tv1, 1e-7))},
  };
  for (const auto& seed : seeds) {
    std::ofstream out(dir / (std::string(seed.name) + ".csgt"), std::ios::binary);
    out << write_native(seed.shape);
    check_round_trip(write_native(seed.shape));
  }
  // Models with a CSG history: a fused pair and a drilled block.
  PrimitiveSpec a, b, drill;
  a.size = {1, 1, 1};
  b.size = {1, 1, 1};
  b.placement = Location::translation({0.5, 0.25, 0});
  drill.type = PrimitiveType::Cylinder;
  drill.radius = 0.2;
  drill.height = 3;
  drill.placement = Location::translation({0.5, 0.5, -1});
  auto leaf = [](const PrimitiveSpec& spec, const char* label) {
    auto m = csg_primitive(spec, label);
    if (!m.ok()) std::exit(1);
    return m.value();
  };
  auto fused = csg_boolean(leaf(a, "a"), leaf(b, "b"), BooleanOp::Fuse);
  auto drilled =
      fused.ok() ? csg_boolean(fused.value(), leaf(drill, "drill"), BooleanOp::Cut) : fused;
  if (!drilled.ok()) {
    std::fprintf(stderr, "seed model failed: %s\n", drilled.error().message.c_str());
    return 1;
  }
  for (const auto& [name, model] :
       {std::pair{"csg_fused", fused.value()}, std::pair{"csg_drilled", drilled.value()}}) {
    std::ofstream out(dir / (std::string(name) + ".csgt"), std::ios::binary);
    out << write_native_model(model);
    check_model_round_trip(write_native_model(model));
  }
  std::printf("wrote %zu seeds to %s\n", std::size(seeds) + 2, dir.c_str());
  return 0;
}

#endif
