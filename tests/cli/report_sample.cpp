// report_sample RUN_DIR GLB [GLB...]: writes a run report (export/report.h) into RUN_DIR with
// one cell per GLB ("0_0", "1_0", …) and one more cell whose GLB is missing, for
// tests/cli/report_chromium.py to open in headless Chromium. Each cell's object footprint
// and bounds come from the GLB's POSITION bounds (glTF y up: x east, −z north), so the top
// view matches what the 3D view shows. Exit 0, or 1 with the failure on stderr.

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <string>

#include <nlohmann/json.hpp>

#include "export/report.h"

namespace {

using csgtile::worker::ReportCell;
using csgtile::worker::ReportInput;
using csgtile::worker::ReportObject;

// POSITION min/max (x and −z) of the GLB's first mesh primitive; false when not found.
bool glb_footprint(const std::string& path, std::array<double, 4>& box) {
  std::ifstream file(path, std::ios::binary);
  const std::string bytes{std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>()};
  if (bytes.size() < 20 || bytes.compare(0, 4, "glTF") != 0) return false;
  std::uint32_t json_length = 0;
  std::memcpy(&json_length, bytes.data() + 12, 4);  // little-endian hosts only: a test tool
  if (bytes.size() < 20 + static_cast<std::size_t>(json_length)) return false;
  const auto gltf = nlohmann::json::parse(bytes.substr(20, json_length), nullptr, false);
  if (gltf.is_discarded()) return false;
  const auto& accessor =
      gltf["accessors"][gltf["meshes"][0]["primitives"][0]["attributes"]["POSITION"].get<int>()];
  const auto& low = accessor["min"];
  const auto& high = accessor["max"];
  box = {low[0].get<double>(), -high[2].get<double>(), high[0].get<double>(),
         -low[2].get<double>()};
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::cerr << "usage: report_sample RUN_DIR GLB [GLB...]\n";
    return 1;
  }
  const std::filesystem::path run_dir = argv[1];
  ReportInput in;
  in.run = "report-sample";
  in.crs = "EPSG:28992+5709";
  double x = 0.0;
  for (int i = 2; i < argc; ++i) {
    std::array<double, 4> box{};
    if (!glb_footprint(argv[i], box)) {
      std::cerr << "report_sample: " << argv[i] << " is not a GLB with POSITION bounds\n";
      return 1;
    }
    // Cells side by side, each 20 m larger than its model.
    const double size = std::max(box[2] - box[0], box[3] - box[1]) + 20.0;
    const double dx = x - box[0] + 10.0, dy = -box[1] + 10.0;
    ReportCell cell;
    cell.id = std::to_string(i - 2) + "_0";
    cell.bounds = {x, 0.0, x + size, size};
    cell.glb_path = argv[i];
    cell.validation = {"gltf: written"};
    ReportObject object;
    object.id = "model-" + cell.id;
    object.primitive_types = {"box", "cylinder"};
    object.volume = 100.0;
    object.valid = true;
    object.footprint = {{{box[0] + dx, box[1] + dy},
                         {box[2] + dx, box[1] + dy},
                         {box[2] + dx, box[3] + dy},
                         {box[0] + dx, box[3] + dy}}};
    cell.objects.push_back(object);
    in.cells.push_back(cell);
    x += size;
  }
  ReportCell missing;
  missing.id = std::to_string(argc - 2) + "_0";
  missing.bounds = {x, 0.0, x + 50.0, 50.0};
  missing.glb_path = (run_dir / "tiles" / "missing.glb").string();
  missing.validation = {"gltf: missing (on purpose)"};
  in.cells.push_back(missing);
  in.primitives_per_type = {{"box", 8}, {"cylinder", 5}, {"sphere", 2}};
  in.fit_rms = {0.002, 0.003, 0.004, 0.004, 0.005, 0.007, 0.009, 0.012, 0.015, 0.021};
  in.validation_counts = {{"objects valid", static_cast<long long>(argc - 2)}};
  in.dead_jobs = {"fit/9: sample dead job <kept escaped>"};
  in.stage_seconds = {{"fit", 1.5}, {"assemble", 0.75}, {"index", 0.25}};

  csgtile::worker::ReportFiles files;
  if (auto failure = csgtile::worker::write_run_report(in, run_dir, files); !failure.ok()) {
    std::cerr << "report_sample: " << failure.message << "\n";
    return 1;
  }
  for (const auto& key : files.keys) std::cout << key << "\n";
  for (const auto& key : files.nondeterministic_keys) std::cout << key << " (not deterministic)\n";
  return 0;
}
