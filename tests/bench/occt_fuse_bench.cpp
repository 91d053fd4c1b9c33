// OpenCASCADE baseline for the Booleans (issue #22 item 3): the same primitives fused by
// csgtile and by OCCT 7.6 from Debian, each side in its own forked child of this process (one
// after the other, one thread each, so that each side's peak memory is its own), and the
// volumes compared. OCCT's side is BRepAlgoAPI_Fuse with the first solid as argument and all
// the others as tools: one run of its General Fuse algorithm over every solid, then the union
// built from its splits (SetRunParallel(false)). Its shapes are built from the same
// kernel::PrimitiveSpec values by BRepPrimAPI (box, cylinder, cone, sphere, torus) and a
// prism of a planar face (extrusion), placed by the same 3×4 matrix. The fuse timings
// exclude building the solids on both sides (build_seconds); csgtile's assembly starts from
// the specs, so its ratio counts OCCT's building too.
//
// Scenes:
//  - city_block N (tests/support/random_city.h): csgtile's n-ary fuse (boolean_fuse_all);
//  - assembly N (random_city: rotated blocks, L-shaped extrusions, wings, roofs, columns):
//    csgtile's assembly (assembly::assemble, voxel culling on, one thread), whose objects'
//    volumes add up to the union's;
//  - gate (the 229 true primitives of `csgtile synth gate`): the n-ary fuse.
// Prints one JSON object: per scene both sides' seconds, volumes, solids and peak RSS, the
// ratio occt_seconds / csgtile_seconds and the volumes' relative difference.
// Each side runs --repeat times (default 3, alternating) and its fastest run is reported (a
// failed run is reported as such). Exit 1 when a side fails or the two volumes differ by more
// than 1e-8 relative: OCCT is then an independent check of csgtile's results (the ctest
// bench.occt_volumes_agree runs small scenes).
// Run: build/tests/bench/occt_fuse_bench [--scenes city_block:1000,city_block:5000,
//        assembly:5000,gate] [--repeat 3] [--sides both|csgtile|occt]
// (--sides csgtile runs csgtile's side alone, e.g. under a profiler; the ratio is then -1)
// (built only when CMake finds OpenCASCADE: deploy/bench-deps.sh installs it).

#include <BRepAlgoAPI_Fuse.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_MakePolygon.hxx>
#include <BRepGProp.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCone.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepPrimAPI_MakePrism.hxx>
#include <BRepPrimAPI_MakeSphere.hxx>
#include <BRepPrimAPI_MakeTorus.hxx>
#include <GProp_GProps.hxx>
#include <Standard_Failure.hxx>
#include <Standard_Version.hxx>
#include <TopExp_Explorer.hxx>
#include <TopLoc_Location.hxx>
#include <TopTools_ListOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Shape.hxx>
#include <gp_Trsf.hxx>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "child_run.h"
#include "csgtile/assembly/assembly.h"
#include "csgtile/geo/synth.h"
#include "csgtile/kernel/boolean.h"
#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/mass_properties.h"
#include "csgtile/kernel/primitives.h"
#include "random_city.h"

using namespace csgtile;
using kernel::PrimitiveSpec;
using kernel::PrimitiveType;

