// Read-only queries on a topology index: what `csgtile query` answers from.

#include <algorithm>
#include <cctype>
#include <charconv>
#include <filesystem>

#include "export/index_rows.h"
#include "export/sqlite_util.h"

namespace csgtile::worker {

struct TopologyIndexReader::Impl {
  detail::SqliteDb db;
};

TopologyIndexReader::TopologyIndexReader(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
TopologyIndexReader::~TopologyIndexReader() = default;

namespace {

using detail::SqliteStatement;

constexpr const char* kShapeColumns = "s.id, s.key, s.object_id, s.kind, s.kind_index";

ShapeRow read_shape(const SqliteStatement& st, int first) {
  return {st.integer(first), st.text(first + 1), st.text(first + 2), st.text(first + 3),
          st.integer(first + 4)};
}

Failure query_failed(const detail::SqliteDb& db) {
  return {ErrorCode::InputInvalid,
          db.path() + ": not a readable topology index: " + sqlite3_errmsg(db.get())};
}

bool is_kind_name(std::string_view kind) {
  for (int k = 0; k < kernel::kShapeKindCount; ++k) {
    if (kind == kernel::shape_kind_name(static_cast<kernel::ShapeKind>(k))) return true;
  }
  return false;
}

}  // namespace

Result<std::unique_ptr<TopologyIndexReader>> TopologyIndexReader::open(
    const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    return Failure{ErrorCode::Io, "cannot read topology index " + path.string() + ": no such file"};
  }
  auto impl = std::make_unique<Impl>();
  if (Failure st = impl->db.open(path.string(), SQLITE_OPEN_READONLY); !st.ok()) return st;
  // A GeoPackage (application_id 'GPKG') carrying our metadata row.
  SqliteStatement app(impl->db, "PRAGMA application_id");
  if (!app.ok() || app.step() != SQLITE_ROW) return query_failed(impl->db);
  if (app.integer(0) != 0x47504B47) {
    return Failure{ErrorCode::InputInvalid,
                   path.string() + ": not a GeoPackage (application_id is not 'GPKG')"};
  }
  SqliteStatement format(impl->db, "SELECT value FROM index_metadata WHERE key = 'format'");
  if (!format.ok() || format.step() != SQLITE_ROW || format.text(0) != "csgtile-topology-index") {
    return Failure{ErrorCode::InputInvalid,
                   path.string() + ": a GeoPackage without csgtile topology tables"};
  }
  return std::unique_ptr<TopologyIndexReader>(new TopologyIndexReader(std::move(impl)));
}

Result<ShapeRow> TopologyIndexReader::shape(std::string_view id_or_key) const {
  const bool numeric =
      !id_or_key.empty() && std::all_of(id_or_key.begin(), id_or_key.end(), [](char c) {
        return std::isdigit(static_cast<unsigned char>(c));
      });
  SqliteStatement st(impl_->db, std::string("SELECT ") + kShapeColumns + " FROM shapes s WHERE " +
                                    (numeric ? "s.id = ?1" : "s.key = ?1"));
  if (!st.ok()) return query_failed(impl_->db);
  if (numeric) {
    std::int64_t id = 0;
    const auto [end, error] =
        std::from_chars(id_or_key.data(), id_or_key.data() + id_or_key.size(), id);
    if (error != std::errc() || end != id_or_key.data() + id_or_key.size()) {
      return Failure{ErrorCode::InputInvalid,
                     "no shape \"" + std::string(id_or_key) + "\" in the index"};
    }
    st.bind(1, id);
  } else {
    st.bind(1, id_or_key);
  }
  const int rc = st.step();
  if (rc == SQLITE_ROW) return read_shape(st, 0);
  if (rc != SQLITE_DONE) return query_failed(impl_->db);
  return Failure{ErrorCode::InputInvalid,
                 "no shape \"" + std::string(id_or_key) + "\" in the index"};
}

Result<std::vector<ChildRow>> TopologyIndexReader::children(std::int64_t shape_id) const {
  SqliteStatement st(impl_->db, std::string("SELECT c.position, c.orientation, c.location, ") +
                                    kShapeColumns +
                                    " FROM shape_children c JOIN shapes s ON s.id = c.child_id "
                                    "WHERE c.parent_id = ?1 ORDER BY c.position");
  if (!st.ok()) return query_failed(impl_->db);
  st.bind(1, shape_id);
  std::vector<ChildRow> out;
  int rc;
  while ((rc = st.step()) == SQLITE_ROW) {
    out.push_back({st.integer(0), st.text(1), st.text(2), read_shape(st, 3)});
  }
  if (rc != SQLITE_DONE) return query_failed(impl_->db);
  return out;
}

Result<std::vector<ShapeRow>> TopologyIndexReader::ancestors(std::int64_t shape_id,
                                                             std::string_view kind) const {
  if (!is_kind_name(kind)) {
    return Failure{ErrorCode::InputInvalid,
                   "unknown shape kind \"" + std::string(kind) +
                       "\" (compound, compsolid, solid, shell, face, wire, edge, vertex)"};
  }
  // Materialised pair: one index range. Any other pair: walk the references upwards; ancestors
  // of one kind ordered by their index in map_child_shapes, which is the kernel's
  // AncestorIndex order (ancestors are met in their first-visit order).
  SqliteStatement kind_of(impl_->db, "SELECT kind FROM shapes WHERE id = ?1");
  if (!kind_of.ok()) return query_failed(impl_->db);
  kind_of.bind(1, shape_id);
  const std::string child_kind = kind_of.step() == SQLITE_ROW ? kind_of.text(0) : "";
  bool use_map = false;
  for (const auto& [c, a] : detail::kAncestorPairs) {
    use_map |= child_kind == kernel::shape_kind_name(c) && kind == kernel::shape_kind_name(a);
  }
  const std::string sql =
      use_map ? std::string("SELECT ") + kShapeColumns +
                    " FROM shape_ancestors a JOIN shapes s ON s.id = a.ancestor_id "
                    "WHERE a.shape_id = ?1 AND a.ancestor_kind = ?2 ORDER BY a.position"
              : std::string(
                    "WITH RECURSIVE up(id) AS (SELECT parent_id FROM shape_children "
                    "WHERE child_id = ?1 UNION SELECT c.parent_id FROM shape_children c "
                    "JOIN up ON c.child_id = up.id) SELECT ") +
                    kShapeColumns +
                    " FROM up JOIN shapes s ON s.id = up.id WHERE s.kind = ?2 "
                    "ORDER BY s.kind_index";
  SqliteStatement st(impl_->db, sql);
  if (!st.ok()) return query_failed(impl_->db);
  st.bind(1, shape_id).bind(2, kind);
  std::vector<ShapeRow> out;
  int rc;
  while ((rc = st.step()) == SQLITE_ROW) out.push_back(read_shape(st, 0));
  if (rc != SQLITE_DONE) return query_failed(impl_->db);
  return out;
}

Result<std::vector<RelationRow>> TopologyIndexReader::relations(std::string_view object_id) const {
  SqliteStatement exists(impl_->db, "SELECT 1 FROM objects WHERE object_id = ?1");
  if (!exists.ok()) return query_failed(impl_->db);
  exists.bind(1, object_id);
  const int found = exists.step();
  if (found == SQLITE_DONE) {
    return Failure{ErrorCode::InputInvalid,
                   "no object \"" + std::string(object_id) + "\" in the index"};
  }
  if (found != SQLITE_ROW) return query_failed(impl_->db);
  SqliteStatement st(impl_->db,
                     "SELECT r.object_id, r.other_id, r.relation, r.shared_area, r.common_volume, "
                     "r.reason FROM object_relations r JOIN objects o ON o.object_id = r.other_id "
                     "WHERE r.object_id = ?1 ORDER BY o.fid");
  if (!st.ok()) return query_failed(impl_->db);
  st.bind(1, object_id);
  std::vector<RelationRow> out;
  int rc;
  while ((rc = st.step()) == SQLITE_ROW) {
    out.push_back(
        {st.text(0), st.text(1), st.text(2), st.optional_real(3), st.optional_real(4), st.text(5)});
  }
  if (rc != SQLITE_DONE) return query_failed(impl_->db);
  return out;
}

Result<std::vector<std::vector<std::string>>> TopologyIndexReader::sql(
    std::string_view statement, const std::vector<std::string>& parameters) const {
  SqliteStatement st(impl_->db, statement);
  if (!st.ok()) {
    return Failure{ErrorCode::InputInvalid,
                   std::string("bad SQL: ") + sqlite3_errmsg(impl_->db.get())};
  }
  for (std::size_t i = 0; i < parameters.size(); ++i)
    st.bind(static_cast<int>(i + 1), parameters[i]);
  std::vector<std::vector<std::string>> out;
  int rc;
  while ((rc = st.step()) == SQLITE_ROW) {
    std::vector<std::string> row;
    for (int c = 0; c < st.columns(); ++c) row.push_back(st.is_null(c) ? "NULL" : st.text(c));
    out.push_back(std::move(row));
  }
  if (rc != SQLITE_DONE) return query_failed(impl_->db);
  return out;
}

}  // namespace csgtile::worker
