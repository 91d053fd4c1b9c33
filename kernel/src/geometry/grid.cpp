#include "csgtile/kernel/grid.h"

#include <charconv>
#include <cmath>
#include <system_error>

namespace csgtile::kernel {

std::string GridCell::name() const {
  return "c" + std::to_string(column) + "_r" + std::to_string(row);
}

Result<GridCell> GridCell::parse(std::string_view text) {
  auto fail = [&] {
    return Error{ErrorCode::InvalidArgument,
                 "cell id '" + std::string(text) + "' is not c<column>_r<row>"};
  };
  if (text.size() < 5 || text[0] != 'c') return fail();
  const auto sep = text.find("_r");
  if (sep == std::string_view::npos) return fail();
  GridCell cell;
  const char* b1 = text.data() + 1;
  const char* e1 = text.data() + sep;
  const char* b2 = text.data() + sep + 2;
  const char* e2 = text.data() + text.size();
  auto r1 = std::from_chars(b1, e1, cell.column);
  auto r2 = std::from_chars(b2, e2, cell.row);
  if (r1.ec != std::errc() || r1.ptr != e1 || r2.ec != std::errc() || r2.ptr != e2 || b1 == e1 ||
      b2 == e2) {
    return fail();
  }
  return cell;
}

GridCell Grid::cell_of(double x, double y) const {
  auto index = [&](double v, double origin, auto edge) -> std::int64_t {
    const double q = std::floor((v - origin) / size);
    // Outside the precondition (NaN, or beyond 2^52 cells where edges stop being distinct
    // doubles) a clamped index instead of overflowing the cast or looping.
    if (!(std::fabs(q) < 4503599627370496.0))
      return q > 0 ? (std::int64_t{1} << 52) : -(std::int64_t{1} << 52);
    auto i = static_cast<std::int64_t>(q);
    // The division is off by at most one cell; a few steps settle it against the edges.
    for (int step = 0; step < 4 && v < edge(i); ++step) --i;
    for (int step = 0; step < 4 && v >= edge(i + 1); ++step) ++i;
    return i;
  };
  GridCell cell;
  cell.column = index(x, origin_x, [this](std::int64_t i) { return edge_x(i); });
  cell.row = index(y, origin_y, [this](std::int64_t i) { return edge_y(i); });
  return cell;
}

BoundingBox Grid::halo_box(GridCell cell) const {
  BoundingBox box;
  box.min = Vec3(edge_x(cell.column) - halo, edge_y(cell.row) - halo, -HUGE_VAL);
  box.max = Vec3(edge_x(cell.column + 1) + halo, edge_y(cell.row + 1) + halo, HUGE_VAL);
  return box;
}

bool Grid::meets_halo(const BoundingBox& box, GridCell cell) const {
  return box.intersects(halo_box(cell));  // false for an empty box
}

bool Grid::within_halo(const BoundingBox& box, GridCell cell) const {
  if (box.empty()) return true;
  const BoundingBox h = halo_box(cell);
  return box.min.x() >= h.min.x() && box.max.x() <= h.max.x() && box.min.y() >= h.min.y() &&
         box.max.y() <= h.max.y();
}

}  // namespace csgtile::kernel