namespace {

// What one side reports from its child.
struct Side {
  int ok = 0;
  double seconds = 0;        // the fuse (csgtile's assembly: from the specs, building included)
  double build_seconds = 0;  // building the solids from the specs (not in `seconds`)
  double volume = 0;
  long long solids = 0;
  long peak_kb = 0;
  char error[160] = {};
};

// Runs `work` in a forked child (tests/support/child_run.h): its peak memory is its own.
Side in_child(const std::function<Side()>& work) {
  const auto run = test::run_in_child(work);
  Side out = run.result.value_or(Side{});
  out.peak_kb = run.peak_kb;
  if (!run.result) {
    out.ok = 0;
    std::snprintf(out.error, sizeof out.error, "child ended with status %d", run.status);
  }
  return out;
}

// Relative difference of the two unions' volumes beyond which the sides disagree (both exact
// to rounding: 1e-13 on the city blocks, 5e-11 on the gate's cylinders).
constexpr double kVolumesAgree = 1e-8;

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// ---------------------------------------------------------------- OCCT's side

TopoDS_Shape occt_extrusion(const PrimitiveSpec& s) {
  auto ring = [](const std::vector<kernel::Vec2>& pts) {
    BRepBuilderAPI_MakePolygon poly;
    for (const auto& p : pts) poly.Add(gp_Pnt(p.x(), p.y(), 0.0));
    poly.Close();
    return poly.Wire();
  };
  // Counter-clockwise outer ring, clockwise holes: the face's normal is +Z.
  auto area = [](const std::vector<kernel::Vec2>& pts) {
    double a = 0;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const auto& p = pts[i];
      const auto& q = pts[(i + 1) % pts.size()];
      a += p.x() * q.y() - q.x() * p.y();
    }
    return a;
  };
  auto oriented = [&](std::vector<kernel::Vec2> pts, bool ccw) {
    if ((area(pts) > 0) != ccw) std::reverse(pts.begin(), pts.end());
    return pts;
  };
  BRepBuilderAPI_MakeFace face(ring(oriented(s.profile, true)), true);
  for (const auto& hole : s.holes) face.Add(ring(oriented(hole, false)));
  return BRepPrimAPI_MakePrism(face.Face(), gp_Vec(0, 0, s.height)).Shape();
}

TopoDS_Shape occt_solid(const PrimitiveSpec& s) {
  if (!s.clips.empty()) throw std::runtime_error("clipped primitives are not in the scenes");
  TopoDS_Shape shape;
  switch (s.type) {
    case PrimitiveType::Box:
      shape = BRepPrimAPI_MakeBox(s.size.x(), s.size.y(), s.size.z()).Shape();
      break;
    case PrimitiveType::Cylinder:
      shape = BRepPrimAPI_MakeCylinder(s.radius, s.height).Shape();
      break;
    case PrimitiveType::Cone:
      shape = BRepPrimAPI_MakeCone(s.radius, s.radius2, s.height).Shape();
      break;
    case PrimitiveType::Sphere:
      shape = BRepPrimAPI_MakeSphere(s.radius).Shape();
      break;
    case PrimitiveType::Torus:
      shape = BRepPrimAPI_MakeTorus(s.radius, s.radius2).Shape();
      break;
    case PrimitiveType::Extrusion:
      shape = occt_extrusion(s);
      break;
    default:
      throw std::runtime_error("primitive type not in the scenes");
  }
  const auto m = s.placement.matrix();
  gp_Trsf t;
  t.SetValues(m(0, 0), m(0, 1), m(0, 2), m(0, 3), m(1, 0), m(1, 1), m(1, 2), m(1, 3), m(2, 0),
              m(2, 1), m(2, 2), m(2, 3));
  return shape.Moved(TopLoc_Location(t));
}

Side occt_fuse(const std::vector<PrimitiveSpec>& specs) {
  Side out;
  try {
    const auto t_build = std::chrono::steady_clock::now();
    std::vector<TopoDS_Shape> solids;
    for (const auto& s : specs) solids.push_back(occt_solid(s));
    out.build_seconds = seconds_since(t_build);
    const auto t0 = std::chrono::steady_clock::now();
    TopTools_ListOfShape arguments, tools;
    arguments.Append(solids.front());
    for (std::size_t i = 1; i < solids.size(); ++i) tools.Append(solids[i]);
    BRepAlgoAPI_Fuse fuse;
    fuse.SetArguments(arguments);
    fuse.SetTools(tools);
    fuse.SetRunParallel(false);
    fuse.Build();
    out.seconds = seconds_since(t0);
    if (fuse.HasErrors() || !fuse.IsDone()) {
      std::ostringstream report;
      fuse.DumpErrors(report);
      std::snprintf(out.error, sizeof out.error, "OCCT fuse failed: %s", report.str().c_str());
      return out;
    }
    GProp_GProps props;
    BRepGProp::VolumeProperties(fuse.Shape(), props);
    out.volume = props.Mass();
    for (TopExp_Explorer e(fuse.Shape(), TopAbs_SOLID); e.More(); e.Next()) ++out.solids;
    out.ok = 1;
  } catch (const std::exception& e) {
    std::snprintf(out.error, sizeof out.error, "%s", e.what());
  } catch (const Standard_Failure& e) {
    std::snprintf(out.error, sizeof out.error, "OCCT: %s", e.GetMessageString());
  }
  return out;
}

