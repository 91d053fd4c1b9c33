// The GeoPackage container of the topology index (OGC GeoPackage 1.3): core tables, the
// objects feature layer with GeoPackage binary geometries and its R-tree, and the topology
// tables registered as attribute tables.
//
// Determinism: SQLite writes the same bytes for the same statements in the same order, so
// everything is inserted in row order and gpkg_contents.last_change comes from the options.

#include <array>
#include <bit>
#include <cstdio>
#include <cstring>
#include <nlohmann/json.hpp>

#include "export/index_rows.h"
#include "export/sqlite_util.h"

namespace csgtile::worker::detail {

namespace {

// Core tables as the GeoPackage 1.3 specification defines them (Annex C / tables 18–21);
// validators compare column types, nullability and defaults.
constexpr const char* kCoreSchema = R"sql(
CREATE TABLE gpkg_spatial_ref_sys (
  srs_name TEXT NOT NULL,
  srs_id INTEGER NOT NULL PRIMARY KEY,
  organization TEXT NOT NULL,
  organization_coordsys_id INTEGER NOT NULL,
  definition TEXT NOT NULL,
  description TEXT
);
CREATE TABLE gpkg_contents (
  table_name TEXT NOT NULL PRIMARY KEY,
  data_type TEXT NOT NULL,
  identifier TEXT UNIQUE,
  description TEXT DEFAULT '',
  last_change DATETIME NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%fZ','now')),
  min_x DOUBLE,
  min_y DOUBLE,
  max_x DOUBLE,
  max_y DOUBLE,
  srs_id INTEGER,
  CONSTRAINT fk_gc_r_srs_id FOREIGN KEY (srs_id) REFERENCES gpkg_spatial_ref_sys(srs_id)
);
CREATE TABLE gpkg_geometry_columns (
  table_name TEXT NOT NULL,
  column_name TEXT NOT NULL,
  geometry_type_name TEXT NOT NULL,
  srs_id INTEGER NOT NULL,
  z TINYINT NOT NULL,
  m TINYINT NOT NULL,
  CONSTRAINT pk_geom_cols PRIMARY KEY (table_name, column_name),
  CONSTRAINT uk_gc_table_name UNIQUE (table_name),
  CONSTRAINT fk_gc_tn FOREIGN KEY (table_name) REFERENCES gpkg_contents(table_name),
  CONSTRAINT fk_gc_srs FOREIGN KEY (srs_id) REFERENCES gpkg_spatial_ref_sys (srs_id)
);
CREATE TABLE gpkg_extensions (
  table_name TEXT,
  column_name TEXT,
  extension_name TEXT NOT NULL,
  definition TEXT NOT NULL,
  scope TEXT NOT NULL,
  CONSTRAINT ge_tce UNIQUE (table_name, column_name, extension_name)
);
)sql";

// The index's own tables (README "Topology index"). Column types are GeoPackage data types.
constexpr const char* kIndexSchema = R"sql(
CREATE TABLE objects (
  fid INTEGER PRIMARY KEY AUTOINCREMENT,
  geom MULTIPOLYGON,
  object_id TEXT NOT NULL UNIQUE,
  cell TEXT NOT NULL,
  shape_id INTEGER NOT NULL,
  primitive_count INTEGER NOT NULL,
  primitive_types TEXT NOT NULL,
  volume REAL NOT NULL,
  area REAL NOT NULL,
  min_x REAL, min_y REAL, min_z REAL,
  max_x REAL, max_y REAL, max_z REAL,
  valid BOOLEAN NOT NULL,
  fit_rms REAL,
  fit_coverage REAL,
  lod TEXT,
  h_ground REAL,
  h_roof_min REAL,
  h_roof_50p REAL,
  h_roof_70p REAL,
  h_roof_max REAL,
  roof_surfaces INTEGER,
  fuse_error TEXT,
  lod12_error TEXT,
  footprint_id TEXT,
  outline TEXT,
  fit_within_2sigma REAL,
  lod13_error TEXT,
  model_rmse REAL,
  model_points INTEGER,
  model_within_2sigma REAL
);
CREATE TABLE lod12 (
  fid INTEGER PRIMARY KEY AUTOINCREMENT,
  geom MULTIPOLYGON,
  object_id TEXT NOT NULL UNIQUE,
  cell TEXT NOT NULL,
  h_ground REAL NOT NULL,
  h_top REAL NOT NULL
);
CREATE TABLE lod13 (
  fid INTEGER PRIMARY KEY AUTOINCREMENT,
  geom MULTIPOLYGON,
  object_id TEXT NOT NULL UNIQUE,
  cell TEXT NOT NULL,
  h_ground REAL NOT NULL,
  h_top REAL NOT NULL
);
CREATE TABLE shapes (
  id INTEGER PRIMARY KEY,
  key TEXT NOT NULL UNIQUE,
  object_id TEXT NOT NULL,
  kind TEXT NOT NULL,
  kind_index INTEGER NOT NULL,
  orientation TEXT NOT NULL,
  tolerance REAL,
  geometry TEXT,
  x REAL, y REAL, z REAL
);
CREATE TABLE shape_children (
  id INTEGER PRIMARY KEY,
  parent_id INTEGER NOT NULL,
  child_id INTEGER NOT NULL,
  position INTEGER NOT NULL,
  orientation TEXT NOT NULL,
  location TEXT
);
CREATE TABLE shape_ancestors (
  id INTEGER PRIMARY KEY,
  shape_id INTEGER NOT NULL,
  ancestor_kind TEXT NOT NULL,
  ancestor_id INTEGER NOT NULL,
  position INTEGER NOT NULL
);
CREATE TABLE object_relations (
  id INTEGER PRIMARY KEY,
  object_id TEXT NOT NULL,
  other_id TEXT NOT NULL,
  relation TEXT NOT NULL,
  shared_area REAL,
  common_volume REAL,
  reason TEXT
);
CREATE TABLE csg_nodes (
  id INTEGER PRIMARY KEY,
  object_id TEXT NOT NULL,
  node INTEGER NOT NULL,
  kind TEXT NOT NULL,
  label TEXT,
  parent INTEGER,
  children TEXT NOT NULL,
  primitive_type TEXT,
  parameters TEXT
);
CREATE TABLE face_sources (
  id INTEGER PRIMARY KEY,
  face_id INTEGER NOT NULL,
  object_id TEXT NOT NULL,
  node INTEGER NOT NULL,
  primitive_face INTEGER NOT NULL
);
CREATE TABLE primitives (
  id INTEGER PRIMARY KEY,
  object_id TEXT NOT NULL,
  node INTEGER,
  primitive_id TEXT,
  type TEXT NOT NULL,
  inliers INTEGER,
  fit_rms REAL,
  fit_coverage REAL
);
CREATE TABLE index_metadata (
  id INTEGER PRIMARY KEY,
  key TEXT NOT NULL UNIQUE,
  value TEXT NOT NULL
);
)sql";

