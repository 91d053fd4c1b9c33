// CGAL baseline for shape detection (issue #22 item 4): CGAL 5.5's Efficient RANSAC (Schnabel
// et al.; planes, cylinders, cones, spheres, tori) on a scan written by `csgtile synth`, given
// the exact normal of every point — the normal of the true surface it was scanned on, at its
// nearest point (truth primitives: boxes and cylinders; ground points get +Z; outliers, which
// have no surface, get +Z too). csgtile's fit is given no normals. Only preprocess() and
// detect() are timed (not reading the file or computing the normals).
//
// Usage: cgal_ransac_bench --las SCAN.las --truth SCENE.json --out CYLINDERS.json
//          [--epsilon 0.03] [--cluster-epsilon 0.1] [--normal-threshold 0.9]
//          [--min-points 100] [--probability 0.05] [--seed 1]
//          [--types plane,cylinder,cone,sphere,torus] [--drop-classes 2,7,18] [--verbose 1]
// Writes the cylinders it found as scene JSON in the truth's frame (each bounded by its
// inliers along the axis; tests/bench/member_recall.py can score them against the truth as
// it scores csgtile's fit) and prints one JSON object: seconds, shapes per type, the share
// of points assigned to a shape, the parameters. tests/bench/fit_baseline.py runs it beside
// `csgtile fit` on the same scan.
// (Built only when CMake finds CGAL: deploy/bench-deps.sh installs it.)

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Random.h>
#include <CGAL/Shape_detection/Efficient_RANSAC.h>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "csgtile/geo/point_reader.h"
#include "csgtile/geo/scene.h"

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using PointWithNormal = std::pair<Kernel::Point_3, Kernel::Vector_3>;
using Points = std::vector<PointWithNormal>;
using PointMap = CGAL::First_of_pair_property_map<PointWithNormal>;
using NormalMap = CGAL::Second_of_pair_property_map<PointWithNormal>;
using Traits = CGAL::Shape_detection::Efficient_RANSAC_traits<Kernel, Points, PointMap, NormalMap>;
using Ransac = CGAL::Shape_detection::Efficient_RANSAC<Traits>;
using Plane = CGAL::Shape_detection::Plane<Traits>;
using Cylinder = CGAL::Shape_detection::Cylinder<Traits>;
using Cone = CGAL::Shape_detection::Cone<Traits>;
using Sphere = CGAL::Shape_detection::Sphere<Traits>;
using Torus = CGAL::Shape_detection::Torus<Traits>;

using csgtile::kernel::PrimitiveSpec;
using csgtile::kernel::PrimitiveType;
using csgtile::kernel::Vec3;

// The outward normal of the true primitive's surface at its point nearest to `p` (world
// frame). Boxes and cylinders only; nullopt for other types.
std::optional<Vec3> surface_normal(const PrimitiveSpec& spec, const Vec3& p) {
  const auto& at = spec.placement;
  const Vec3 q = at.inverse().apply_point(p);
  Vec3 local = Vec3::Zero();
  if (spec.type == PrimitiveType::Box) {
    double best = std::numeric_limits<double>::infinity();
    for (int axis = 0; axis < 3; ++axis) {
      const double lo = std::abs(q[axis]), hi = std::abs(q[axis] - spec.size[axis]);
      if (lo < best) best = lo, local = -Vec3::Unit(axis);
      if (hi < best) best = hi, local = Vec3::Unit(axis);
    }
  } else if (spec.type == PrimitiveType::Cylinder) {
    const double rho = std::hypot(q.x(), q.y());
    const double side = std::abs(rho - spec.radius);
    const double bottom = std::abs(q.z()), top = std::abs(q.z() - spec.height);
    if (side <= bottom && side <= top && rho > 0)
      local = Vec3(q.x() / rho, q.y() / rho, 0.0);
    else
      local = bottom < top ? Vec3(0, 0, -1) : Vec3(0, 0, 1);
  } else {
    return std::nullopt;
  }
  return at.apply_direction(local);
}

const char* arg(int argc, char** argv, const char* name, const char* fallback) {
  for (int i = 1; i + 1 < argc; ++i)
    if (!std::strcmp(argv[i], name)) return argv[i + 1];
  return fallback;
}

