#pragma once
// The rows of a topology index, built from objects (topology_index.cpp) and written into a
// GeoPackage (gpkg_writer.cpp). Split so that the kernel side (ids, maps, geometry) and the
// container side (SQLite, GeoPackage binary geometry) can be read and tested apart.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "csgtile/kernel/bounding_box.h"
#include "export/topology_index.h"

namespace csgtile::worker::detail {

/// A polygon with closed rings (first point repeated last); the first ring is the exterior,
/// counter-clockwise seen from outside the solid.
struct Polygon3 {
  std::vector<std::vector<kernel::Vec3>> rings;
};

struct ObjectRecord {
  std::string object_id, cell;
  std::int64_t shape_id = 0;  ///< the object's root shape
  std::int64_t primitive_count = 0;
  std::string primitive_types;  ///< sorted, distinct, comma-separated
  double volume = 0.0, area = 0.0;
  kernel::BoundingBox bounds;  ///< in the SRS
  bool valid = false;
  std::optional<double> fit_rms, fit_coverage;
  std::optional<double> fit_within_2sigma;  ///< share of its fitted points within 2σ
  bool has_geometry = false;                ///< false: NULL geometry (tessellation failed)
  std::vector<Polygon3> boundary;           ///< in the SRS
  /// Buildings (IndexObject::heights, lod12, lod13): the LoD reached ("2.2", "1.3", "1.2"),
  /// heights in the SRS, why the model or a block is missing, and the blocks' boundaries
  /// (lod12 and lod13 layers).
  std::optional<std::string> lod, fuse_error, lod12_error, lod13_error;
  std::optional<std::string> footprint_id, outline;  ///< buildings: "footprint" or "derived"
  std::optional<double> h_ground, h_roof_min, h_roof_50p, h_roof_70p, h_roof_max;
  std::optional<std::int64_t> roof_surfaces;
  bool has_lod12 = false;
  std::vector<Polygon3> lod12_boundary;  ///< in the SRS
  bool has_lod13 = false;
  std::vector<Polygon3> lod13_boundary;  ///< in the SRS
  /// IndexObject::model_fit: its points' RMS distance to its model, their count and share
  /// within 2σ.
  std::optional<double> model_rmse = {};
  std::optional<std::int64_t> model_points = {};
  std::optional<double> model_within_2sigma = {};
};

struct ShapeRecord {
  std::int64_t id = 0;
  std::string key, object_id, kind;
  std::int64_t kind_index = 0;
  std::string orientation;  ///< of the first use seen from the object's root
  std::optional<double> tolerance;
  std::string geometry;               ///< surface or curve kind; "degenerate"; empty otherwise
  std::optional<kernel::Vec3> point;  ///< vertices, in the SRS
};

struct ChildRecord {
  std::int64_t parent_id = 0, child_id = 0, position = 0;
  std::string orientation, location;  ///< of the reference stored in the parent's body
};

struct AncestorRecord {
  std::int64_t shape_id = 0;
  std::string ancestor_kind;
  std::int64_t ancestor_id = 0, position = 0;
};

struct RelationRecord {
  std::string object_id, other_id, relation;
  std::optional<double> shared_area, common_volume;
  std::string reason;
};

struct CsgNodeRecord {
  std::string object_id;
  std::int64_t node = 0;
  std::string kind, label;
  std::optional<std::int64_t> parent;
  std::string children;                    ///< JSON array of node indices
  std::string primitive_type, parameters;  ///< empty for operations
};

struct FaceSourceRecord {
  std::int64_t face_id = 0;
  std::string object_id;
  std::int64_t node = 0, primitive_face = 0;
};

struct PrimitiveRecord {
  std::string object_id;
  std::optional<std::int64_t> node;
  std::string primitive_id, type;
  std::optional<std::int64_t> inliers;
  std::optional<double> fit_rms, fit_coverage;
};

struct IndexRows {
  std::vector<ObjectRecord> objects;
  std::vector<ShapeRecord> shapes;
  std::vector<ChildRecord> children;
  std::vector<AncestorRecord> ancestors;
  std::vector<RelationRecord> relations;
  std::vector<CsgNodeRecord> csg_nodes;
  std::vector<FaceSourceRecord> face_sources;
  std::vector<PrimitiveRecord> primitives;
};

/// The (child kind, ancestor kind) pairs materialised in shape_ancestors.
inline constexpr std::pair<kernel::ShapeKind, kernel::ShapeKind> kAncestorPairs[] = {
    {kernel::ShapeKind::Vertex, kernel::ShapeKind::Edge},
    {kernel::ShapeKind::Edge, kernel::ShapeKind::Face},
    {kernel::ShapeKind::Face, kernel::ShapeKind::Shell},
    {kernel::ShapeKind::Face, kernel::ShapeKind::Solid},
};

/// Builds every row at once: the reference the streamed write_topology_index (object_rows,
/// offset_ids, GpkgRowWriter) is tested against. Errors: InputInvalid, GeometryInvalid (see
/// write_topology_index).
Result<IndexRows> build_index_rows(const std::vector<IndexObject>& objects,
                                   const IndexOptions& options, IndexStats& stats);

/// The object_relations rows of `objects` (both directions of each related pair, in (a, b)
/// order): options.cell_relations for pairs inside a cell, the others classified
/// (compute_relations). Fills stats.relation_pairs and stats.unknown_relations.
std::vector<RelationRecord> relation_records(const std::vector<IndexObject>& objects,
                                             const IndexOptions& options, IndexStats& stats);

/// Writes the rows as a GeoPackage at `path` (which must not exist; the caller renames it),
/// through one GpkgRowWriter: the all-at-once reference of the streamed index. Error: Io
/// naming the path and SQLite's message.
Failure write_gpkg(const std::string& path, const IndexRows& rows, const IndexOptions& options);

/// The same file written object by object, so that only a few objects' rows are ever held:
/// open, add each object's rows in order (ids final, relations aside), finish with the
/// relations. The file is what write_gpkg writes for all the rows at once, row for row. After a
/// failure the later calls return it; finish closes the file in every case.
class GpkgRowWriter {
 public:
  GpkgRowWriter();
  ~GpkgRowWriter();
  GpkgRowWriter(const GpkgRowWriter&) = delete;
  GpkgRowWriter& operator=(const GpkgRowWriter&) = delete;
  Failure open(const std::string& path, const IndexOptions& options);
  Failure add(const IndexRows& rows);
  Failure finish(const std::vector<RelationRecord>& relations);

