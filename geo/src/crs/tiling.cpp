// The city grid and the tile index.
//
// Invariant: cell_of(x, y) == c exactly when core_bounds(c) holds (x, y) half-open. Both use
// kernel::Grid's edges (origin + index·size, one rounding), whose cell_of corrects the floor
// of the division against them.

#include "csgtile/geo/tiling.h"

#include <algorithm>
#include <cmath>
#include <tuple>
#include <utility>

#include "csgtile/geo/georeference.h"

namespace csgtile::geo {

using kernel::Error;
using kernel::ErrorCode;
using kernel::Result;

bool Bounds2::is_valid() const {
  return std::isfinite(min_x) && std::isfinite(min_y) && std::isfinite(max_x) &&
         std::isfinite(max_y) && min_x <= max_x && min_y <= max_y;
}

bool Bounds2::intersects(const Bounds2& o) const {
  return min_x <= o.max_x && o.min_x <= max_x && min_y <= o.max_y && o.min_y <= max_y;
}

Result<CityGrid> CityGrid::create(const Crs& crs, const GridSpec& spec) {
  if (!std::isfinite(spec.origin_x) || !std::isfinite(spec.origin_y) ||
      !std::isfinite(spec.cell_size) || !std::isfinite(spec.halo)) {
    return Error{ErrorCode::InvalidArgument, "grid: origin, cell size and halo must be finite"};
  }
  if (!(spec.cell_size > 0))
    return Error{ErrorCode::InvalidArgument, "grid: cell size must be positive"};
  if (spec.halo < 0 || spec.halo >= spec.cell_size) {
    return Error{ErrorCode::InvalidArgument,
                 "grid: halo must be >= 0 and smaller than the cell size"};
  }
  if (auto status = validate_crs(crs); !status.ok()) return status.error();
  return CityGrid(crs, spec);
}

GridCell CityGrid::cell_of(double x, double y) const { return grid_.cell_of(x, y); }

Bounds2 CityGrid::core_bounds(GridCell c) const {
  return Bounds2{grid_.edge_x(c.column), grid_.edge_y(c.row), grid_.edge_x(c.column + 1),
                 grid_.edge_y(c.row + 1)};
}

Bounds2 CityGrid::halo_bounds(GridCell c) const {
  const kernel::BoundingBox halo = grid_.halo_box(c);
  return Bounds2{halo.min.x(), halo.min.y(), halo.max.x(), halo.max.y()};
}

bool CityGrid::in_core(GridCell c, double x, double y) const {
  const Bounds2 b = core_bounds(c);
  return x >= b.min_x && x < b.max_x && y >= b.min_y && y < b.max_y;
}

bool CityGrid::in_halo(GridCell c, double x, double y) const {
  const Bounds2 b = halo_bounds(c);
  return x >= b.min_x && x <= b.max_x && y >= b.min_y && y <= b.max_y;
}

Result<std::vector<GridCell>> CityGrid::cells_meeting(const Bounds2& bounds, bool include_halo,
                                                      std::size_t max_cells) const {
  if (!bounds.is_valid()) return Error{ErrorCode::InvalidArgument, "cells_meeting: invalid bounds"};
  const double h = include_halo ? grid_.halo : 0.0;
  // Candidates: cells whose core meets the bounds grown by the halo; then the exact test.
  const double span_x = (bounds.max_x - bounds.min_x + 2 * h) / grid_.size + 3;
  const double span_y = (bounds.max_y - bounds.min_y + 2 * h) / grid_.size + 3;
  if (!(span_x * span_y <= static_cast<double>(max_cells) * 4 + 64)) {
    return Error{ErrorCode::InvalidArgument,
                 "cells_meeting: bounds span more than " + std::to_string(max_cells) + " cells"};
  }
  const GridCell lo = cell_of(bounds.min_x - h, bounds.min_y - h);
  const GridCell hi = cell_of(bounds.max_x + h, bounds.max_y + h);
  std::vector<GridCell> out;
  for (std::int64_t column = lo.column - 1; column <= hi.column + 1; ++column) {
    for (std::int64_t row = lo.row - 1; row <= hi.row + 1; ++row) {
      const GridCell c{column, row};
      const Bounds2 b = include_halo ? halo_bounds(c) : core_bounds(c);
      // Cores are half-open: a box touching a core's upper edge does not meet it.
      const bool meets = include_halo ? b.intersects(bounds)
                                      : (bounds.min_x < b.max_x && b.min_x <= bounds.max_x &&
                                         bounds.min_y < b.max_y && b.min_y <= bounds.max_y);
      if (!meets) continue;
      out.push_back(c);
      if (out.size() > max_cells) {
        return Error{ErrorCode::InvalidArgument, "cells_meeting: bounds span more than " +
                                                     std::to_string(max_cells) + " cells"};
      }
    }
  }
  return out;  // column-major loops: already in (column, row) order
}

Result<TileIndex> TileIndex::build(const CityGrid& grid, std::vector<InputBounds> inputs,
                                   std::size_t max_cells_per_input) {
  std::stable_sort(inputs.begin(), inputs.end(), [](const InputBounds& a, const InputBounds& b) {
    return std::tie(a.name, a.bounds.min_x, a.bounds.min_y, a.bounds.max_x, a.bounds.max_y) <
           std::tie(b.name, b.bounds.min_x, b.bounds.min_y, b.bounds.max_x, b.bounds.max_y);
  });
  std::vector<std::pair<GridCell, std::size_t>> pairs;
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    if (!inputs[i].bounds.is_valid()) {
      return Error{ErrorCode::InvalidArgument, "input '" + inputs[i].name + "' has invalid bounds"};
    }
    auto cells = grid.cells_meeting(inputs[i].bounds, true, max_cells_per_input);
    if (!cells.ok())
      return Error{ErrorCode::InvalidArgument,
                   "input '" + inputs[i].name + "': " + cells.error().message};
    for (const GridCell& c : cells.value()) pairs.emplace_back(c, i);
  }
  std::sort(pairs.begin(), pairs.end());
  TileIndex index(grid);
  index.inputs_ = std::move(inputs);
  for (const auto& [cell, input] : pairs) {
    if (index.cells_.empty() || !(index.cells_.back().cell == cell))
      index.cells_.push_back(CellInputs{cell, {}});
    index.cells_.back().inputs.push_back(input);
  }
  return index;
}