// Created after the rows are in (a bulk load is faster without them): every recipe of the
// README is an index lookup.
constexpr const char* kIndexIndexes = R"sql(
CREATE UNIQUE INDEX shapes_object_kind ON shapes (object_id, kind, kind_index);
CREATE UNIQUE INDEX shape_children_parent ON shape_children (parent_id, position);
CREATE INDEX shape_children_child ON shape_children (child_id);
CREATE UNIQUE INDEX shape_ancestors_shape ON shape_ancestors (shape_id, ancestor_kind, position);
CREATE INDEX shape_ancestors_ancestor ON shape_ancestors (ancestor_id, ancestor_kind, shape_id);
CREATE UNIQUE INDEX object_relations_object ON object_relations (object_id, relation, other_id);
CREATE UNIQUE INDEX csg_nodes_object ON csg_nodes (object_id, node);
CREATE INDEX face_sources_face ON face_sources (face_id);
CREATE INDEX face_sources_node ON face_sources (object_id, node);
CREATE INDEX primitives_object ON primitives (object_id);
)sql";

// The R-tree of objects.geom and the triggers GeoPackage 1.3 (extension F.3) lists to keep it
// in step with later edits. They call ST_* functions that GeoPackage readers provide, so
// they are created after the R-tree has been filled here.
constexpr const char* kRtree = R"sql(
CREATE VIRTUAL TABLE rtree_objects_geom USING rtree(id, minx, maxx, miny, maxy);
)sql";
constexpr const char* kRtreeTriggers = R"sql(
CREATE TRIGGER rtree_objects_geom_insert AFTER INSERT ON objects
  WHEN (new.geom NOT NULL AND NOT ST_IsEmpty(NEW.geom))
BEGIN
  INSERT OR REPLACE INTO rtree_objects_geom VALUES (
    NEW.fid, ST_MinX(NEW.geom), ST_MaxX(NEW.geom), ST_MinY(NEW.geom), ST_MaxY(NEW.geom));
END;
CREATE TRIGGER rtree_objects_geom_update1 AFTER UPDATE OF geom ON objects
  WHEN OLD.fid = NEW.fid AND (NEW.geom NOTNULL AND NOT ST_IsEmpty(NEW.geom))
BEGIN
  INSERT OR REPLACE INTO rtree_objects_geom VALUES (
    NEW.fid, ST_MinX(NEW.geom), ST_MaxX(NEW.geom), ST_MinY(NEW.geom), ST_MaxY(NEW.geom));
END;
CREATE TRIGGER rtree_objects_geom_update2 AFTER UPDATE OF geom ON objects
  WHEN OLD.fid = NEW.fid AND (NEW.geom ISNULL OR ST_IsEmpty(NEW.geom))
BEGIN
  DELETE FROM rtree_objects_geom WHERE id = OLD.fid;
END;
CREATE TRIGGER rtree_objects_geom_update3 AFTER UPDATE ON objects
  WHEN OLD.fid != NEW.fid AND (NEW.geom NOTNULL AND NOT ST_IsEmpty(NEW.geom))
BEGIN
  DELETE FROM rtree_objects_geom WHERE id = OLD.fid;
  INSERT OR REPLACE INTO rtree_objects_geom VALUES (
    NEW.fid, ST_MinX(NEW.geom), ST_MaxX(NEW.geom), ST_MinY(NEW.geom), ST_MaxY(NEW.geom));
END;
CREATE TRIGGER rtree_objects_geom_update4 AFTER UPDATE ON objects
  WHEN OLD.fid != NEW.fid AND (NEW.geom ISNULL OR ST_IsEmpty(NEW.geom))
BEGIN
  DELETE FROM rtree_objects_geom WHERE id IN (OLD.fid, NEW.fid);
END;
CREATE TRIGGER rtree_objects_geom_delete AFTER DELETE ON objects
  WHEN old.geom NOT NULL
BEGIN
  DELETE FROM rtree_objects_geom WHERE id = OLD.fid;
END;
)sql";

constexpr const char* kWgs84Wkt =
    "GEOGCS[\"WGS 84\",DATUM[\"WGS_1984\",SPHEROID[\"WGS 84\",6378137,298.257223563,"
    "AUTHORITY[\"EPSG\",\"7030\"]],AUTHORITY[\"EPSG\",\"6326\"]],PRIMEM[\"Greenwich\",0,"
    "AUTHORITY[\"EPSG\",\"8901\"]],UNIT[\"degree\",0.0174532925199433,AUTHORITY[\"EPSG\","
    "\"9122\"]],AXIS[\"Latitude\",NORTH],AXIS[\"Longitude\",EAST],AUTHORITY[\"EPSG\",\"4326\"]]";

