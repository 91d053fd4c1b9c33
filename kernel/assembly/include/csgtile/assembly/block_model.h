#pragma once
/// \file
/// Buildings at LoD1.2 and LoD1.3 (the block models 3D city models publish beside LoD2.2, e.g.
/// 3DBAG): the footprint of a building's solid extruded from its ground to a percentile of its
/// roof's height (LoD1.2), or each roof part to its own (LoD1.3), with the heights 3D city
/// models publish. All are derived from the LoD2.2 model itself, so they agree with it
/// whatever made it.

#include <cstddef>
#include <memory>
#include <optional>

#include "csgtile/kernel/csg.h"
#include "csgtile/kernel/tessellation.h"

namespace csgtile::assembly {

/// Heights of a solid as city models publish them (3DBAG's b3_h_*), in its z units.
struct BuildingHeights {
  double ground = 0.0;  ///< the lowest point of its downward faces (its base)
  /// Its roof (faces whose outward normal points up by more than a wall's, nz > 0.2): lowest
  /// and highest point, and percentiles of its height over its area seen from above.
  double roof_min = 0.0, roof_50p = 0.0, roof_70p = 0.0, roof_max = 0.0;
  double roof_area = 0.0;      ///< seen from above
  std::size_t roof_faces = 0;  ///< faces with some roof
};

/// The heights of `shape` from its tessellation at `chordal_tolerance`: exact for planar
/// roofs (the height is linear over each triangle and the percentiles are found on the exact
/// area function), within the tolerance for curved ones. Errors: as kernel::tessellate;
/// DegenerateGeometry when the shape has no roof seen from above.
/// `mesh`: the shape's tessellation at `chordal_tolerance` when the caller has made it (the
/// exporters share one per object); null, it is made here.
kernel::Result<BuildingHeights> building_heights(const kernel::Shape& shape,
                                                 double chordal_tolerance,
                                                 std::shared_ptr<const kernel::Mesh> mesh = {});

struct BlockModelOptions {
  /// Of the tessellation the heights and footprint use; also the narrowest strip a face seen
  /// from below must project to to be part of the footprint (a wall leaning out by less adds
  /// a sliver no block model shows).
  double chordal_tolerance = 0.01;
  double tolerance = kernel::kDefaultTolerance;  ///< of the extrusions and their fuse
  /// LoD1.3: roof parts whose heights differ by less than this (model units) are one level.
  double level_step = 0.5;
};

/// A building's LoD1.2: its footprint (every face of its solid that looks down, seen from
/// above: the projection of the solid) extruded from heights.ground to its roof's 70th percentile,
/// one extrusion per downward face, fused by the exact Booleans. Its history is its own CSG tree.
struct BlockModel {
  BuildingHeights heights;
  kernel::CsgModel model;
};

/// The block model of `model`, a building: a solid (or a compound of solids whose fuse
/// failed) whose CSG leaves are all extrusions or boxes, placed any way, with or without roof
/// clips: every face is planar, and the faces that look down at all are the footprint.
/// Errors: InvalidArgument when a leaf is a curved primitive (not a building: no block
/// model); DegenerateGeometry when the top is not above the ground, a footprint face's rings
/// make no extrusion or the footprint is in several pieces; the Booleans' errors;
/// InvalidShape when the fused block fails the checker.
kernel::Result<BlockModel> block_model(const kernel::CsgModel& model,
                                       const BlockModelOptions& options = {});

/// A building's LoD1.3, 3DBAG's multi-height block: each roof part — a leaf of its CSG tree,
/// an extrusion or a box cut by its roof planes — has its footprint (the faces of the leaf
/// without its roof planes that look down) extruded from the building's ground to the 70th
/// percentile of its level's roof. A part's roof is what is left of it in the model (the
/// faces whose history names the leaf; a part with none takes the building's height); a
/// level is the parts whose own 70th percentiles lie within `level_step` of the next (single
/// linkage), its roof the union of theirs. The extrusions are fused by the exact Booleans.
/// One roof part (or one level) gives LoD1.2's block. `heights` are the building's.
/// Errors: as block_model.
kernel::Result<BlockModel> multi_height_block_model(const kernel::CsgModel& model,
                                                    const BlockModelOptions& options = {});

/// Both blocks of a building from one measurement of its model, as exporters publish them:
/// LoD1.2 as block_model (its errors are this function's), LoD1.3 as multi_height_block_model
/// or the error that left it out.
struct BuildingBlocks {
  BuildingHeights heights;
  kernel::CsgModel lod12;
  std::optional<kernel::CsgModel> lod13;
  std::optional<kernel::Error> lod13_error;
};
/// `mesh`: the model's tessellation at options.chordal_tolerance, as for building_heights.
kernel::Result<BuildingBlocks> building_blocks(const kernel::CsgModel& model,
                                               const BlockModelOptions& options = {},
                                               std::shared_ptr<const kernel::Mesh> mesh = {});

}  // namespace csgtile::assembly