std::span<const std::size_t> TileIndex::inputs_for(GridCell cell) const {
  auto it = std::lower_bound(cells_.begin(), cells_.end(), cell,
                             [](const CellInputs& a, const GridCell& b) { return a.cell < b; });
  if (it == cells_.end() || !(it->cell == cell)) return {};
  return it->inputs;
}

std::vector<std::size_t> select_points(const CityGrid& grid, GridCell cell,
                                       std::span<const kernel::Vec3> points, bool include_halo) {
  std::vector<std::size_t> out;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double x = points[i].x();
    const double y = points[i].y();
    if (include_halo ? grid.in_halo(cell, x, y) : grid.in_core(cell, x, y)) out.push_back(i);
  }
  return out;
}

Result<Bounds2> transform_bounds(const Crs& from, const Crs& to, const Bounds2& bounds,
                                 int samples_per_edge) {
  if (!bounds.is_valid())
    return Error{ErrorCode::InvalidArgument, "transform_bounds: invalid bounds"};
  if (samples_per_edge < 2 || samples_per_edge > 10000) {
    return Error{ErrorCode::InvalidArgument,
                 "transform_bounds: samples per edge must be in [2, 10000]"};
  }
  Bounds2 out{INFINITY, INFINITY, -INFINITY, -INFINITY};
  const int n = samples_per_edge;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const double x = bounds.min_x + (bounds.max_x - bounds.min_x) * i / (n - 1);
      const double y = bounds.min_y + (bounds.max_y - bounds.min_y) * j / (n - 1);
      auto p = transform_point(from, to, kernel::Vec3(x, y, 0.0));
      if (!p.ok()) return p.error();
      out.min_x = std::min(out.min_x, p.value().x());
      out.min_y = std::min(out.min_y, p.value().y());
      out.max_x = std::max(out.max_x, p.value().x());
      out.max_y = std::max(out.max_y, p.value().y());
    }
  }
  return out;
}

}  // namespace csgtile::geo