// Feature tables, their gpkg_contents descriptions and which extent they have (0: the
// objects', 1: the LoD1.2 blocks', 2: the LoD1.3 blocks').
struct FeatureTable {
  const char* table;
  const char* description;
  int box;
};
constexpr FeatureTable kFeatureTables[] = {
    {"objects", "csgtile: one feature per object, its boundary as MULTIPOLYGON Z", 0},
    {"lod12",
     "csgtile: LoD1.2 of each building, its footprint extruded from the ground to the roof's "
     "70th percentile, as MULTIPOLYGON Z",
     1},
    {"lod13",
     "csgtile: LoD1.3 of each building, each roof part's footprint extruded from the ground to "
     "its level's 70th percentile, fused, as MULTIPOLYGON Z (h_top: the highest level)",
     2},
};

// The R-tree statements of objects.geom for another feature table.
std::string for_table(std::string_view sql, std::string_view table) {
  std::string out;
  constexpr std::string_view kObjects = "objects";
  std::size_t at = 0;
  for (std::size_t hit; (hit = sql.find(kObjects, at)) != std::string_view::npos;
       at = hit + kObjects.size()) {
    out.append(sql.substr(at, hit - at)).append(table);
  }
  out.append(sql.substr(at));
  return out;
}

// Attribute tables and their gpkg_contents descriptions.
constexpr std::pair<const char*, const char*> kAttributeTables[] = {
    {"shapes", "csgtile: distinct sub-shapes of every object (id, key, kind, tolerance)"},
    {"shape_children",
     "csgtile: sub-shape references (parent, child, position, orientation, location)"},
    {"shape_ancestors", "csgtile: ancestor maps vertex>edge, edge>face, face>shell, face>solid"},
    {"object_relations",
     "csgtile: touches / overlaps / contains / within / equals between objects"},
    {"csg_nodes", "csgtile: CSG trees (post-order nodes: operations and primitives)"},
    {"face_sources", "csgtile: CSG history, the primitive faces each face comes from"},
    {"primitives", "csgtile: primitives of each object with their fit quality"},
    {"index_metadata", "csgtile: format, version and parameters of this index"},
};

// ---- GeoPackage binary geometry ---------------------------------------------------------------

