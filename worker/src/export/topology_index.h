#pragma once
/// \file
/// The topology index (DESIGN.md §6, README "Topology index"): a GeoPackage 1.3 file with
///   - `objects`, a feature layer (MULTIPOLYGON Z boundary, R-tree indexed) with one feature
///     per object: id, cell, primitives, volume, area, 3D bounds, validity, fit quality;
///   - attribute tables `shapes`, `shape_children` (sub-shape references), `shape_ancestors`
///     (the paper's MapCsgFatherShape: vertex→edge, edge→face, face→shell, face→solid),
///     `object_relations`, `csg_nodes`, `face_sources` and `primitives`.
///
/// Ids are stable: objects keep the caller's ids and order; shapes are numbered 1, 2, … in
/// (object order, kind order compound → vertex, kernel::map_child_shapes order) and also carry
/// the text key "<object id>/<kind>/<index in map_child_shapes(object, kind)>". The same
/// objects give the same ids and the same file bytes.
///
/// Internal API of the worker (exporters); not installed.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "csgtile/assembly/assembly.h"
#include "csgtile/assembly/block_model.h"
#include "csgtile/kernel/csg.h"
#include "csgtile/kernel/shape.h"
#include "csgtile/kernel/tessellation.h"
#include "csgtile/worker/errors.h"

