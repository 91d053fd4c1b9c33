#pragma once
/// \file
/// The square grid of a city run: one cell type for the assembly, the georeferenced tiling
/// (geo/tiling.h) and the worker's cell jobs, and the one rule for which cell holds a point.

#include <compare>
#include <cstdint>
#include <string>
#include <string_view>

#include "csgtile/kernel/bounding_box.h"
#include "csgtile/kernel/result.h"

namespace csgtile::kernel {

/// A cell of a grid. Ordered by column, then row: an object whose primitives are anchored in
/// several cells belongs to the least of them.
struct GridCell {
  std::int64_t column = 0;
  std::int64_t row = 0;

  // NOLINTNEXTLINE(modernize-use-nullptr): clang-tidy 14 misreads a defaulted <=>
  std::strong_ordering operator<=>(const GridCell& other) const = default;
  bool operator==(const GridCell& other) const = default;

  /// "c<column>_r<row>", e.g. "c12_r-3": stable, used in object keys and job names.
  std::string name() const;
  /// Inverse of name(). Errors: InvalidArgument naming the text.
  static Result<GridCell> parse(std::string_view text);
};

/// Square cells of side `size` in the XY plane from (origin_x, origin_y). The core of cell
/// (c, r) is [edge_x(c), edge_x(c + 1)) × [edge_y(r), edge_y(r + 1)), half-open; its halo is
/// the core grown by `halo` on every side, closed. Neighbouring cells share their edges bit
/// for bit (each edge is origin + index·size, one rounding).
struct Grid {
  double origin_x = 0.0;
  double origin_y = 0.0;
  double size = 1.0;  ///< > 0
  double halo = 0.0;  ///< ≥ 0

  double edge_x(std::int64_t column) const { return origin_x + static_cast<double>(column) * size; }
  double edge_y(std::int64_t row) const { return origin_y + static_cast<double>(row) * size; }

  /// The cell whose core holds (x, y): the floor of the division, corrected against the
  /// edges so that rounding cannot disagree with them. Precondition: finite and within ±2^52
  /// cells of the origin; otherwise a clamped cell (whose core does not hold the point).
  GridCell cell_of(double x, double y) const;
  /// The cell's halo as a box: its core grown by `halo` in x and y, unbounded in z.
  BoundingBox halo_box(GridCell cell) const;
  /// Whether the xy extent of `box` meets the cell's halo (closed); false for an empty box.
  bool meets_halo(const BoundingBox& box, GridCell cell) const;
  /// Whether the xy extent of `box` lies within the cell's halo; true for an empty box.
  bool within_halo(const BoundingBox& box, GridCell cell) const;
};

}  // namespace csgtile::kernel