// A finite cylinder primitive for a detected infinite one: the axis through its inliers'
// extent along the direction, in the scene's local frame.
PrimitiveSpec bounded_cylinder(const Cylinder& c, const Points& points) {
  const auto axis = c.axis();
  Vec3 o(axis.point().x(), axis.point().y(), axis.point().z());
  Vec3 d(axis.to_vector().x(), axis.to_vector().y(), axis.to_vector().z());
  d.normalize();
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const std::size_t i : c.indices_of_assigned_points()) {
    const auto& pt = points[i].first;
    const double t = (Vec3(pt.x(), pt.y(), pt.z()) - o).dot(d);
    lo = std::min(lo, t);
    hi = std::max(hi, t);
  }
  // A rotation taking +Z to d.
  const Vec3 helper = std::abs(d.z()) < 0.9 ? Vec3::UnitZ() : Vec3::UnitX();
  const Vec3 x = helper.cross(d).normalized();
  const Vec3 y = d.cross(x);
  Eigen::Matrix3d r;
  r.col(0) = x;
  r.col(1) = y;
  r.col(2) = d;
  PrimitiveSpec s;
  s.type = PrimitiveType::Cylinder;
  s.radius = c.radius();
  s.height = std::max(hi - lo, 1e-6);
  s.placement = csgtile::kernel::Location::from_parts(r, 1.0, o + lo * d).value();
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  const char* las_path = arg(argc, argv, "--las", nullptr);
  const char* truth_path = arg(argc, argv, "--truth", nullptr);
  const char* out_path = arg(argc, argv, "--out", nullptr);
  if (!las_path || !truth_path || !out_path) {
    std::fprintf(stderr,
                 "usage: cgal_ransac_bench --las SCAN.las --truth SCENE.json --out "
                 "CYLINDERS.json [--epsilon E] [--cluster-epsilon C] "
                 "[--normal-threshold T] [--min-points N] [--probability P] [--seed S]\n");
    return 2;
  }
  Ransac::Parameters parameters;
  parameters.epsilon = std::atof(arg(argc, argv, "--epsilon", "0.03"));
  parameters.cluster_epsilon = std::atof(arg(argc, argv, "--cluster-epsilon", "0.1"));
  parameters.normal_threshold = std::atof(arg(argc, argv, "--normal-threshold", "0.9"));
  parameters.min_points =
      static_cast<std::size_t>(std::atol(arg(argc, argv, "--min-points", "100")));
  parameters.probability = std::atof(arg(argc, argv, "--probability", "0.05"));
  const unsigned seed = static_cast<unsigned>(std::atol(arg(argc, argv, "--seed", "1")));

  auto truth = csgtile::geo::read_scene(truth_path);
  if (!truth.ok()) {
    std::fprintf(stderr, "cgal_ransac_bench: %s\n", truth.error().message.c_str());
    return 1;
  }
  const Vec3 origin =
      truth->frame ? Vec3(truth->frame->origin[0], truth->frame->origin[1], truth->frame->origin[2])
                   : Vec3::Zero();
  auto reader = csgtile::geo::open_point_file(las_path);
  if (!reader.ok()) {
    std::fprintf(stderr, "cgal_ransac_bench: %s\n", reader.error().message.c_str());
    return 1;
  }
  // The classes left out (the scan's own labels: CGAL is spared separating them).
  std::array<bool, 256> dropped{};
  {
    std::stringstream list(arg(argc, argv, "--drop-classes", "2,7,18"));
    std::string item;
    while (std::getline(list, item, ','))
      if (!item.empty()) dropped[static_cast<std::size_t>(std::atoi(item.c_str()) & 255)] = true;
  }
  Points points;
  csgtile::geo::PointBatch batch;
  for (;;) {
    auto got = reader.value()->read(batch, 1 << 16);
    if (!got.ok()) {
      std::fprintf(stderr, "cgal_ransac_bench: %s\n", got.error().message.c_str());
      return 1;
    }
    if (got.value() == 0) break;
    for (std::size_t i = 0; i < batch.size(); ++i) {
      const auto& pt = batch.points[i];
      if (dropped[pt.classification]) continue;
      const Vec3 p = Vec3(pt.x, pt.y, pt.z) - origin;
      Vec3 n = Vec3::UnitZ();  // ground, when kept; outliers, when kept, have no surface
      const auto index = batch.extra_value(i, "truth_index");
      if (!index) {
        std::fprintf(stderr,
                     "cgal_ransac_bench: %s has no truth_index (not a csgtile synth "
                     "scan)\n",
                     las_path);
        return 1;
      }
      if (*index >= 0) {
        const auto k = static_cast<std::size_t>(*index);
        if (k >= truth->primitives.size()) {
          std::fprintf(stderr, "cgal_ransac_bench: truth_index %zu out of range\n", k);
          return 1;
        }
        const auto normal = surface_normal(truth->primitives[k].spec, p);
        if (!normal) {
          std::fprintf(stderr,
                       "cgal_ransac_bench: truth primitive %zu is neither a box nor a "
                       "cylinder\n",
                       k);
          return 1;
        }
        n = *normal;
      }
      points.emplace_back(Kernel::Point_3(p.x(), p.y(), p.z()),
                          Kernel::Vector_3(n.x(), n.y(), n.z()));
    }
  }

  CGAL::get_default_random() = CGAL::Random(seed);
  Ransac ransac;
  ransac.set_input(points);
  const std::string types = arg(argc, argv, "--types", "plane,cylinder,cone,sphere,torus");
  auto wanted = [&](const char* t) { return types.find(t) != std::string::npos; };
  if (wanted("plane")) ransac.add_shape_factory<Plane>();
  if (wanted("cylinder")) ransac.add_shape_factory<Cylinder>();
  if (wanted("cone")) ransac.add_shape_factory<Cone>();
  if (wanted("sphere")) ransac.add_shape_factory<Sphere>();
  if (wanted("torus")) ransac.add_shape_factory<Torus>();
  const auto t0 = std::chrono::steady_clock::now();
  ransac.preprocess();
  const double preprocess_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ransac.detect(parameters);
  const double total_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  int planes = 0, cylinders = 0, cones = 0, spheres = 0, tori = 0;
  std::size_t assigned = 0;
  csgtile::geo::Scene out;
  out.name = "cgal_efficient_ransac_cylinders";
  out.frame = truth->frame;
  const bool verbose = arg(argc, argv, "--verbose", nullptr) != nullptr;
  for (const auto& shape : ransac.shapes()) {
    assigned += shape->indices_of_assigned_points().size();
    if (verbose)
      std::fprintf(stderr, "%zu points: %s\n", shape->indices_of_assigned_points().size(),
                   shape->info().c_str());
    if (dynamic_cast<Plane*>(shape.get())) ++planes;
    if (dynamic_cast<Cone*>(shape.get())) ++cones;
    if (dynamic_cast<Sphere*>(shape.get())) ++spheres;
    if (dynamic_cast<Torus*>(shape.get())) ++tori;
    if (const auto* c = dynamic_cast<Cylinder*>(shape.get())) {
      ++cylinders;
      csgtile::geo::ScenePrimitive p;
      p.spec = bounded_cylinder(*c, points);
      p.id = "cgal-" + std::to_string(cylinders);
      out.primitives.push_back(std::move(p));
    }
  }
  std::ofstream(out_path) << csgtile::geo::scene_to_json(out);
  std::printf(
      "{\"method\": \"CGAL %s Efficient_RANSAC, exact normals\", \"points\": %zu, "
      "\"seconds\": %.3f, \"preprocess_seconds\": %.3f, \"shapes\": %zu, \"planes\": %d, "
      "\"cylinders\": %d, \"cones\": %d, \"spheres\": %d, \"tori\": %d, "
      "\"assigned_share\": %.4f, \"parameters\": {\"epsilon\": %g, \"cluster_epsilon\": %g, "
      "\"normal_threshold\": %g, \"min_points\": %zu, \"probability\": %g, \"seed\": %u}, "
      "\"cylinders_out\": \"%s\"}\n",
      CGAL_VERSION_STR, points.size(), total_s, preprocess_s, ransac.shapes().size(), planes,
      cylinders, cones, spheres, tori,
      points.empty() ? 0.0 : static_cast<double>(assigned) / static_cast<double>(points.size()),
      parameters.epsilon, parameters.cluster_epsilon, parameters.normal_threshold,
      parameters.min_points, parameters.probability, seed, out_path);
  return 0;
}