namespace csgtile::worker {

// ---- input ----------------------------------------------------------------------------------

/// A primitive of an object: the CSG leaf it is and, when it was fitted, its fit quality.
struct PrimitiveInfo {
  int node = -1;     ///< its Primitive node in the object's CsgModel; -1 when there is none
  std::string id;    ///< scene or fit id (may be empty)
  std::string type;  ///< kernel::primitive_type_name, e.g. "cylinder"
  std::optional<long long> inliers;
  std::optional<double> rms;            ///< fit RMS error (model units)
  std::optional<double> coverage;       ///< fit coverage in [0, 1]
  std::optional<double> within_2sigma;  ///< share of its points within 2σ of its solid
};

/// How far an object's points lie from its model, as 3DBAG measures a LoD2.2 (b3_rmse_lod22):
/// the points standing over the object (city/model_fit.h), their RMS 3D distance to its
/// boundary and the share of them within 2σ (σ: its fit's noise estimate).
struct ModelFit {
  long long points = 0;
  double rmse = 0.0;              ///< metres
  std::optional<double> sigma{};  ///< metres; absent when its fit gave none
  std::optional<double> within_2sigma{};
};

/// One object of the index: a solid (or a compound of solids) with its CSG history.
struct IndexObject {
  std::string id;          ///< unique in the index; becomes objects.object_id
  std::string cell = "0";  ///< output cell the object belongs to
  kernel::CsgModel model;  ///< nodes and face_sources may be empty (no history)
  std::vector<PrimitiveInfo> primitives;
  /// Heights of its model (every object with a roof seen from above) and, for a building
  /// (an object of extrusions along +z), its LoD1.2 block model; `lod12_error` says why a
  /// building has none. Filled by add_building_lods.
  std::optional<assembly::BuildingHeights> heights;
  std::string fuse_error;  ///< why its primitives are not one solid (empty: they are)
  /// When its primitives fused only after escalation (AssemblyOptions::escalate_to): the snap
  /// they got and why the first fuse failed.
  std::optional<assembly::AssembledObject::Escalation> escalation;
  std::optional<kernel::CsgModel> lod12;
  std::string lod12_error;
  /// The footprint it was fitted in (city.footprints_id's value, or the feature id); empty
  /// when its outline was derived from the points.
  std::string footprint_id;
  /// A building's LoD1.3 (assembly::multi_height_block_model: each roof part extruded to its
  /// level's height); `lod13_error` says why a building with a LoD1.2 block has none.
  std::optional<kernel::CsgModel> lod13 = {};
  std::string lod13_error = {};
  /// Its points' distances to its model, when the run kept the points (city runs).
  std::optional<ModelFit> model_fit = {};
  /// check_shape(model.shape).valid(), when its job checked it once for all its exporters
  /// (model_valid); unset, each exporter checks the model itself.
  std::optional<bool> valid = {};
  /// Its model tessellated at `mesh_tolerance` (chordal), when its job made the mesh once for
  /// every exporter and its blocks (model_mesh); null, each makes its own.
  std::shared_ptr<const kernel::Mesh> mesh = {};
  double mesh_tolerance = 0.0;
};

/// Whether the object's model passes the checker: `valid` when set, else checked now.
bool model_valid(const IndexObject& object);

/// The object's model tessellated at `chordal_tolerance`: its shared `mesh` when made at that
/// tolerance, else tessellated now. Errors: as kernel::tessellate.
kernel::Result<std::shared_ptr<const kernel::Mesh>> model_mesh(const IndexObject& object,
                                                               double chordal_tolerance);

/// The shared `mesh` when it was made at `chordal_tolerance`; null otherwise.
std::shared_ptr<const kernel::Mesh> shared_mesh(const IndexObject& object,
                                                double chordal_tolerance);

/// Moves an object's model by `by`: its shape and, so that its history stays in the shape's
/// frame, every primitive leaf's placement.
void move_model(kernel::CsgModel& model, const kernel::Location& by);

/// Fills heights, lod12, lod12_error, lod13 and lod13_error of every object (block_model.h) at
/// the exporters' chordal tolerance and the Booleans' linear tolerance. Each object on its own: the
/// result does not depend on the order or the thread count.
void add_building_lods(std::vector<IndexObject>& objects, double chordal_tolerance,
                       double linear_tolerance);

/// Whether add_building_lods found the object a building (it has a block, or a reason why not).
bool is_building(const IndexObject& object);
/// A building's LoD reached: "2.2" when its model is one solid, else "1.2" when it has its
/// block, else empty (also for objects that are not buildings).
std::string lod_reached(const IndexObject& object);
/// Why a building's model is not one solid: its fuse error, or that it is in several solids.
std::string lod22_failure(const IndexObject& object);
/// Why a building's LoD2.2 or its block is missing ("LoD2.2: …; LoD1.2: …"); empty if neither.
std::string building_problem(const IndexObject& object);

/// Fit quality of an object: RMS and coverage of its fitted primitives, weighted by their
/// inlier counts (equal weights when no counts are known); both unset when none was fitted.
/// The share of its points within 2σ, likewise over the primitives that have one.
struct FitSummary {
  std::optional<double> rms, coverage, within_2sigma;
};
FitSummary fit_summary(const std::vector<PrimitiveInfo>& primitives);

enum class RelationKind { Touches, Overlaps, Contains, Within, Equals, Unknown };
/// "touches", "overlaps", "contains", "within", "equals", "unknown".
const char* relation_kind_name(RelationKind kind);
/// The relation seen from the other object (contains ↔ within; the others are symmetric).
RelationKind converse(RelationKind kind);

/// The relation of object a to object b (a < b).
struct ObjectRelation {
  std::size_t a = 0, b = 0;
  RelationKind kind = RelationKind::Unknown;
  double shared_area = 0.0;    ///< touches: area of the common boundary
  double common_volume = 0.0;  ///< overlaps, contains, within, equals: volume of a ∩ b
  std::string reason;          ///< unknown: the Boolean error that stopped the classification
};

/// The spatial reference system of the objects layer (a gpkg_spatial_ref_sys row).
struct IndexSrs {
  int srs_id = -1;
  std::string organization = "NONE";
  int organization_coordsys_id = -1;
  std::string name = "Undefined Cartesian SRS";
  std::string definition_wkt = "undefined";
  /// srs_id -1: the GeoPackage's "undefined Cartesian" row (models without a CRS).
  static IndexSrs undefined_cartesian() { return {}; }
};

struct IndexOptions {
  IndexSrs srs;
  /// Maps model coordinates to the SRS (e.g. adds a tile origin); null = identity. Applied to
  /// geometries, bounds and vertex coordinates; volumes and areas stay in model units.
  std::function<kernel::Vec3(const kernel::Vec3&)> to_srs;
  /// Chordal tolerance of curved faces in the objects layer (model units, > 0).
  double chordal_tolerance = 0.01;
  /// Linear tolerance of the Booleans that classify relations.
  double linear_tolerance = 1e-7;
  /// Compute object_relations (Booleans over candidate pairs); off leaves the table empty.
  bool relations = true;
  /// Threads for the relations' Booleans and for building the objects' rows ahead of the one
  /// writer (0: one per core). The output does not depend on it.
  int threads = 0;
  /// gpkg_contents.last_change of every table. Fixed by default so that the same objects give
  /// the same bytes; a caller that wants the wall clock passes it (format %Y-%m-%dT%H:%M:%fZ).
  std::string last_change = "1970-01-01T00:00:00.000Z";
  /// When given, the relations of objects of the same `cell` were classified already (by the
  /// job that built the cell): they are taken from here (indices into the objects, a < b) and
  /// only pairs across cells are classified.
  std::optional<std::vector<ObjectRelation>> cell_relations = {};
};

/// What a write produced.
struct IndexStats {
  /// Row counts; `relations` counts related object pairs (each has a row per direction).
  std::size_t objects = 0, shapes = 0, children = 0, ancestors = 0, relations = 0, csg_nodes = 0,
              primitives = 0;
  std::size_t unknown_relations = 0;  ///< pairs whose Booleans failed (kind "unknown")
  std::uint64_t bytes = 0;
  /// Objects whose boundary could not be tessellated (written with a NULL geometry), etc.
  std::vector<std::string> warnings;
  /// The related pairs written (indices into the objects, a < b, in (a, b) order).
  std::vector<ObjectRelation> relation_pairs = {};
};

/// Writes the index to `path` atomically: the GeoPackage is built in a temporary file beside
/// `path` and renamed over it, so `path` is either the old file or the complete new one; the
/// temporary is removed on failure. The output is a rollback-journal database (no WAL).
/// Errors: InputInvalid (duplicate or empty object ids, a non-solid object, bad options),
/// GeometryInvalid (a face the index cannot store), Io (the file cannot be written, naming the
/// path). Deterministic; O(model size) plus
/// two Booleans per object pair whose bounding boxes meet.
Failure write_topology_index(const std::filesystem::path& path,
                             const std::vector<IndexObject>& objects,
                             const IndexOptions& options = {}, IndexStats* stats = nullptr);

/// A GeoPackage write_topology_index wrote for some of the objects (a cell's), and where its
/// model frame lies in the frame of the objects given to merge_topology_indexes.
struct IndexPart {
  std::filesystem::path path;
  kernel::Vec3 offset = kernel::Vec3::Zero();
};

/// The index write_topology_index writes for `objects`, made from the parts' GeoPackages
/// (each written with these options and SRS, their objects in `objects`' order, one part after
/// the other): their rows are copied with ids offset and placements moved instead of being
/// built again from the models. Only the relations are computed (as write_topology_index
/// does: options.cell_relations inside a part's cell, the other pairs classified), so
/// `objects` are the parts' objects in one frame. Coordinates in the SRS are the parts' (equal
/// to a rebuild's to rounding). stats.warnings stays empty: the parts' warnings are theirs.
/// Errors as write_topology_index; InputInvalid when the parts do not hold exactly the objects'
/// ids in their order (nothing is written then).
Failure merge_topology_indexes(const std::filesystem::path& path,
                               const std::vector<IndexPart>& parts,
                               const std::vector<IndexObject>& objects, const IndexOptions& options,
                               IndexStats* stats = nullptr);

// ---- relations ------------------------------------------------------------------------------

/// Relations between solids (or compounds of solids) in one frame. Candidate pairs are those
/// whose bounding boxes, grown by `linear_tolerance`, meet; each is classified exactly by one
/// union: vol(a ∩ b) = vol(a) + vol(b) − vol(a ∪ b) > 0 → overlaps, or contains / within /
/// equals when a ∩ b is one of them (equal volumes, relative 1e-8); otherwise touches when the
/// shared boundary area (area(a) + area(b) − area(a ∪ b)) / 2 is positive. Disjoint pairs and pairs
/// that meet only along edges or at points give no row. A Boolean error gives kind Unknown with the
/// error as the reason. Rows are sorted by (a, b). Pairs are classified on `threads` threads (0:
/// one per core); the result does not depend on it. Deterministic; never throws. `skip` (optional):
/// candidate pairs (i < j) for which it returns true are not classified.
std::vector<ObjectRelation> compute_relations(
    const std::vector<kernel::Shape>& solids, double linear_tolerance, int threads = 0,
    const std::function<bool(std::size_t, std::size_t)>& skip = {});

// ---- reading ---------------------------------------------------------------------------------

/// A row of `shapes`.
struct ShapeRow {
  std::int64_t id = 0;
  std::string key;  ///< "<object>/<kind>/<index>"
  std::string object_id;
  std::string kind;  ///< shape_kind_name
  std::int64_t kind_index = 0;
};

/// A row of `shape_children` joined with the child's shape row.
struct ChildRow {
  std::int64_t position = 0;
  std::string orientation;  ///< of the reference in the parent body
  std::string location;     ///< JSON 3×4 matrix of the reference, empty for the identity
  ShapeRow child;
};

/// A row of `object_relations`.
struct RelationRow {
  std::string object_id, other_id, relation;
  std::optional<double> shared_area, common_volume;
  std::string reason;
};

/// Read-only access to a topology index (what `csgtile query` answers from).
class TopologyIndexReader {
 public:
  /// Opens read-only and checks that the file is a GeoPackage with the index tables.
  /// Errors: Io (missing or unreadable file), InputInvalid (not a GeoPackage or no topology
  /// tables).
  static Result<std::unique_ptr<TopologyIndexReader>> open(const std::filesystem::path& path);
  ~TopologyIndexReader();
  TopologyIndexReader(const TopologyIndexReader&) = delete;
  TopologyIndexReader& operator=(const TopologyIndexReader&) = delete;

  /// A shape by numeric id ("42") or key ("3-0/edge/7"). Error: InputInvalid naming the id.
  Result<ShapeRow> shape(std::string_view id_or_key) const;
  /// Sub-shape references of a shape, in child order.
  Result<std::vector<ChildRow>> children(std::int64_t shape_id) const;
  /// Ancestors of `kind` (e.g. "edge") of a shape, each once, in the kernel's AncestorIndex
  /// order: from shape_ancestors when the pair is materialised, otherwise by walking
  /// shape_children upwards. Error: InputInvalid for an unknown kind.
  Result<std::vector<ShapeRow>> ancestors(std::int64_t shape_id, std::string_view kind) const;
  /// Relations of an object, ordered by the other object's id. Error: InputInvalid when
  /// the object is not in the index.
  Result<std::vector<RelationRow>> relations(std::string_view object_id) const;
  /// Runs one SQL statement with text parameters (?1, ?2, …) and returns every row with each
  /// value as text (NULL as "NULL"): for tests and the README's recipes.
  Result<std::vector<std::vector<std::string>>> sql(
      std::string_view statement, const std::vector<std::string>& parameters = {}) const;

 private:
  struct Impl;
  explicit TopologyIndexReader(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace csgtile::worker
