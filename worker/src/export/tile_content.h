#pragma once
/// \file
/// The content of a 3D Tiles tile: the run's objects as one glTF binary (gltf_writer.h) in
/// the tile's east-north-up frame, one feature per object.
///
/// Each object is tessellated at the chordal tolerance and its vertices are mapped into the
/// ENU frame (metres, z up). Vertices are split per kernel face: a planar face has one flat
/// normal, a curved face the area-weighted mean of its triangles' normals at each vertex, and
/// edges between faces stay sharp. glTF is y up: positions and normals are stored rotated by
/// (x, y, z) → (x, z, −y) in the vertex data itself (the node has no matrix), so the tile's
/// transform maps ENU straight to ECEF, as 3D Tiles clients expect after their y-up → z-up
/// step. The feature id of a vertex is its object's row in the property table (class
/// `object`: id, primitive_types, primitive_count, volume, area, valid).
///
/// Internal API of the worker (exporters); not installed.

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "csgtile/kernel/shape.h"
#include "export/topology_index.h"

namespace csgtile::worker {

struct TileContentOptions {
  /// Model coordinates → the tile's ENU frame (metres); null = identity. A non-finite result
  /// marks a point outside the CRS's domain (its object is left out with a warning).
  std::function<kernel::Vec3(const kernel::Vec3&)> to_enu;
  /// Chordal tolerance of the tessellation (model units, > 0).
  double chordal_tolerance = 0.01;
  std::string generator = "csgtile";
};

struct TileContent {
  std::string glb;
  /// ENU bounds of the vertices as stored (the float32 values, rotated back to z up).
  kernel::Vec3 low = kernel::Vec3::Zero(), high = kernel::Vec3::Zero();
  /// The property table's rows: feature id i is object_ids[i] (the written objects, in
  /// input order).
  std::vector<std::string> object_ids;
  std::size_t vertices = 0, triangles = 0;
  /// Objects left out (tessellation failed, points outside the CRS's domain).
  std::vector<std::string> warnings;
};

/// The tile content of `objects` (ids unique and non-empty, as for the topology index).
/// Deterministic: the same objects and options give the same bytes. Errors:
/// GeometryInvalid (no object has triangles; the message names the first few), InputInvalid
/// (a bad tolerance, duplicate or empty ids, or as glb_bytes).
Result<TileContent> tile_content(const std::vector<IndexObject>& objects,
                                 const TileContentOptions& options = {});

}  // namespace csgtile::worker
