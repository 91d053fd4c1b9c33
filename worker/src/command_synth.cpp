// `csgtile synth SCENE --out FILE.las --truth TRUTH.json [...]`: simulates an airborne or
// terrestrial LIDAR scan of a known scene (geo/synth.h) and writes the points as LAS 1.4 and
// the scanned primitives as scene JSON, both atomically.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "csgtile/geo/crs.h"
#include "csgtile/geo/synth.h"
#include "csgtile/worker/errors.h"

namespace csgtile::worker::detail {

namespace {

using Json = nlohmann::ordered_json;

struct SynthCommand {
  geo::SynthOptions options;
  std::string mode = "airborne";
  int point_format = 7;  // CLI11 would read a uint8_t as a character
  std::string out;
  std::string truth;
  bool json = false;
};

const char* class_name(int c) {
  switch (c) {
    case geo::kClassUnclassified:
      return "unclassified";
    case geo::kClassGround:
      return "ground";
    case geo::kClassBuilding:
      return "building";
    case geo::kClassLowNoise:
      return "low_noise";
    case geo::kClassHighNoise:
      return "high_noise";
    default:
      return "other";
  }
}

int run_synth(SynthCommand c) {
  const auto start = std::chrono::steady_clock::now();
  Json out;
  out["scene"] = c.options.scene;
  out["mode"] = c.mode;
  out["seed"] = c.options.seed;
  auto fail = [&](const Failure& f) { return detail::report_failure("synth", f, c.json, out); };

  // Everything the user typed is checked before any file is touched: usage errors (64).
  const auto& names = geo::synth_scene_names();
  if (std::find(names.begin(), names.end(), c.options.scene) == names.end()) {
    std::string list;
    for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
    return fail(
        {ErrorCode::Usage, "unknown scene \"" + c.options.scene + "\"; valid scenes: " + list});
  }
  if (c.mode == "airborne") {
    c.options.mode = geo::ScanMode::Airborne;
  } else if (c.mode == "terrestrial") {
    c.options.mode = geo::ScanMode::Terrestrial;
  } else {
    return fail(
        {ErrorCode::Usage, "unknown mode \"" + c.mode + "\"; valid modes: airborne, terrestrial"});
  }
  if (c.point_format != 6 && c.point_format != 7) {
    return fail({ErrorCode::Usage, "--point-format must be 6 or 7"});
  }
  c.options.point_format = static_cast<std::uint8_t>(c.point_format);
  if (auto s = c.options.validate(); !s.ok()) return fail({ErrorCode::Usage, s.error().message});
  if (c.options.scene == "random" &&
      (c.options.random_primitives < 1 || c.options.random_primitives > 100000)) {
    return fail({ErrorCode::Usage, "--primitives must be in [1, 100000]"});
  }
  if (auto crs = geo::crs_from_config(c.options.crs); !crs.ok()) {
    return fail({ErrorCode::Usage, "--crs: " + crs.error().message});
  }

  auto summary = geo::synthesize(c.options, c.out, c.truth);
  if (!summary.ok()) return fail(failure_of(summary.error()));
  const geo::SynthSummary& s = summary.value();
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  Json classes = Json::object();
  for (std::size_t k = 0; k < s.points_per_class.size(); ++k) {
    if (s.points_per_class[k] > 0) classes[std::to_string(k)] = s.points_per_class[k];
  }
  Json primitives = Json::object();
  for (int t = 0; t < kernel::kPrimitiveTypeCount; ++t) {
    primitives[kernel::primitive_type_name(static_cast<kernel::PrimitiveType>(t))] =
        s.primitives_per_type[static_cast<std::size_t>(t)];
  }
  out["points"] = s.points;
  out["requested_points"] = c.options.points;
  out["classes"] = classes;
  out["primitives"] = primitives;
  out["passes"] = s.passes;
  if (!s.bounds.empty()) {
    out["bounds"] = {{"min", s.bounds.min}, {"max", s.bounds.max}};
  }
  out["crs"] = c.options.crs;
  out["origin"] = c.options.origin;
  out["las"] = c.out;
  out["truth"] = c.truth;
  out["seconds"] = seconds;
  out["points_per_second"] = seconds > 0 ? static_cast<double>(s.points) / seconds : 0.0;
  out["error"] = nullptr;
  if (c.json) {
    std::cout << out.dump() << "\n";
    return 0;
  }
  int primitive_count = 0;
  for (int n : s.primitives_per_type) primitive_count += n;
  std::printf("%-11s%s (%d primitives), %s, seed %llu\n", "scene", c.options.scene.c_str(),
              primitive_count, c.mode.c_str(), static_cast<unsigned long long>(c.options.seed));
  std::printf("%-11s%llu in %d %s\n", "points", static_cast<unsigned long long>(s.points), s.passes,
              c.options.mode == geo::ScanMode::Airborne ? "strips" : "stations");
  for (std::size_t k = 0; k < s.points_per_class.size(); ++k) {
    if (s.points_per_class[k] == 0) continue;
    std::printf("  class %-3zu %-13s%llu\n", k, class_name(static_cast<int>(k)),
                static_cast<unsigned long long>(s.points_per_class[k]));
  }
  std::printf("%-11s%s\n%-11s%s\n%-11s%.3f s\n", "las", c.out.c_str(), "truth", c.truth.c_str(),
              "time", seconds);
  return 0;
}

}  // namespace

void register_synth(CLI::App& app, Action& action) {
  auto* cmd = app.add_subcommand(
      "synth",
      "Simulate a LIDAR scan of a known scene (gate, city-block, random): LAS 1.4 points with "
      "ground, building and noise classes, plus the ground-truth primitives as scene JSON");
  auto c = std::make_shared<SynthCommand>();
  geo::SynthOptions& o = c->options;
  cmd->add_option("SCENE", o.scene, "Scene: gate, city-block or random")->required();
  cmd->add_option("--out", c->out, "LAS file to write")->required();
  cmd->add_option("--truth", c->truth, "Scene JSON of the scanned primitives to write")->required();
  cmd->add_option("--points", o.points, "Target number of points")->capture_default_str();
  cmd->add_option("--seed", o.seed, "Seed of every random choice")->capture_default_str();
  cmd->add_option("--noise", o.noise_sigma, "Range noise sigma (m)")->capture_default_str();
  cmd->add_option("--outliers", o.outlier_fraction, "Share of pulses returning an outlier")
      ->capture_default_str();
  cmd->add_option("--mode", c->mode, "airborne or terrestrial")->capture_default_str();
  cmd->add_option("--primitives", o.random_primitives, "Primitives of the random scene")
      ->capture_default_str();
  cmd->add_option("--altitude", o.altitude, "Airborne: flying height (m)")->capture_default_str();
  cmd->add_option("--scan-angle", o.scan_angle_deg, "Airborne: half field of view (degrees)")
      ->capture_default_str();
  cmd->add_option("--strips", o.strips, "Airborne: minimum number of strips")
      ->capture_default_str();
  cmd->add_option("--stations", o.stations, "Terrestrial: number of stations")
      ->capture_default_str();
  cmd->add_option("--max-range", o.max_range, "Terrestrial: maximum range (m)")
      ->capture_default_str();
  cmd->add_option("--point-format", c->point_format, "LAS point format: 6, or 7 with RGB")
      ->capture_default_str();
  cmd->add_option("--crs", o.crs, "CRS of the output (EPSG:code[+vertical] or WKT)")
      ->capture_default_str();
  cmd->add_flag("--json", c->json, "Print one JSON object");
  cmd->callback([&action, c] { action = [c] { return run_synth(*c); }; });
}

}  // namespace csgtile::worker::detail
