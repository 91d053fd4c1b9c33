#include "checks/run_checks.h"

#include <filesystem>
#include <string>

#include "city/city_jobs.h"
#include "csgtile/geo/crs.h"
#include "csgtile/geo/footprints.h"
#include "fetch/fetch.h"

namespace csgtile::worker::detail {

std::vector<config::Problem> check_run_config(const config::LoadResult& loaded, RunChecks what) {
  std::vector<config::Problem> problems;
  const config::Config& config = *loaded.config;
  // GDAL loads while PROJ reads the CRS.
  const std::jthread gdal = what != RunChecks::CrsOnly && !config.city.footprints.empty()
                                ? geo::load_footprints_in_background()
                                : std::jthread();
  if (!config.run.crs.empty()) {
    auto crs = geo::crs_from_config(config.run.crs);
    if (!crs.ok()) {
      problems.push_back({"run.crs", loaded.line_of("run.crs"),
                          "not a CRS this build reads: " + crs.error().message});
    }
  }
  if (what == RunChecks::CrsOnly) return problems;
  // Footprints: the source opens, has the layer and the attribute, and reprojects to run.crs.
  if (!config.city.footprints.empty()) {
    geo::FootprintQuery query;
    query.target_crs = config.run.crs;
    query.check_only = true;
    auto checked = geo::read_footprints(
        {config.city.footprints, config.city.footprints_layer, config.city.footprints_id}, query);
    if (!checked.ok()) {
      problems.push_back(
          {"city.footprints", loaded.line_of("city.footprints"), checked.error().message});
    }
  }
  for (std::size_t i = 0; i < config.run.inputs.size(); ++i) {
    const std::string& input = config.run.inputs[i];
    const std::string key = "run.inputs[" + std::to_string(i) + "]";
    if (fetch::is_url(input)) continue;  // fetched (and checked) when its job runs
    const std::string& path = input;
    std::error_code ec;
    const auto status = std::filesystem::status(path, ec);
    if (!std::filesystem::exists(status)) {
      problems.push_back(
          {key, loaded.line_of(key),
           path + ": no such file or directory" +
               (ec && ec != std::errc::no_such_file_or_directory ? " (" + ec.message() + ")"
                                                                 : "")});
      continue;
    }
    if (!std::filesystem::is_directory(status)) continue;
    bool readable = false;
    std::filesystem::directory_iterator it(path, ec), end;
    for (; !ec && it != end && !readable; it.increment(ec)) {
      const std::string name = it->path().filename().string();
      std::error_code type_ec;
      if (!it->is_regular_file(type_ec) || name.empty() || name[0] == '.') continue;
      readable = city::is_tile_input(name);
    }
    if (ec) {
      problems.push_back({key, loaded.line_of(key), path + ": cannot list: " + ec.message()});
    } else if (!readable) {
      problems.push_back({key, loaded.line_of(key),
                          path + ": the directory holds no LIDAR tile (.las .laz .ply .pcd "
                                 ".xyz .txt); a directory input is a city of tiles"});
    }
  }
  return problems;
}

}  // namespace csgtile::worker::detail
