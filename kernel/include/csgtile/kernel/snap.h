#pragma once
/// \file
/// Fuzzy mode for fitted primitives: near-coincidences between primitives, within the fit's
/// own accuracy, made exact before the Booleans meet them.
///
/// Primitives fitted from points are never exact: a column 1 mrad off vertical, a beam's top
/// 1.3 mm above the column's, two beams' end faces 0.2 mm apart and 0.9 mrad off parallel.
/// The exact Booleans intersect such faces into slivers micrometres thick whose vertices no
/// tolerance places consistently. Snapping makes them what they were meant to be, the way
/// regularisation of fitted models does (GlobFit): axes within `angle` of each other become
/// one direction (their mean; the vertical itself within `angle` of it, the world's z being
/// up; directions within `angle` of a right angle to each other become exactly orthogonal),
/// and parallel plane faces (box faces, the caps of cylinders, cones and
/// extrusions) whose planes lie within `distance` of each other become one plane; parallel
/// axes of surfaces of revolution (cylinders, cones, tori, revolutions) within `distance` of
/// each other become one axis line, and cylinders on one line whose radii differ by at most
/// `distance` one radius; last, the side walls of parallel extrusions share their vertices: a
/// profile vertex within `distance` of another extrusion's vertex becomes it, one within
/// `distance` of its edge is inserted into it (a wall 5 mm off its neighbour's corner leaves
/// a slot the Booleans would keep, pinched to a non-manifold edge at its end). Each
/// primitive turns about its own centre; a face moves along its normal by at most `distance`
/// (its primitive's size changes accordingly); clip planes stay where they are in the world.
/// The two faces of one primitive never merge. Deterministic (input order).

#include <vector>

#include "csgtile/kernel/primitives.h"

namespace csgtile::kernel {

struct SnapOptions {
  double distance = 0.0;  ///< world units; plane faces this close become one plane (0: none)
  double angle = 0.0;     ///< radians; axes this close become one direction (0: none)
};

struct SnapReport {
  int directions = 0;     ///< distinct axis directions after snapping
  int axes_snapped = 0;   ///< primitive axes turned onto a shared direction
  int planes = 0;         ///< planes shared by two or more faces
  int faces_snapped = 0;  ///< faces moved onto a shared plane
  double max_turn = 0.0;  ///< largest rotation of a primitive (radians)
  double max_move = 0.0;  ///< largest move of a face, an axis or a radius (world units)
  int lines = 0;          ///< axis lines shared by two or more surfaces of revolution
  int axes_moved = 0;     ///< surfaces of revolution moved onto a shared axis line
  int radii_snapped = 0;  ///< cylinder radii changed to a shared radius
  int walls_shared = 0;   ///< extrusion profile vertices moved or inserted to share a wall
};

/// The primitives with their near-coincidences snapped (see the file comment). Errors:
/// InvalidArgument for a negative or non-finite distance or angle.
Result<std::vector<PrimitiveSpec>> snap_primitives(const std::vector<PrimitiveSpec>& primitives,
                                                   const SnapOptions& options,
                                                   SnapReport* report = nullptr);

}  // namespace csgtile::kernel