// ---------------------------------------------------------------- csgtile's side

Side csgtile_fuse(const std::vector<PrimitiveSpec>& specs) {
  Side out;
  const auto t_build = std::chrono::steady_clock::now();
  std::vector<kernel::Shape> solids;
  for (const auto& s : specs) {
    auto b = kernel::build_primitive(s);
    if (!b.ok()) {
      std::snprintf(out.error, sizeof out.error, "%s", b.error().message.c_str());
      return out;
    }
    solids.push_back(std::move(b).value());
  }
  out.build_seconds = seconds_since(t_build);
  const auto t0 = std::chrono::steady_clock::now();
  auto fused = kernel::boolean_fuse_all(solids);
  out.seconds = seconds_since(t0);
  if (!fused.ok()) {
    std::snprintf(out.error, sizeof out.error, "%s", fused.error().message.c_str());
    return out;
  }
  out.volume = kernel::mass_properties(fused.value()).volume;
  out.solids = static_cast<long long>(
      kernel::count_shapes(fused.value())[static_cast<int>(kernel::ShapeKind::Solid)]);
  out.ok = 1;
  return out;
}

Side csgtile_assemble(const std::vector<PrimitiveSpec>& specs) {
  Side out;
  std::vector<assembly::AssemblyPrimitive> prims;
  for (std::size_t i = 0; i < specs.size(); ++i)
    prims.push_back({specs[i], "p" + std::to_string(i)});
  assembly::AssemblyOptions o;
  o.threads = 1;
  const auto t0 = std::chrono::steady_clock::now();
  auto a = assembly::assemble(prims, o);
  out.seconds = seconds_since(t0);
  if (!a.ok()) {
    std::snprintf(out.error, sizeof out.error, "%s", a.error().message.c_str());
    return out;
  }
  for (const auto& obj : a->objects) {
    out.volume += obj.volume;
    out.solids += obj.fused ? 1 : static_cast<long long>(obj.primitives.size());
  }
  out.ok = 1;
  return out;
}

// ---------------------------------------------------------------- scenes

struct Scene {
  std::string name;
  int n = 0;
  bool assembly = false;
};

std::vector<PrimitiveSpec> primitives_of(const Scene& scene) {
  if (scene.name == "gate") {
    std::vector<PrimitiveSpec> out;
    auto gate = geo::make_synth_scene("gate", 1);
    if (!gate.ok()) throw std::runtime_error(gate.error().message);
    for (const auto& p : gate.value().scene.primitives) out.push_back(p.spec);
    return out;
  }
  return scene.assembly ? test::random_city(scene.n, 42) : test::city_block(scene.n, 42);
}

std::vector<Scene> parse_scenes(const std::string& list) {
  std::vector<Scene> out;
  std::stringstream in(list);
  std::string item;
  while (std::getline(in, item, ',')) {
    Scene s;
    const auto colon = item.find(':');
    s.name = item.substr(0, colon);
    if (colon != std::string::npos) s.n = std::atoi(item.c_str() + colon + 1);
    s.assembly = s.name == "assembly";
    if (s.name != "gate" && s.name != "assembly" && s.name != "city_block")
      throw std::runtime_error("unknown scene '" + s.name + "' (city_block:N, assembly:N, gate)");
    if (s.name != "gate" && s.n <= 0) throw std::runtime_error("scene '" + item + "' needs :N");
    out.push_back(s);
  }
  return out;
}

