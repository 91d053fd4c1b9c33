#pragma once
/// \file
/// The city grid: square cells in one CRS, each with a halo, and the index saying which input
/// files feed which cell.
///
/// The cells are kernel::GridCell of a kernel::Grid (kernel/grid.h): cell (column, row) has
/// the core [x0 + column·size, x0 + (column+1)·size) × [y0 + row·size, y0 + (row+1)·size),
/// half-open, so every point lies in exactly one core; cell_of agrees with core_bounds bit for
/// bit. Its halo bounds are the core grown by `halo` on every side, closed; halos of
/// neighbours overlap by 2·halo. All coordinates are in the grid CRS's units (feet for a foot
/// CRS, degrees for a geographic one).
///
/// Determinism: cells are ordered by (column, row), GridCell's order; inputs are put in a
/// canonical order (by name, then bounds) before indexing, so the index does not depend on
/// the order files were listed in.

#include <compare>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "csgtile/geo/crs.h"
#include "csgtile/kernel/grid.h"
#include "csgtile/kernel/location.h"
#include "csgtile/kernel/result.h"

namespace csgtile::geo {

/// An axis-aligned 2D box, min <= max.
struct Bounds2 {
  double min_x = 0.0, min_y = 0.0, max_x = 0.0, max_y = 0.0;

  bool is_valid() const;  ///< finite and min <= max
  /// Closed-box overlap test (touching counts).
  bool intersects(const Bounds2& other) const;
};

using kernel::GridCell;

/// Grid definition, in the grid CRS's units.
struct GridSpec {
  double origin_x = 0.0;
  double origin_y = 0.0;
  double cell_size = 1000.0;  ///< > 0
  double halo = 0.0;          ///< >= 0 and < cell_size
};

/// A city grid. Cheap to copy.
class CityGrid {
 public:
  /// Errors: InvalidArgument for a non-finite spec, cell_size <= 0, halo < 0 or
  /// halo >= cell_size; as validate_crs.
  static kernel::Result<CityGrid> create(const Crs& crs, const GridSpec& spec);

  const Crs& crs() const { return crs_; }
  GridSpec spec() const { return {grid_.origin_x, grid_.origin_y, grid_.size, grid_.halo}; }

  /// The cell whose core holds (x, y). Precondition: finite, and within ±2^52 cells of the
  /// origin; otherwise a clamped cell is returned (whose core does not hold the point).
  GridCell cell_of(double x, double y) const;
  Bounds2 core_bounds(GridCell cell) const;
  Bounds2 halo_bounds(GridCell cell) const;
  bool in_core(GridCell cell, double x, double y) const;  ///< half-open
  bool in_halo(GridCell cell, double x, double y) const;  ///< closed
  /// Cells whose halo (or core, when include_halo is false) meets `bounds` (closed), in
  /// (column, row) order. Errors: InvalidArgument for invalid bounds or more than
  /// `max_cells` cells.
  kernel::Result<std::vector<GridCell>> cells_meeting(const Bounds2& bounds, bool include_halo,
                                                      std::size_t max_cells = 1'000'000) const;

 private:
  CityGrid(Crs crs, GridSpec spec)
      : crs_(std::move(crs)), grid_{spec.origin_x, spec.origin_y, spec.cell_size, spec.halo} {}
  Crs crs_;
  kernel::Grid grid_;
};

/// One input file's extent in the grid CRS (a LAS header's bounds, transformed with
/// transform_bounds when the file uses another CRS).
struct InputBounds {
  std::string name;  ///< URL or path: the canonical sort key
  Bounds2 bounds;
};

/// The inputs feeding one cell (its halo meets their bounds): indices into
/// TileIndex::inputs(), ascending.
struct CellInputs {
  GridCell cell;
  std::vector<std::size_t> inputs;
};

/// Which inputs feed which cell.
class TileIndex {
 public:
  /// Errors: InvalidArgument naming an input with invalid bounds, or one meeting more than
  /// `max_cells_per_input` cells.
  static kernel::Result<TileIndex> build(const CityGrid& grid, std::vector<InputBounds> inputs,
                                         std::size_t max_cells_per_input = 1'000'000);

  const CityGrid& grid() const { return grid_; }
  /// The inputs in canonical order (by name, then bounds).
  const std::vector<InputBounds>& inputs() const { return inputs_; }
  /// Every cell fed by at least one input, in (column, row) order.
  const std::vector<CellInputs>& cells() const { return cells_; }
  /// The inputs of one cell (empty when none). O(log cells).
  std::span<const std::size_t> inputs_for(GridCell cell) const;

 private:
  explicit TileIndex(CityGrid grid) : grid_(std::move(grid)) {}
  CityGrid grid_;
  std::vector<InputBounds> inputs_;
  std::vector<CellInputs> cells_;
};

/// Indices of `points` (x, y in the grid CRS) inside a cell's core or halo, ascending: the
/// points of several files are gathered by calling this per file in the index's order.
std::vector<std::size_t> select_points(const CityGrid& grid, GridCell cell,
                                       std::span<const kernel::Vec3> points, bool include_halo);

/// Bounds of `bounds` (in `from`) expressed in `to`: the box around `samples_per_edge` points
/// per edge and an interior grid, transformed by transform_point. Curved images of edges can
/// bulge past the samples by a little; pad the result when that matters.
/// Errors: InvalidArgument for invalid bounds or samples < 2; transform_point's errors.
kernel::Result<Bounds2> transform_bounds(const Crs& from, const Crs& to, const Bounds2& bounds,
                                         int samples_per_edge = 16);

}  // namespace csgtile::geo