 private:
  struct State;
  std::unique_ptr<State> state_;
};

/// One object's rows with its shape ids numbered from 1 (`ids`: how many it took; the writer
/// moves them after the objects before it) and its warnings. No relations.
struct ObjectRows {
  IndexRows rows;
  std::int64_t ids = 0;
  std::vector<std::string> warnings;
};
ObjectRows object_rows(const IndexObject& object, const IndexOptions& options);
/// Moves the shape ids of `rows` (numbered from 1) by `offset`; 0, no shape, stays 0.
void offset_ids(IndexRows& rows, std::int64_t offset);

/// A GeoPackage write_gpkg wrote, and where its model frame lies in the merged one's: its
/// primitives' placements are moved by `offset` (coordinates in the SRS need no move).
struct GpkgPart {
  std::string path;
  kernel::Vec3 offset = kernel::Vec3::Zero();
};
struct GpkgCounts {
  std::size_t objects = 0, shapes = 0, children = 0, ancestors = 0, csg_nodes = 0, primitives = 0;
};

/// Writes at `path` (which must not exist) the GeoPackage of the parts' objects one after
/// another, as write_gpkg would write them all: ids offset by the rows before, placements
/// moved, the feature tables' extents joined; object_relations is `relations` (the parts'
/// own are not read). The parts must have the options' SRS and chordal tolerance and hold
/// exactly the objects `object_ids`, in that order. Errors: InputInvalid when they do not; Io
/// naming the path and SQLite's message (a duplicate object id among the parts too).
Failure merge_gpkgs(const std::string& path, const std::vector<GpkgPart>& parts,
                    const std::vector<std::string>& object_ids,
                    const std::vector<RelationRecord>& relations, const IndexOptions& options,
                    GpkgCounts& counts);

}  // namespace csgtile::worker::detail
