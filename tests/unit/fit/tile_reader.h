#pragma once
// A real tile's points for the fit's tests: read from ../shared/data in place.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <vector>

#include "csgtile/geo/point_reader.h"
#include "csgtile/kernel/location.h"

namespace csgtile::fit::testing {

struct TilePoints {
  std::vector<kernel::Vec3> points;  ///< less `origin`
  std::vector<std::uint8_t> classes;
  std::vector<std::uint8_t> returns;  ///< of each point's pulse
};

/// Every point of the file (coordinates less `origin`), its class and its pulse's returns;
/// nullopt when it cannot be read.
inline std::optional<TilePoints> read_tile(const std::filesystem::path& path,
                                           const kernel::Vec3& origin = kernel::Vec3::Zero()) {
  auto reader = geo::open_point_file(path);
  if (!reader.ok()) return std::nullopt;
  TilePoints tile;
  geo::PointBatch batch;
  for (;;) {
    auto n = reader.value()->read(batch, 65536);
    if (!n.ok()) return std::nullopt;
    if (n.value() == 0) break;
    for (const geo::Point& p : batch.points) {
      tile.points.push_back(kernel::Vec3(p.x, p.y, p.z) - origin);
      tile.classes.push_back(p.classification);
      tile.returns.push_back(p.number_of_returns);
    }
  }
  return tile;
}

}  // namespace csgtile::fit::testing