class LittleEndian {
 public:
  void byte(std::uint8_t v) { out_.push_back(static_cast<char>(v)); }
  void u32(std::uint32_t v) {
    for (int i = 0; i < 4; ++i) byte(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  void f64(double v) {
    const auto bits = std::bit_cast<std::uint64_t>(v);
    for (int i = 0; i < 8; ++i) byte(static_cast<std::uint8_t>(bits >> (8 * i)));
  }
  std::string take() { return std::move(out_); }

 private:
  std::string out_;
};

// "GP", version 0, flags (little-endian, XYZ envelope, not empty, standard binary), srs_id,
// envelope [minx, maxx, miny, maxy, minz, maxz], then ISO WKB MultiPolygon Z (type 1006) of
// Polygon Z (1003), little-endian throughout.
std::string geopackage_multipolygon_z(const std::vector<Polygon3>& polygons, int srs_id) {
  kernel::BoundingBox box;
  for (const Polygon3& p : polygons) {
    for (const auto& ring : p.rings) {
      for (const kernel::Vec3& v : ring) box.add(v);
    }
  }
  LittleEndian w;
  w.byte('G');
  w.byte('P');
  w.byte(0);
  w.byte(0x01 | (2 << 1));
  w.u32(static_cast<std::uint32_t>(srs_id));
  for (int axis = 0; axis < 3; ++axis) {
    w.f64(box.min[axis]);
    w.f64(box.max[axis]);
  }
  w.byte(1);
  w.u32(1006);
  w.u32(static_cast<std::uint32_t>(polygons.size()));
  for (const Polygon3& p : polygons) {
    w.byte(1);
    w.u32(1003);
    w.u32(static_cast<std::uint32_t>(p.rings.size()));
    for (const auto& ring : p.rings) {
      w.u32(static_cast<std::uint32_t>(ring.size()));
      for (const kernel::Vec3& v : ring) {
        w.f64(v.x());
        w.f64(v.y());
        w.f64(v.z());
      }
    }
  }
  return w.take();
}

kernel::BoundingBox boundary_box(const std::vector<Polygon3>& boundary) {
  kernel::BoundingBox box;
  for (const Polygon3& p : boundary) {
    for (const auto& ring : p.rings) {
      for (const kernel::Vec3& v : ring) box.add(v);
    }
  }
  return box;
}

// ---- table writers ------------------------------------------------------------------------------

#define CSGTILE_TRY(expr)                            \
  do {                                               \
    if (Failure st_ = (expr); !st_.ok()) return st_; \
  } while (false)

Failure insert_srs(SqliteDb& db, const IndexSrs& srs) {
  SqliteStatement st(
      db,
      "INSERT INTO gpkg_spatial_ref_sys (srs_name, srs_id, organization, "
      "organization_coordsys_id, definition, description) VALUES (?1,?2,?3,?4,?5,?6)");
  CSGTILE_TRY(st.status());
  auto row = [&](const std::string& name, std::int64_t id, const std::string& org,
                 std::int64_t code, const std::string& definition, const std::string& description) {
    st.bind(1, name)
        .bind(2, id)
        .bind(3, org)
        .bind(4, code)
        .bind(5, definition)
        .bind(6, description);
    return st.run();
  };
  CSGTILE_TRY(row("Undefined Cartesian SRS", -1, "NONE", -1, "undefined",
                  "undefined Cartesian coordinate reference system"));
  CSGTILE_TRY(row("Undefined geographic SRS", 0, "NONE", 0, "undefined",
                  "undefined geographic coordinate reference system"));
  CSGTILE_TRY(row("WGS 84 geodetic", 4326, "EPSG", 4326, kWgs84Wkt,
                  "longitude/latitude coordinates in decimal degrees on the WGS 84 spheroid"));
  if (srs.srs_id != -1 && srs.srs_id != 0 && srs.srs_id != 4326) {
    CSGTILE_TRY(row(srs.name, srs.srs_id, srs.organization, srs.organization_coordsys_id,
                    srs.definition_wkt, srs.name));
  }
  return {};
}

// The statements of the rows of objects (write_gpkg and GpkgRowWriter), prepared once.
struct RowStatements {
  explicit RowStatements(const SqliteDb& db)
      : objects(db,
                "INSERT INTO objects (fid, geom, object_id, cell, shape_id, primitive_count, "
                "primitive_types, volume, area, min_x, min_y, min_z, max_x, max_y, max_z, valid, "
                "fit_rms, fit_coverage, lod, h_ground, h_roof_min, h_roof_50p, h_roof_70p, "
                "h_roof_max, roof_surfaces, fuse_error, lod12_error, footprint_id, outline, "
                "fit_within_2sigma, lod13_error, model_rmse, model_points, model_within_2sigma) "
                "VALUES (?1,?2,?3,?4,?5,?6,?7,?8,?9,?10,?11,?12,?13,?14,?15,?16,?17,?18,?19,?20,"
                "?21,?22,?23,?24,?25,?26,?27,?28,?29,?30,?31,?32,?33,?34)"),
        rtree(db, "INSERT INTO rtree_objects_geom VALUES (?1,?2,?3,?4,?5)"),
        block(db,
              "INSERT INTO lod12 (fid, geom, object_id, cell, h_ground, h_top) "
              "VALUES (?1,?2,?3,?4,?5,?6)"),
        block_rtree(db, "INSERT INTO rtree_lod12_geom VALUES (?1,?2,?3,?4,?5)"),
        levels(db,
               "INSERT INTO lod13 (fid, geom, object_id, cell, h_ground, h_top) "
               "VALUES (?1,?2,?3,?4,?5,?6)"),
        levels_rtree(db, "INSERT INTO rtree_lod13_geom VALUES (?1,?2,?3,?4,?5)"),
        shapes(db,
               "INSERT INTO shapes (id, key, object_id, kind, kind_index, orientation, "
               "tolerance, geometry, x, y, z) VALUES (?1,?2,?3,?4,?5,?6,?7,?8,?9,?10,?11)"),
        children(db,
                 "INSERT INTO shape_children (parent_id, child_id, position, orientation, "
                 "location) VALUES (?1,?2,?3,?4,?5)"),
        ancestors(db,
                  "INSERT INTO shape_ancestors (shape_id, ancestor_kind, ancestor_id, position) "
                  "VALUES (?1,?2,?3,?4)"),
        csg_nodes(db,
                  "INSERT INTO csg_nodes (object_id, node, kind, label, parent, children, "
                  "primitive_type, parameters) VALUES (?1,?2,?3,?4,?5,?6,?7,?8)"),
        face_sources(db,
                     "INSERT INTO face_sources (face_id, object_id, node, primitive_face) "
                     "VALUES (?1,?2,?3,?4)"),
        primitives(db,
                   "INSERT INTO primitives (object_id, node, primitive_id, type, inliers, "
                   "fit_rms, fit_coverage) VALUES (?1,?2,?3,?4,?5,?6,?7)") {}
  Failure status() const {
    for (const SqliteStatement* st :
         {&objects, &rtree, &block, &block_rtree, &levels, &levels_rtree, &shapes, &children,
          &ancestors, &csg_nodes, &face_sources, &primitives}) {
      CSGTILE_TRY(st->status());
    }
    return {};
  }
  SqliteStatement objects, rtree, block, block_rtree, levels, levels_rtree, shapes, children,
      ancestors, csg_nodes, face_sources, primitives;
};

// The last feature ids written to the objects, lod12 and lod13 layers.
using FeatureIds = std::array<std::int64_t, 3>;

Failure insert_objects(RowStatements& sts, const IndexRows& rows, int srs_id, FeatureIds& fids) {
  SqliteStatement& st = sts.objects;
  SqliteStatement& rtree = sts.rtree;
  SqliteStatement& block = sts.block;
  SqliteStatement& block_rtree = sts.block_rtree;
  SqliteStatement& levels = sts.levels;
  SqliteStatement& levels_rtree = sts.levels_rtree;
  std::int64_t& block_fid = fids[1];
  std::int64_t& levels_fid = fids[2];
  for (const ObjectRecord& o : rows.objects) {
    const std::int64_t fid = ++fids[0];
    st.bind(1, fid);
    if (o.has_geometry) {
      st.bind_blob(2, geopackage_multipolygon_z(o.boundary, srs_id));
    } else {
      st.bind_null(2);
    }
    st.bind(3, o.object_id).bind(4, o.cell).bind(5, o.shape_id).bind(6, o.primitive_count);
    st.bind(7, o.primitive_types).bind(8, o.volume).bind(9, o.area);
    if (o.bounds.empty()) {
      for (int c = 10; c <= 15; ++c) st.bind_null(c);
    } else {
      for (int a = 0; a < 3; ++a) {
        st.bind(10 + a, o.bounds.min[a]);
        st.bind(13 + a, o.bounds.max[a]);
      }
    }
    st.bind(16, static_cast<std::int64_t>(o.valid ? 1 : 0))
        .bind(17, o.fit_rms)
        .bind(18, o.fit_coverage);
    st.bind(19, o.lod).bind(20, o.h_ground).bind(21, o.h_roof_min).bind(22, o.h_roof_50p);
    st.bind(23, o.h_roof_70p).bind(24, o.h_roof_max).bind(25, o.roof_surfaces);
    st.bind(26, o.fuse_error).bind(27, o.lod12_error).bind(28, o.footprint_id).bind(29, o.outline);
    st.bind(30, o.fit_within_2sigma).bind(31, o.lod13_error);
    st.bind(32, o.model_rmse).bind(33, o.model_points).bind(34, o.model_within_2sigma);
    CSGTILE_TRY(st.run());
    // SQLite's R-tree stores 32-bit floats, rounded outwards.
    auto index = [](SqliteStatement& tree, std::int64_t id, const kernel::BoundingBox& b) {
      tree.bind(1, id).bind(2, b.min.x()).bind(3, b.max.x()).bind(4, b.min.y());
      tree.bind(5, b.max.y());
      return tree.run();
    };
    if (o.has_geometry) CSGTILE_TRY(index(rtree, fid, boundary_box(o.boundary)));
    if (o.has_lod12 && o.h_ground && o.h_roof_70p) {
      ++block_fid;
      block.bind(1, block_fid).bind_blob(2, geopackage_multipolygon_z(o.lod12_boundary, srs_id));
      block.bind(3, o.object_id).bind(4, o.cell).bind(5, *o.h_ground).bind(6, *o.h_roof_70p);
      CSGTILE_TRY(block.run());
      CSGTILE_TRY(index(block_rtree, block_fid, boundary_box(o.lod12_boundary)));
    }
    if (o.has_lod13 && o.h_ground) {
      ++levels_fid;
      const kernel::BoundingBox box = boundary_box(o.lod13_boundary);
      levels.bind(1, levels_fid).bind_blob(2, geopackage_multipolygon_z(o.lod13_boundary, srs_id));
      levels.bind(3, o.object_id).bind(4, o.cell).bind(5, *o.h_ground).bind(6, box.max.z());
      CSGTILE_TRY(levels.run());
      CSGTILE_TRY(index(levels_rtree, levels_fid, box));
    }
  }
  return {};
}

// Inserts every row of `rows` with one prepared statement; `bind` binds one row.
template <class Row, class Bind>
Failure insert_each(SqliteStatement& st, const std::vector<Row>& rows, const Bind& bind) {
  for (const Row& r : rows) {
    bind(st, r);
    CSGTILE_TRY(st.run());
  }
  return {};
}

Failure insert_relations(SqliteDb& db, const std::vector<RelationRecord>& relations) {
  SqliteStatement insert(db,
                         "INSERT INTO object_relations (object_id, other_id, relation, "
                         "shared_area, common_volume, reason) VALUES (?1,?2,?3,?4,?5,?6)");
  CSGTILE_TRY(insert.status());
  return insert_each(insert, relations, [](SqliteStatement& st, const RelationRecord& r) {
    st.bind(1, r.object_id).bind(2, r.other_id).bind(3, r.relation).bind(4, r.shared_area);
    st.bind(5, r.common_volume).bind_text_or_null(6, r.reason);
  });
}

// Every row of `rows` but the relations.
Failure insert_rows(RowStatements& sts, const IndexRows& rows) {
  CSGTILE_TRY(insert_each(sts.shapes, rows.shapes, [](SqliteStatement& st, const ShapeRecord& r) {
    st.bind(1, r.id).bind(2, r.key).bind(3, r.object_id).bind(4, r.kind).bind(5, r.kind_index);
    st.bind(6, r.orientation).bind(7, r.tolerance).bind_text_or_null(8, r.geometry);
    for (int a = 0; a < 3; ++a) {
      if (r.point) {
        st.bind(9 + a, (*r.point)[a]);
      } else {
        st.bind_null(9 + a);
      }
    }
  }));
  CSGTILE_TRY(
      insert_each(sts.children, rows.children, [](SqliteStatement& st, const ChildRecord& r) {
        st.bind(1, r.parent_id).bind(2, r.child_id).bind(3, r.position).bind(4, r.orientation);
        st.bind_text_or_null(5, r.location);
      }));
  CSGTILE_TRY(
      insert_each(sts.ancestors, rows.ancestors, [](SqliteStatement& st, const AncestorRecord& r) {
        st.bind(1, r.shape_id).bind(2, r.ancestor_kind).bind(3, r.ancestor_id).bind(4, r.position);
      }));
  CSGTILE_TRY(
      insert_each(sts.csg_nodes, rows.csg_nodes, [](SqliteStatement& st, const CsgNodeRecord& r) {
        st.bind(1, r.object_id).bind(2, r.node).bind(3, r.kind).bind_text_or_null(4, r.label);
        st.bind(5, r.parent).bind(6, r.children).bind_text_or_null(7, r.primitive_type);
        st.bind_text_or_null(8, r.parameters);
      }));
  CSGTILE_TRY(insert_each(
      sts.face_sources, rows.face_sources, [](SqliteStatement& st, const FaceSourceRecord& r) {
        st.bind(1, r.face_id).bind(2, r.object_id).bind(3, r.node).bind(4, r.primitive_face);
      }));
  CSGTILE_TRY(insert_each(sts.primitives, rows.primitives,
                          [](SqliteStatement& st, const PrimitiveRecord& r) {
                            st.bind(1, r.object_id)
                                .bind(2, r.node)
                                .bind_text_or_null(3, r.primitive_id)
                                .bind(4, r.type);
                            st.bind(5, r.inliers).bind(6, r.fit_rms).bind(7, r.fit_coverage);
                          }));
  return {};
}

Failure insert_metadata(SqliteDb& db, const IndexOptions& options) {
  {
    SqliteStatement st(db, "INSERT INTO index_metadata (key, value) VALUES (?1, ?2)");
    CSGTILE_TRY(st.status());
    std::string pairs;
    for (const auto& [child, ancestor] : kAncestorPairs) {
      pairs += std::string(pairs.empty() ? "" : ",") + kernel::shape_kind_name(child) + ">" +
               kernel::shape_kind_name(ancestor);
    }
    char chordal[32];
    std::snprintf(chordal, sizeof chordal, "%.17g", options.chordal_tolerance);
    const std::pair<std::string, std::string> entries[] = {
        {"format", "csgtile-topology-index"},
        {"format_version", "1"},
        {"csgtile_version", CSGTILE_VERSION},
        {"shape_ids",
         "(object order, kind compound..vertex, map_child_shapes order) from 1; "
         "key <object>/<kind>/<index>"},
        {"ancestor_pairs", pairs},
        {"chordal_tolerance", chordal},
    };
    for (const auto& [key, value] : entries) {
      st.bind(1, key).bind(2, value);
      CSGTILE_TRY(st.run());
    }
  }
  return {};
}

// The extents of the feature tables (kFeatureTables order) for gpkg_contents.
using FeatureExtents = std::array<kernel::BoundingBox, 3>;

void add_extents(const IndexRows& rows, FeatureExtents& e) {
  for (const ObjectRecord& o : rows.objects) {
    if (o.has_geometry) e[0].add(boundary_box(o.boundary));
    if (o.has_lod12) e[1].add(boundary_box(o.lod12_boundary));
    if (o.has_lod13) e[2].add(boundary_box(o.lod13_boundary));
  }
}

Failure register_contents(SqliteDb& db, const FeatureExtents& extents,
                          const IndexOptions& options) {
  SqliteStatement st(
      db,
      "INSERT INTO gpkg_contents (table_name, data_type, identifier, description, "
      "last_change, min_x, min_y, max_x, max_y, srs_id) VALUES (?1,?2,?3,?4,?5,?6,?7,"
      "?8,?9,?10)");
  CSGTILE_TRY(st.status());
  for (const auto& [table, description, box] : kFeatureTables) {
    const kernel::BoundingBox& b = extents[static_cast<std::size_t>(box)];
    st.bind(1, std::string_view(table)).bind(2, std::string_view("features"));
    st.bind(3, std::string_view(table)).bind(4, std::string_view(description));
    st.bind(5, options.last_change);
    if (b.empty()) {
      for (int c = 6; c <= 9; ++c) st.bind_null(c);
    } else {
      st.bind(6, b.min.x()).bind(7, b.min.y()).bind(8, b.max.x()).bind(9, b.max.y());
    }
    st.bind(10, static_cast<std::int64_t>(options.srs.srs_id));
    CSGTILE_TRY(st.run());
  }
  for (const auto& [table, description] : kAttributeTables) {
    st.bind(1, std::string_view(table)).bind(2, std::string_view("attributes"));
    st.bind(3, std::string_view(table)).bind(4, std::string_view(description));
    st.bind(5, options.last_change);
    for (int c = 6; c <= 10; ++c) st.bind_null(c);
    CSGTILE_TRY(st.run());
  }
  SqliteStatement geometry(db,
                           "INSERT INTO gpkg_geometry_columns (table_name, column_name, "
                           "geometry_type_name, srs_id, z, m) VALUES (?1, 'geom', "
                           "'MULTIPOLYGON', ?2, 1, 0)");
  SqliteStatement extension(
      db,
      "INSERT INTO gpkg_extensions (table_name, column_name, extension_name, definition, scope) "
      "VALUES (?1, 'geom', 'gpkg_rtree_index', "
      "'http://www.geopackage.org/spec120/#extension_rtree', 'write-only')");
  CSGTILE_TRY(geometry.status());
  CSGTILE_TRY(extension.status());
  for (const auto& feature_table : kFeatureTables) {
    const std::string_view table = feature_table.table;
    geometry.bind(1, table).bind(2, static_cast<std::int64_t>(options.srs.srs_id));
    CSGTILE_TRY(geometry.run());
    extension.bind(1, table);
    CSGTILE_TRY(extension.run());
  }
  return {};
}

// The schema, in the transaction begun here.
Failure begin_gpkg(SqliteDb& db, const IndexOptions& options) {
  // The file is a temporary that is deleted on failure and fsync'ed by the caller: no journal
  // file, no syncs here. Set first: a header pragma before them wrote and synced a journal.
  CSGTILE_TRY(db.exec("PRAGMA journal_mode = MEMORY; PRAGMA synchronous = OFF;"));
  CSGTILE_TRY(db.exec("BEGIN;"));
  // application_id 'GPKG' and user_version 10300 (GeoPackage 1.3), in the one transaction.
  CSGTILE_TRY(db.exec("PRAGMA application_id = 1196444487; PRAGMA user_version = 10300;"));
  CSGTILE_TRY(db.exec(kCoreSchema));
  CSGTILE_TRY(insert_srs(db, options.srs));
  CSGTILE_TRY(db.exec(kIndexSchema));
  for (const auto& feature_table : kFeatureTables) {
    CSGTILE_TRY(db.exec(for_table(kRtree, feature_table.table)));
  }
  return {};
}

// After the rows: the metadata, the indexes, the R-trees' triggers and the contents; commits.
Failure finish_gpkg(SqliteDb& db, const FeatureExtents& extents, const IndexOptions& options) {
  CSGTILE_TRY(insert_metadata(db, options));
  CSGTILE_TRY(db.exec(kIndexIndexes));
  for (const auto& feature_table : kFeatureTables) {
    CSGTILE_TRY(db.exec(for_table(kRtreeTriggers, feature_table.table)));
  }
  CSGTILE_TRY(register_contents(db, extents, options));
  return db.exec("COMMIT;");
}

// ---- merging indexes ----------------------------------------------------------------------------

// A primitive's parameters (topology_index.cpp, primitive_parameters) moved by `by`: the
// translation column of its placement.
std::string moved_parameters(const std::string& text, const kernel::Vec3& by) {
  if (text.empty() || by.isZero(0.0)) return text;
  nlohmann::ordered_json j = nlohmann::ordered_json::parse(text, nullptr, false);
  if (!j.is_object() || !j.contains("placement")) return text;
  nlohmann::ordered_json& m = j["placement"];
  for (int r = 0; r < 3; ++r) m[r][3] = m[r][3].get<double>() + by[r];
  return j.dump();
}

// Row count of `table` in the database `schema`.
Failure count_rows(SqliteDb& db, const std::string& schema, const char* table, std::int64_t& n) {
  SqliteStatement st(db, "SELECT COUNT(*) FROM " + schema + "." + table);
  CSGTILE_TRY(st.status());
  if (st.step() != SQLITE_ROW) return db.failure("cannot count the rows of");
  n = st.integer(0);
  return {};
}

// `sql` with ?1 bound to `offset`, run once.
Failure run_offset(SqliteDb& db, const std::string& sql, std::int64_t offset) {
  SqliteStatement st(db, sql);
  CSGTILE_TRY(st.status());
  st.bind(1, offset);
  return st.run();
}

// Appends the rows of the attached database "part" (an index of the same schema and SRS),
// ids after those already in: objects and blocks by `fids`, shapes by `shapes`.
Failure append_part(SqliteDb& db, const kernel::Vec3& offset, std::array<std::int64_t, 3>& fids,
                    std::int64_t& shapes, FeatureExtents& extents) {
  // The extents of its feature tables.
  {
    SqliteStatement st(db,
                       "SELECT table_name, min_x, min_y, max_x, max_y FROM part.gpkg_contents "
                       "WHERE min_x IS NOT NULL");
    CSGTILE_TRY(st.status());
    int rc;
    while ((rc = st.step()) == SQLITE_ROW) {
      const std::string table = st.text(0);
      for (std::size_t t = 0; t < std::size(kFeatureTables); ++t) {
        if (table != kFeatureTables[t].table) continue;
        extents[t].add(kernel::Vec3(st.real(1), st.real(2), 0.0));
        extents[t].add(kernel::Vec3(st.real(3), st.real(4), 0.0));
      }
    }
    if (rc != SQLITE_DONE) return db.failure("cannot read gpkg_contents of a part of");
  }
  const std::string columns =
      "primitive_count, primitive_types, volume, area, min_x, min_y, min_z, max_x, max_y, max_z, "
      "valid, fit_rms, fit_coverage, lod, h_ground, h_roof_min, h_roof_50p, h_roof_70p, "
      "h_roof_max, roof_surfaces, fuse_error, lod12_error, footprint_id, outline, "
      "fit_within_2sigma, lod13_error, model_rmse, model_points, model_within_2sigma";
  // An INSERT … SELECT of no rows would still give an AUTOINCREMENT table its
  // sqlite_sequence row, which write_gpkg gives only tables with rows.
  std::array<std::int64_t, 3> added{};
  for (std::size_t t = 0; t < std::size(kFeatureTables); ++t) {
    const std::string table = kFeatureTables[t].table;
    CSGTILE_TRY(count_rows(db, "part", kFeatureTables[t].table, added[t]));
    if (added[t] == 0) continue;
    if (t == 0) {
      SqliteStatement st(db, "INSERT INTO main.objects (fid, geom, object_id, cell, shape_id, " +
                                 columns +
                                 ") SELECT fid + ?1, geom, object_id, cell, shape_id + ?2, " +
                                 columns + " FROM part.objects ORDER BY fid");
      CSGTILE_TRY(st.status());
      st.bind(1, fids[0]).bind(2, shapes);
      CSGTILE_TRY(st.run());
    } else {
      CSGTILE_TRY(run_offset(db,
                             "INSERT INTO main." + table +
                                 " (fid, geom, object_id, cell, h_ground, h_top) SELECT fid + ?1, "
                                 "geom, object_id, cell, h_ground, h_top FROM part." +
                                 table + " ORDER BY fid",
                             fids[t]));
    }
    CSGTILE_TRY(run_offset(db,
                           "INSERT INTO main.rtree_" + table +
                               "_geom SELECT id + ?1, minx, maxx, miny, maxy FROM part.rtree_" +
                               table + "_geom ORDER BY id",
                           fids[t]));
  }
  // Shape ids: a reference to no shape (0) stays 0.
  CSGTILE_TRY(run_offset(db,
                         "INSERT INTO main.shapes (id, key, object_id, kind, kind_index, "
                         "orientation, tolerance, geometry, x, y, z) SELECT id + ?1, key, "
                         "object_id, kind, kind_index, orientation, tolerance, geometry, x, y, z "
                         "FROM part.shapes ORDER BY id",
                         shapes));
  CSGTILE_TRY(run_offset(db,
                         "INSERT INTO main.shape_children (parent_id, child_id, position, "
                         "orientation, location) SELECT parent_id + ?1, CASE child_id WHEN 0 "
                         "THEN 0 ELSE child_id + ?1 END, position, orientation, location FROM "
                         "part.shape_children ORDER BY id",
                         shapes));
  CSGTILE_TRY(run_offset(db,
                         "INSERT INTO main.shape_ancestors (shape_id, ancestor_kind, ancestor_id, "
                         "position) SELECT CASE shape_id WHEN 0 THEN 0 ELSE shape_id + ?1 END, "
                         "ancestor_kind, CASE ancestor_id WHEN 0 THEN 0 ELSE ancestor_id + ?1 "
                         "END, position FROM part.shape_ancestors ORDER BY id",
                         shapes));
  {
    // The primitives' placements are in the part's frame: moved into the merged index's.
    SqliteStatement read(db,
                         "SELECT object_id, node, kind, label, parent, children, primitive_type, "
                         "parameters FROM part.csg_nodes ORDER BY id");
    SqliteStatement write(db,
                          "INSERT INTO main.csg_nodes (object_id, node, kind, label, parent, "
                          "children, primitive_type, parameters) VALUES (?1,?2,?3,?4,?5,?6,?7,?8)");
    CSGTILE_TRY(read.status());
    CSGTILE_TRY(write.status());
    int rc;
    while ((rc = read.step()) == SQLITE_ROW) {
      write.bind(1, read.text(0)).bind(2, read.integer(1)).bind(3, read.text(2));
      write.bind_text_or_null(4, read.text(3));
      if (read.is_null(4)) {
        write.bind_null(5);
      } else {
        write.bind(5, read.integer(4));
      }
      write.bind(6, read.text(5)).bind_text_or_null(7, read.text(6));
      write.bind_text_or_null(8, moved_parameters(read.text(7), offset));
      CSGTILE_TRY(write.run());
    }
    if (rc != SQLITE_DONE) return db.failure("cannot read csg_nodes of a part of");
  }
  CSGTILE_TRY(run_offset(db,
                         "INSERT INTO main.face_sources (face_id, object_id, node, primitive_face) "
                         "SELECT face_id + ?1, object_id, node, primitive_face FROM "
                         "part.face_sources ORDER BY id",
                         shapes));
  CSGTILE_TRY(db.exec(
      "INSERT INTO main.primitives (object_id, node, primitive_id, type, inliers, fit_rms, "
      "fit_coverage) SELECT object_id, node, primitive_id, type, inliers, fit_rms, fit_coverage "
      "FROM part.primitives ORDER BY id"));
  std::int64_t part_shapes = 0;
  CSGTILE_TRY(count_rows(db, "part", "shapes", part_shapes));
  for (std::size_t t = 0; t < 3; ++t) fids[t] += added[t];
  shapes += part_shapes;
  return {};
}

// Whether the merged objects are exactly `ids`, in order (InputInvalid naming the first that
// is not).
Failure expect_objects(SqliteDb& db, const std::vector<std::string>& ids) {
  SqliteStatement st(db, "SELECT object_id FROM main.objects ORDER BY fid");
  CSGTILE_TRY(st.status());
  std::size_t i = 0;
  for (int rc; (rc = st.step()) != SQLITE_DONE; ++i) {
    if (rc != SQLITE_ROW) return db.failure("cannot read the objects of");
    if (i >= ids.size() || st.text(0) != ids[i]) {
      return {ErrorCode::InputInvalid,
              "the indexes to merge hold object " + st.text(0) + " where the run has " +
                  (i < ids.size() ? ids[i] : std::string("no more objects"))};
    }
  }
  if (i != ids.size()) {
    return {ErrorCode::InputInvalid, "the indexes to merge hold " + std::to_string(i) +
                                         " objects, the run " + std::to_string(ids.size())};
  }
  return {};
}

Failure merge_all(SqliteDb& db, const std::vector<GpkgPart>& parts,
                  const std::vector<std::string>& object_ids,
                  const std::vector<RelationRecord>& relations, const IndexOptions& options,
                  GpkgCounts& counts) {
  CSGTILE_TRY(begin_gpkg(db, options));
  // A database is attached between transactions.
  CSGTILE_TRY(db.exec("COMMIT;"));
  std::array<std::int64_t, 3> fids{};
  std::int64_t shapes = 0;
  FeatureExtents extents;
  for (const GpkgPart& part : parts) {
    {
      SqliteStatement attach(db, "ATTACH DATABASE ?1 AS part");
      CSGTILE_TRY(attach.status());
      attach.bind(1, part.path);
      CSGTILE_TRY(attach.run());
    }
    CSGTILE_TRY(db.exec("BEGIN;"));
    CSGTILE_TRY(append_part(db, part.offset, fids, shapes, extents));
    CSGTILE_TRY(db.exec("COMMIT;"));
    CSGTILE_TRY(db.exec("DETACH DATABASE part;"));
  }
  CSGTILE_TRY(expect_objects(db, object_ids));
  CSGTILE_TRY(db.exec("BEGIN;"));
  CSGTILE_TRY(insert_relations(db, relations));
  CSGTILE_TRY(finish_gpkg(db, extents, options));
  for (auto [table, n] : {std::pair("objects", &counts.objects),
                          {"shapes", &counts.shapes},
                          {"shape_children", &counts.children},
                          {"shape_ancestors", &counts.ancestors},
                          {"csg_nodes", &counts.csg_nodes},
                          {"primitives", &counts.primitives}}) {
    std::int64_t v = 0;
    CSGTILE_TRY(count_rows(db, "main", table, v));
    *n = static_cast<std::size_t>(v);
  }
  return {};
}

#undef CSGTILE_TRY

}  // namespace

Failure merge_gpkgs(const std::string& path, const std::vector<GpkgPart>& parts,
                    const std::vector<std::string>& object_ids,
                    const std::vector<RelationRecord>& relations, const IndexOptions& options,
                    GpkgCounts& counts) {
  SqliteDb db;
  if (Failure st = db.open(path, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE); !st.ok()) return st;
  Failure st = merge_all(db, parts, object_ids, relations, options, counts);
  if (!db.close() && st.ok()) st = db.failure("cannot close");
  return st;
}

struct GpkgRowWriter::State {
  SqliteDb db;
  IndexOptions options;
  std::optional<RowStatements> statements;
  FeatureIds fids{};
  FeatureExtents extents;
  Failure failed;
};

GpkgRowWriter::GpkgRowWriter() : state_(std::make_unique<State>()) {}
GpkgRowWriter::~GpkgRowWriter() = default;

Failure GpkgRowWriter::open(const std::string& path, const IndexOptions& options) {
  State& s = *state_;
  s.options = options;
  s.failed = s.db.open(path, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE);
  if (s.failed.ok()) s.failed = begin_gpkg(s.db, options);
  if (s.failed.ok()) {
    s.statements.emplace(s.db);
    s.failed = s.statements->status();
  }
  return s.failed;
}

Failure GpkgRowWriter::add(const IndexRows& rows) {
  State& s = *state_;
  if (!s.failed.ok()) return s.failed;
  if (!s.statements) return s.failed = {ErrorCode::Internal, "GpkgRowWriter::add before open"};
  s.failed = insert_objects(*s.statements, rows, s.options.srs.srs_id, s.fids);
  if (s.failed.ok()) s.failed = insert_rows(*s.statements, rows);
  add_extents(rows, s.extents);
  return s.failed;
}

Failure GpkgRowWriter::finish(const std::vector<RelationRecord>& relations) {
  State& s = *state_;
  if (s.failed.ok() && !s.statements)
    s.failed = {ErrorCode::Internal, "GpkgRowWriter::finish before open"};
  s.statements.reset();  // finalised before the commit and the close
  if (s.failed.ok()) s.failed = insert_relations(s.db, relations);
  if (s.failed.ok()) s.failed = finish_gpkg(s.db, s.extents, s.options);
  if (!s.db.close() && s.failed.ok()) s.failed = s.db.failure("cannot close");
  return s.failed;
}

Failure write_gpkg(const std::string& path, const IndexRows& rows, const IndexOptions& options) {
  GpkgRowWriter writer;
  if (Failure f = writer.open(path, options); !f.ok()) {
    writer.finish({});
    return f;
  }
  writer.add(rows);
  return writer.finish(rows.relations);
}

}  // namespace csgtile::worker::detail
