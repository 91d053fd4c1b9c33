#pragma once
// A partition of a grid into labelled parts and the polygons of its parts (partition.cpp):
// the roof partition of a building (roof_partition.cpp) labels the cells of its outline with
// the roof plane that explains their points; each part (4-connected cells of one label)
// becomes a polygon whose boundary it shares exactly with its neighbours, so that the parts'
// extrusions tile the building without gaps or overlaps.

#include <vector>

#include <Eigen/Core>

namespace csgtile::fit::detail {

/// nx × ny cells, row-major by y; a label ≥ 0 or −1 (outside).
struct LabelGrid {
  int nx = 0, ny = 0;
  std::vector<int> label;
  int at(int i, int j) const {
    if (i < 0 || j < 0 || i >= nx || j >= ny) return -1;
    return label[static_cast<std::size_t>(j) * static_cast<std::size_t>(nx) +
                 static_cast<std::size_t>(i)];
  }
  int& cell(int i, int j) {
    return label[static_cast<std::size_t>(j) * static_cast<std::size_t>(nx) +
                 static_cast<std::size_t>(i)];
  }
};

/// Morphological closing of an nx × ny occupancy grid (row-major by y): a 3 × 3 dilation,
/// then a 3 × 3 erosion, over the cells not on the grid's border (the gaps between a scan's
/// lines are filled, the outline kept).
void close_cells(std::vector<char>& occupied, int nx, int ny);

/// The 4-connected components of equal labels ≥ 0: per cell its component or −1, and
/// `count` components numbered in the order of their first cell.
struct Components {
  std::vector<int> of;
  int count = 0;
};
Components label_components(const LabelGrid& grid);

/// Removes diagonal pinches: two cells of one label (or two outside cells) meeting only at a
/// corner, the other two cells of the 2 × 2 block holding something else. A pinch would make
/// a part's ring touch itself, or two parts meet along a line only (a non-manifold union).
/// The block is joined through one of the other cells (a labelled diagonal takes it; an
/// outside diagonal gives it the other diagonal's first label). Also four-way junctions: four
/// labels (the outside one of them) around a corner, where two opposite parts higher than
/// the other two would meet along a vertical line only; a cell takes its neighbour's label,
/// so that three meet. Returns the cells changed.
int unpinch(LabelGrid& grid);

/// One part: its component, label, outer ring (counter-clockwise) and holes (clockwise), in
/// grid units (vertex (i, j) is the corner (i, j) of the cells), its cells and neighbours.
struct PartPolygon {
  int label = -1;
  std::vector<Eigen::Vector2d> outer;
  std::vector<std::vector<Eigen::Vector2d>> holes;
  std::vector<int> cells;       ///< ascending cell indices
  std::vector<int> neighbours;  ///< the parts sharing a cell edge with it, ascending
};

/// The polygons of every component of a pinch-free grid (unpinch). Each boundary between two
/// parts (or a part and the outside) is one chain of cell edges simplified once
/// (Douglas–Peucker within `tolerance` cells, its ends fixed) and used by both sides, so that
/// neighbouring polygons share it exactly. Where a simplified chain would cross or touch
/// another, leave a hole outside its ring, or change a part's area by a quarter or more, the
/// chains concerned keep their cell edges (collinear vertices removed). Deterministic. A grid
/// of 2³² vertices or more gives the parts without polygons.
std::vector<PartPolygon> partition_polygons(const LabelGrid& grid, double tolerance);

}  // namespace csgtile::fit::detail