void print_side(const char* name, const Side& s) {
  std::printf(
      "\"%s\": {\"ok\": %s, \"seconds\": %.4f, \"build_seconds\": %.4f, \"volume\": %.10g, "
      "\"solids\": %lld, "
      "\"peak_rss_mb\": %.1f, \"error\": \"",
      name, s.ok ? "true" : "false", s.seconds, s.build_seconds, s.volume, s.solids,
      s.peak_kb / 1024.0);
  for (const char* c = s.error; *c; ++c)
    if (*c != '"' && *c != '\\' && static_cast<unsigned char>(*c) >= 0x20) std::putchar(*c);
  std::printf("\"}");
}

}  // namespace

int main(int argc, char** argv) {
  std::string list = "city_block:1000,city_block:5000,assembly:5000,gate";
  int repeat = 3;
  std::string sides = "both";
  for (int i = 1; i + 1 < argc; ++i) {
    if (!std::strcmp(argv[i], "--scenes"))
      list = argv[++i];
    else if (!std::strcmp(argv[i], "--repeat"))
      repeat = std::max(1, std::atoi(argv[++i]));
    else if (!std::strcmp(argv[i], "--sides"))
      sides = argv[++i];
  }
  const bool run_ours = sides != "occt", run_occt = sides != "csgtile";
  std::vector<Scene> scenes;
  try {
    scenes = parse_scenes(list);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "occt_fuse_bench: %s\n", e.what());
    return 2;
  }
  std::printf(
      "{\"benchmark\": \"occt_fuse_baseline\", \"occt\": \"%s\", \"repeat\": %d, \"runs\": [\n",
      OCC_VERSION_COMPLETE, repeat);
  bool all_ok = true;
  for (std::size_t k = 0; k < scenes.size(); ++k) {
    const Scene& scene = scenes[k];
    std::vector<PrimitiveSpec> specs;
    try {
      specs = primitives_of(scene);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "occt_fuse_bench: %s: %s\n", scene.name.c_str(), e.what());
      return 1;
    }
    // Best of `repeat` children per side (the sides alternate: one machine state for both).
    Side ours, occt;
    for (int r = 0; r < repeat; ++r) {
      const Side a = run_ours ? in_child([&] {
        return scene.assembly ? csgtile_assemble(specs) : csgtile_fuse(specs);
      })
                              : Side{};
      const Side b = run_occt ? in_child([&] { return occt_fuse(specs); }) : Side{};
      if (r == 0 || !a.ok || (ours.ok && a.seconds < ours.seconds)) ours = a;
      if (r == 0 || !b.ok || (occt.ok && b.seconds < occt.seconds)) occt = b;
    }
    const bool both = ours.ok && occt.ok;
    // The assembly starts from the specs (it builds its solids): OCCT's building counts too.
    const double theirs = scene.assembly ? occt.build_seconds + occt.seconds : occt.seconds;
    const double difference =
        both ? std::abs(ours.volume - occt.volume) / std::max(occt.volume, 1e-300) : -1.0;
    const bool ran_ok = (!run_ours || ours.ok) && (!run_occt || occt.ok);
    if (difference > kVolumesAgree) {
      std::fprintf(stderr,
                   "occt_fuse_bench: %s: the volumes differ by %.3g (csgtile %.17g, "
                   "OCCT %.17g)\n",
                   scene.name.c_str(), difference, ours.volume, occt.volume);
    }
    all_ok = all_ok && ran_ok && difference <= kVolumesAgree;
    std::printf("%s  {\"scene\": \"%s\", \"n\": %zu, \"csgtile_method\": \"%s\", ", k ? ",\n" : "",
                scene.name.c_str(), specs.size(),
                scene.assembly ? "assembly::assemble" : "boolean_fuse_all");
    print_side("csgtile", ours);
    std::printf(", ");
    print_side("occt", occt);
    std::printf(", \"occt_over_csgtile\": %.2f, \"volume_relative_difference\": %.3g}",
                both && ours.seconds > 0 ? theirs / ours.seconds : -1.0, difference);
    std::fflush(stdout);
  }
  std::printf("\n]}\n");
  return all_ok ? 0 : 1;
}
