// 3D Tiles (tileset.h): the tile's placement from the Georeferencer, its region, the tileset
// text, and the run's tiles written beside its other exports.

#include "export/tileset.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>

#include "csgtile/worker/publish.h"
#include "export/tile_content.h"

namespace csgtile::worker {

namespace {

using Json = nlohmann::ordered_json;
using kernel::Vec3;

constexpr double kDegree = std::numbers::pi / 180.0;
// Below every radius of curvature of the WGS 84 ellipsoid (6 335 km on the equator's
// meridian): metres → radians conservatively.
constexpr double kSmallRadius = 6.3e6;

// An angle in (−π, π].
double wrapped(double radians) {
  double r = std::remainder(radians, 2.0 * std::numbers::pi);
  if (r <= -std::numbers::pi) r += 2.0 * std::numbers::pi;
  return r;
}

}  // namespace

std::array<double, 16> tile_transform(const geo::TileFrame& frame) {
  const Eigen::Matrix3d r = frame.local_to_ecef.rotation() * frame.local_to_ecef.scale();
  const Vec3& t = frame.local_to_ecef.translation();
  return {r(0, 0), r(1, 0), r(2, 0), 0.0, r(0, 1), r(1, 1), r(2, 1), 0.0,
          r(0, 2), r(1, 2), r(2, 2), 0.0, t.x(),   t.y(),   t.z(),   1.0};
}

Region enu_box_region(const geo::Georeferencer& frame, const Vec3& low, const Vec3& high) {
  // Longitude, latitude and height are smooth over a tile and nearly linear in ENU: their
  // extremes over the box lie at samples up to the curvature between them (height: the drop
  // d²/2R away from the tangent point, whose minimum is the bottom point nearest the
  // vertical; latitude: the meridians' convergence, growing with tan φ).
  std::vector<Vec3> samples;
  for (int i = 0; i <= 2; ++i) {
    for (int j = 0; j <= 2; ++j) {
      for (int k = 0; k <= 2; ++k) {
        samples.emplace_back(low + (high - low).cwiseProduct(Vec3(i, j, k) / 2.0));
      }
    }
  }
  samples.emplace_back(std::clamp(0.0, low.x(), high.x()), std::clamp(0.0, low.y(), high.y()),
                       low.z());
  const geo::GeodeticPoint& origin = frame.frame().origin;
  double west = INFINITY, east = -INFINITY, south = INFINITY, north = -INFINITY;
  double bottom = INFINITY, top = -INFINITY;
  for (const Vec3& s : samples) {
    const geo::GeodeticPoint g = frame.local_to_geodetic(s);
    // Longitudes relative to the origin's: no jump at the antimeridian.
    const double east_of_origin = std::remainder(g.longitude_deg - origin.longitude_deg, 360.0);
    west = std::min(west, east_of_origin);
    east = std::max(east, east_of_origin);
    south = std::min(south, g.latitude_deg);
    north = std::max(north, g.latitude_deg);
    bottom = std::min(bottom, g.height_m);
    top = std::max(top, g.height_m);
  }
  // Height is convex in the horizontal position (extremes at the corners and the sample
  // nearest the vertical: sampled), so its margin covers little more than rounding; latitude
  // and longitude bend with tan φ.
  const double span = std::hypot(high.x() - low.x(), high.y() - low.y());
  const double tan_latitude = std::min(std::abs(std::tan(origin.latitude_deg * kDegree)), 100.0);
  const double margin_height = 0.01 + span * span / (8.0 * kSmallRadius);
  const double margin_m = 0.01 + (1.0 + tan_latitude) * span * span / kSmallRadius;
  const double margin_lat = margin_m / kSmallRadius;
  const double widest = std::max(std::abs(south), std::abs(north)) * kDegree + margin_lat;
  const double margin_lon = margin_m / (kSmallRadius * std::max(std::cos(widest), 1e-6));

  Region region;
  const double lon0 = origin.longitude_deg * kDegree;
  if ((east - west) * kDegree + 2.0 * margin_lon >= 2.0 * std::numbers::pi) {
    region[0] = -std::numbers::pi;
    region[2] = std::numbers::pi;
  } else {
    region[0] = wrapped(lon0 + west * kDegree - margin_lon);
    region[2] = wrapped(lon0 + east * kDegree + margin_lon);
  }
  region[1] = std::max(south * kDegree - margin_lat, -std::numbers::pi / 2);
  region[3] = std::min(north * kDegree + margin_lat, std::numbers::pi / 2);
  region[4] = bottom - margin_height;
  region[5] = top + margin_height;
  return region;
}

std::string tileset_json(const Region& region, const std::array<double, 16>& transform,
                         const TilesetOptions& options) {
  Json root;
  root["transform"] = transform;
  root["boundingVolume"] = {{"region", region}};
  root["geometricError"] = options.tile_geometric_error;
  root["refine"] = "ADD";
  root["content"] = {{"uri", options.content_uri}};
  Json tileset;
  tileset["asset"] = {{"version", "1.1"}};
  tileset["geometricError"] = options.geometric_error;
  tileset["root"] = std::move(root);
  return tileset.dump(2, ' ', false, Json::error_handler_t::replace) + "\n";
}

Failure write_run_tiles(const RunExportOptions& settings, const RunObjects& run,
                        const std::filesystem::path& run_dir, TilesReport& report) {
  report = TilesReport{};
  // A run without tiles leaves none from an earlier run for a reader to mistake for its own.
  auto skip = [&](std::string why) {
    std::error_code ec;
    std::filesystem::remove(run_dir / report.key, ec);
    std::filesystem::remove(run_dir / report.content, ec);
    report.skipped = std::move(why);
    return Failure{};
  };
  if (run.objects.empty()) return skip("the run has no objects");
  if (!run.crs) {
    return skip(
        "the objects have no common EPSG CRS (scene keys \"crs\" and \"origin\"): 3D Tiles "
        "need a georeference");
  }
  auto georef = geo::Georeferencer::create_at(*run.crs, run.origin);
  if (!georef.ok()) {
    return skip("the CRS cannot be placed on WGS 84: " + georef.error().message);
  }

  TileContentOptions options;
  options.to_enu = [frame = georef.value(), origin = run.origin](const Vec3& p) {
    return frame.to_local(origin + p);
  };
  options.chordal_tolerance = settings.chordal_tolerance;
  options.generator = "csgtile " CSGTILE_VERSION;
  auto made = tile_content(run.objects, options);
  if (!made.ok()) {
    if (made.error().code == ErrorCode::GeometryInvalid) {
      return skip(made.error().message);
    }
    return {ErrorCode::Internal, made.error().message};
  }
  TileContent content = std::move(made).value();

  TilesetOptions tileset;
  tileset.content_uri = std::filesystem::path(report.content).filename().string();
  const double metres_per_unit = run.crs->is_projected() ? run.crs->linear_unit.metres : 1.0;
  tileset.tile_geometric_error = settings.chordal_tolerance * metres_per_unit;
  tileset.geometric_error =
      std::max((content.high - content.low).norm(), tileset.tile_geometric_error);
  const std::string text = tileset_json(enu_box_region(georef.value(), content.low, content.high),
                                        tile_transform(georef.value().frame()), tileset);

  // The content first: a tileset is never published naming a missing file.
  if (Failure f = write_file_atomic(run_dir / report.content, content.glb); !f.ok()) return f;
  if (Failure f = write_file_atomic(run_dir / report.key, text); !f.ok()) return f;
  report.written = true;
  report.sha256 = sha256_hex(text);
  report.bytes = text.size();
  report.content_sha256 = sha256_hex(content.glb);
  report.content_bytes = content.glb.size();
  report.objects = content.object_ids.size();
  report.triangles = content.triangles;
  report.warnings = std::move(content.warnings);
  return {};
}

}  // namespace csgtile::worker
