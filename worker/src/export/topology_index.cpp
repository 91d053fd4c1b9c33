// Rows of the topology index from objects: stable ids, the child and ancestor maps, the
// objects layer's boundary polygons, CSG nodes, face sources, primitives and relations.

#include <tbb/info.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <functional>
#include <iterator>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <system_error>

#include "csgtile/kernel/check.h"
#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/face_rings.h"
#include "csgtile/kernel/mass_properties.h"
#include "csgtile/kernel/tessellation.h"
#include "csgtile/worker/files.h"
#include "export/index_rows.h"

namespace csgtile::worker {

namespace detail {
namespace {

using kernel::EdgePoints;
using kernel::planar_face_rings;
using kernel::Shape;
using kernel::ShapeKind;
using kernel::Vec3;
using Json = nlohmann::ordered_json;

const char* surface_kind_name(kernel::SurfaceKind kind) {
  switch (kind) {
    case kernel::SurfaceKind::Plane:
      return "plane";
    case kernel::SurfaceKind::Cylinder:
      return "cylinder";
    case kernel::SurfaceKind::Cone:
      return "cone";
    case kernel::SurfaceKind::Sphere:
      return "sphere";
    case kernel::SurfaceKind::Torus:
      return "torus";
    case kernel::SurfaceKind::Extrusion:
      return "extrusion";
    case kernel::SurfaceKind::Revolution:
      return "revolution";
  }
  return "surface";
}

const char* curve_kind_name(kernel::CurveKind kind) {
  switch (kind) {
    case kernel::CurveKind::Line:
      return "line";
    case kernel::CurveKind::Circle:
      return "circle";
    case kernel::CurveKind::Ellipse:
      return "ellipse";
    case kernel::CurveKind::Polyline:
      return "polyline";
    case kernel::CurveKind::Trig:
      return "trig";
  }
  return "curve";
}

Json matrix_json(const kernel::Location& location) {
  const kernel::Matrix34 m = location.matrix();
  Json rows = Json::array();
  for (int r = 0; r < 3; ++r) rows.push_back({m(r, 0), m(r, 1), m(r, 2), m(r, 3)});
  return rows;
}

Json points_json(const std::vector<kernel::Vec2>& points) {
  Json out = Json::array();
  for (const auto& p : points) out.push_back({p.x(), p.y()});
  return out;
}

// The parameters of a primitive, keyed as the scene format names them.
std::string primitive_parameters(const kernel::PrimitiveSpec& spec) {
  Json j;
  switch (spec.type) {
    case kernel::PrimitiveType::Box:
      j["size"] = {spec.size.x(), spec.size.y(), spec.size.z()};
      break;
    case kernel::PrimitiveType::Cylinder:
      j["r"] = spec.radius;
      j["h"] = spec.height;
      break;
    case kernel::PrimitiveType::Cone:
      j["r1"] = spec.radius;
      j["r2"] = spec.radius2;
      j["h"] = spec.height;
      break;
    case kernel::PrimitiveType::Sphere:
      j["r"] = spec.radius;
      break;
    case kernel::PrimitiveType::Torus:
      j["R"] = spec.radius;
      j["r"] = spec.radius2;
      break;
    case kernel::PrimitiveType::Extrusion: {
      j["profile"] = points_json(spec.profile);
      Json holes = Json::array();
      for (const auto& h : spec.holes) holes.push_back(points_json(h));
      j["holes"] = std::move(holes);
      j["h"] = spec.height;
      break;
    }
    case kernel::PrimitiveType::Revolution:
      j["profile"] = points_json(spec.profile);
      j["angle"] = spec.angle;
      break;
  }
  if (!spec.clips.empty()) {
    Json clips = Json::array();
    for (const auto& c : spec.clips) clips.push_back(Json::array({c.x(), c.y(), c.z(), c.w()}));
    j["clip"] = std::move(clips);
  }
  j["placement"] = matrix_json(spec.placement);
  return j.dump();
}

Vec3 map_point(const IndexOptions& options, const Vec3& p) {
  return options.to_srs ? options.to_srs(p) : p;
}

// The rings of a planar face as a polygon with closed rings (face_rings.h).
std::optional<Polygon3> planar_face_polygon(const Shape& face, const EdgePoints& edge_points) {
  auto rings = planar_face_rings(face, edge_points);
  if (!rings) return std::nullopt;
  Polygon3 polygon{std::move(*rings)};
  for (auto& ring : polygon.rings) ring.push_back(ring.front());
  return polygon;
}

// The object's boundary: planar faces as polygons with holes, curved faces as the triangles
// of the tessellation. Planar faces of a solid with curved faces take their edges' points
// from the same tessellation, so the boundary has no cracks; a solid with planar faces only
// has straight edges and its polygons are exactly its faces. Faces used Internal or External
// bound nothing and are left out.
kernel::Result<std::vector<Polygon3>> boundary_polygons(
    const Shape& root, const kernel::ShapeIndex& faces, const kernel::ShapeIndex& edges,
    const IndexOptions& options, std::shared_ptr<const kernel::Mesh> given = {}) {
  std::vector<Polygon3> out;
  bool any_curved = false;
  for (const Shape& f : faces.shapes()) {
    any_curved |= f.body().face()->surface->kind() != kernel::SurfaceKind::Plane;
  }
  // `given`: root's tessellation at the chordal tolerance, shared with the other exporters.
  std::shared_ptr<const kernel::Mesh> shared;
  if (any_curved) {
    auto meshed = kernel::shared_tessellation(root, options.chordal_tolerance, std::move(given));
    if (!meshed.ok()) return meshed.error();
    shared = std::move(meshed).value();
  }
  static const kernel::Mesh kNoMesh;
  const kernel::Mesh& mesh = shared ? *shared : kNoMesh;
  const EdgePoints edge_points = [&](const Shape& edge) {
    std::vector<Vec3> points;
    const kernel::EdgeData* data = edge.body().edge();
    if (data == nullptr || data->degenerate()) return points;
    if (any_curved) {
      const std::size_t e = edges.find(edge);
      if (e < mesh.edge_vertices.size()) {
        for (std::uint32_t v : mesh.edge_vertices[e]) points.push_back(mesh.vertices[v]);
      }
      return points;
    }
    for (double t : kernel::discretize_edge(edge, options.chordal_tolerance, 0.5)) {
      points.push_back(edge.location().apply_point(data->curve->point(t)));
    }
    // The ends are the edge's vertices (a curve end is only within tolerance of them), so
    // that the rings of neighbouring faces meet exactly. Read through the edge used Forward:
    // its start vertex is then the Forward child.
    for (const Shape& v : edge.oriented(kernel::Orientation::Forward).children()) {
      if (points.empty()) break;
      if (v.orientation() == kernel::Orientation::Forward) points.front() = kernel::vertex_point(v);
      if (v.orientation() == kernel::Orientation::Reversed) points.back() = kernel::vertex_point(v);
    }
    return points;
  };
  // Triangles grouped by face, in mesh order.
  std::vector<std::vector<std::size_t>> triangles_of(faces.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    if (mesh.triangle_face[t] < faces.size()) triangles_of[mesh.triangle_face[t]].push_back(t);
  }
  for (std::size_t i = 0; i < faces.size(); ++i) {
    const Shape& face = faces[i];
    if (face.orientation() != kernel::Orientation::Forward &&
        face.orientation() != kernel::Orientation::Reversed) {
      continue;
    }
    if (face.body().face()->surface->kind() == kernel::SurfaceKind::Plane) {
      if (auto p = planar_face_polygon(face, edge_points)) out.push_back(std::move(*p));
      continue;
    }
    for (std::size_t t : triangles_of[i]) {
      const auto& tri = mesh.triangles[t];
      out.push_back(Polygon3{{{mesh.vertices[tri[0]], mesh.vertices[tri[1]], mesh.vertices[tri[2]],
                               mesh.vertices[tri[0]]}}});
    }
  }
  for (Polygon3& p : out) {
    for (auto& ring : p.rings) {
      for (Vec3& v : ring) v = map_point(options, v);
    }
  }
  return out;
}

kernel::BoundingBox map_box(const kernel::BoundingBox& box, const IndexOptions& options) {
  if (box.empty() || !options.to_srs) return box;
  kernel::BoundingBox out;
  for (int c = 0; c < 8; ++c) {
    const Vec3 corner((c & 1) ? box.max.x() : box.min.x(), (c & 2) ? box.max.y() : box.min.y(),
                      (c & 4) ? box.max.z() : box.min.z());
    out.add(options.to_srs(corner));
  }
  return out;
}

Failure check_objects(const std::vector<IndexObject>& objects, const IndexOptions& options) {
  if (!(options.chordal_tolerance > 0.0) || !(options.linear_tolerance > 0.0)) {
    return {ErrorCode::InputInvalid, "topology index: tolerances must be > 0"};
  }
  std::set<std::string> seen;
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const IndexObject& o = objects[i];
    const std::string where = "topology index: object " + std::to_string(i);
    if (o.id.empty()) return {ErrorCode::InputInvalid, where + " has an empty id"};
    if (!seen.insert(o.id).second) {
      return {ErrorCode::InputInvalid, where + ": duplicate id \"" + o.id + "\""};
    }
    const Shape& s = o.model.shape;
    if (s.is_null() || (s.kind() != ShapeKind::Solid &&
                        kernel::map_child_shapes(s, ShapeKind::Solid).size() == 0)) {
      return {ErrorCode::InputInvalid,
              where + " (\"" + o.id + "\") is not a solid or a compound of solids"};
    }
    if (!o.model.face_sources.empty() &&
        o.model.face_sources.size() != kernel::map_child_shapes(s, ShapeKind::Face).size()) {
      return {ErrorCode::InputInvalid,
              where + " (\"" + o.id + "\"): face_sources do not match the faces"};
    }
  }
  return {};
}

// A building's columns and its LoD1.2 and LoD1.3 blocks' boundaries: heights mapped to the SRS at
// the centre of the object's bounds (a translation in z for the SRSs of city models).
void add_building_columns(const IndexObject& object, const IndexOptions& options,
                          const kernel::BoundingBox& b, ObjectRecord& o,
                          std::vector<std::string>& warnings) {
  const bool building = is_building(object);
  if (!object.fuse_error.empty()) o.fuse_error = object.fuse_error;
  if (!object.lod12_error.empty()) o.lod12_error = object.lod12_error;
  if (const auto& h = object.heights) {
    const Vec3 c = b.empty() ? Vec3::Zero() : Vec3(0.5 * (b.min + b.max));
    auto z = [&](double height) { return map_point(options, Vec3(c.x(), c.y(), height)).z(); };
    o.h_ground = z(h->ground);
    o.h_roof_min = z(h->roof_min);
    o.h_roof_50p = z(h->roof_50p);
    o.h_roof_70p = z(h->roof_70p);
    o.h_roof_max = z(h->roof_max);
    o.roof_surfaces = static_cast<std::int64_t>(h->roof_faces);
  }
  if (!building) return;
  if (!object.footprint_id.empty()) o.footprint_id = object.footprint_id;
  o.outline = object.footprint_id.empty() ? "derived" : "footprint";
  if (!object.lod13_error.empty()) o.lod13_error = object.lod13_error;
  auto block_boundary = [&](const std::optional<kernel::CsgModel>& model, const char* lod,
                            std::vector<Polygon3>& out) {
    if (!model) return false;
    const Shape& block = model->shape;
    auto boundary = boundary_polygons(block, kernel::map_child_shapes(block, ShapeKind::Face),
                                      kernel::map_child_shapes(block, ShapeKind::Edge), options);
    if (!boundary.ok()) {
      warnings.push_back("object " + object.id + ": no " + lod +
                         " geometry: " + kernel::error_code_name(boundary.error().code) + ": " +
                         boundary.error().message);
      return false;
    }
    out = std::move(boundary).value();
    return !out.empty();
  };
  o.has_lod12 = block_boundary(object.lod12, "LoD1.2", o.lod12_boundary);
  o.has_lod13 = block_boundary(object.lod13, "LoD1.3", o.lod13_boundary);
  if (std::string lod = lod_reached(object); !lod.empty()) o.lod = std::move(lod);
}

template <typename T>
void append(std::vector<T>& to, std::vector<T>& from) {
  to.insert(to.end(), std::make_move_iterator(from.begin()), std::make_move_iterator(from.end()));
}

// Moves every row of `from` but the relations to the end of `to`.
void append_rows(IndexRows& to, IndexRows& from) {
  append(to.objects, from.objects);
  append(to.shapes, from.shapes);
  append(to.children, from.children);
  append(to.ancestors, from.ancestors);
  append(to.csg_nodes, from.csg_nodes);
  append(to.face_sources, from.face_sources);
  append(to.primitives, from.primitives);
}

}  // namespace

std::vector<RelationRecord> relation_records(const std::vector<IndexObject>& objects,
                                             const IndexOptions& options, IndexStats& stats) {
  std::vector<RelationRecord> out;
  std::vector<Shape> solids;
  for (const IndexObject& o : objects) solids.push_back(o.model.shape);
  // Pairs within a cell come classified from the cell's job when it says so; the others are
  // classified here. One list in (a, b) order either way.
  std::function<bool(std::size_t, std::size_t)> skip;
  if (options.cell_relations) {
    skip = [&objects](std::size_t i, std::size_t j) { return objects[i].cell == objects[j].cell; };
  }
  std::vector<ObjectRelation> related =
      compute_relations(solids, options.linear_tolerance, options.threads, skip);
  if (options.cell_relations) {
    for (const ObjectRelation& r : *options.cell_relations) {
      if (r.a < r.b && r.b < objects.size() && objects[r.a].cell == objects[r.b].cell) {
        related.push_back(r);
      }
    }
    std::stable_sort(related.begin(), related.end(),
                     [](const ObjectRelation& x, const ObjectRelation& y) {
                       return std::pair(x.a, x.b) < std::pair(y.a, y.b);
                     });
  }
  stats.relation_pairs = related;
  for (const ObjectRelation& r : related) {
    // Both directions, so that "relations of O" is one index lookup.
    for (int side = 0; side < 2; ++side) {
      RelationRecord rec;
      rec.object_id = objects[side == 0 ? r.a : r.b].id;
      rec.other_id = objects[side == 0 ? r.b : r.a].id;
      rec.relation = relation_kind_name(side == 0 ? r.kind : converse(r.kind));
      if (r.kind == RelationKind::Touches) rec.shared_area = r.shared_area;
      if (r.kind != RelationKind::Touches && r.kind != RelationKind::Unknown) {
        rec.common_volume = r.common_volume;
      }
      rec.reason = r.reason;
      out.push_back(std::move(rec));
    }
    if (r.kind == RelationKind::Unknown) ++stats.unknown_relations;
  }
  return out;
}

ObjectRows object_rows(const IndexObject& object, const IndexOptions& options) {
  ObjectRows out;
  IndexRows& rows = out.rows;
  std::int64_t next_id = 1;
  const Shape& root = object.model.shape;
  // Ids: every distinct sub-shape of each kind, kinds from compound to vertex, each in
  // map_child_shapes order. base[k] is the id of the first shape of kind k.
  std::array<kernel::ShapeIndex, kernel::kShapeKindCount> maps;
  std::array<std::int64_t, kernel::kShapeKindCount> base{};
  for (int k = 0; k < kernel::kShapeKindCount; ++k) {
    maps[k] = kernel::map_child_shapes(root, static_cast<ShapeKind>(k));
    base[k] = next_id;
    next_id += static_cast<std::int64_t>(maps[k].size());
  }
  auto id_of = [&](const Shape& s) -> std::int64_t {
    const int k = static_cast<int>(s.kind());
    const std::size_t i = maps[k].find(s);
    return i == kernel::ShapeIndex::npos ? 0 : base[k] + static_cast<std::int64_t>(i);
  };

  for (int k = 0; k < kernel::kShapeKindCount; ++k) {
    const auto kind = static_cast<ShapeKind>(k);
    for (std::size_t i = 0; i < maps[k].size(); ++i) {
      const Shape& s = maps[k][i];
      ShapeRecord r;
      r.id = base[k] + static_cast<std::int64_t>(i);
      r.object_id = object.id;
      r.kind = kernel::shape_kind_name(kind);
      r.kind_index = static_cast<std::int64_t>(i);
      r.key = object.id + "/" + r.kind + "/" + std::to_string(i);
      r.orientation = kernel::orientation_name(s.orientation());
      if (kind == ShapeKind::Vertex) {
        r.tolerance = kernel::tolerance(s);
        r.point = map_point(options, kernel::vertex_point(s));
      } else if (kind == ShapeKind::Edge) {
        r.tolerance = kernel::tolerance(s);
        const kernel::EdgeData* e = s.body().edge();
        r.geometry = e->degenerate() ? "degenerate" : curve_kind_name(e->curve->kind());
      } else if (kind == ShapeKind::Face) {
        r.tolerance = kernel::tolerance(s);
        r.geometry = surface_kind_name(s.body().face()->surface->kind());
      }
      rows.shapes.push_back(std::move(r));
      // Sub-shape references: the parent's body children, with their own location and
      // orientation; the child id is the child as seen through this (located) parent.
      const auto& refs = s.body().children();
      for (std::size_t c = 0; c < refs.size(); ++c) {
        ChildRecord ref;
        ref.parent_id = base[k] + static_cast<std::int64_t>(i);
        ref.child_id = id_of(s.child(c));
        ref.position = static_cast<std::int64_t>(c);
        ref.orientation = kernel::orientation_name(refs[c].orientation());
        if (!refs[c].location().is_identity())
          ref.location = matrix_json(refs[c].location()).dump();
        rows.children.push_back(std::move(ref));
      }
    }
  }

  for (const auto& [child_kind, ancestor_kind] : kAncestorPairs) {
    const kernel::AncestorIndex index(root, child_kind, ancestor_kind);
    for (std::size_t i = 0; i < index.size(); ++i) {
      const std::int64_t key_id = id_of(index.keys()[i]);
      const auto& ancestors = index.ancestors(i);
      for (std::size_t a = 0; a < ancestors.size(); ++a) {
        rows.ancestors.push_back({key_id, kernel::shape_kind_name(ancestor_kind),
                                  id_of(ancestors[a]), static_cast<std::int64_t>(a)});
      }
    }
  }

  const auto& nodes = object.model.nodes;
  std::vector<std::optional<std::int64_t>> parent(nodes.size());
  for (std::size_t n = 0; n < nodes.size(); ++n) {
    for (int c : nodes[n].children) {
      if (c >= 0 && static_cast<std::size_t>(c) < nodes.size())
        parent[c] = static_cast<std::int64_t>(n);
    }
  }
  for (std::size_t n = 0; n < nodes.size(); ++n) {
    CsgNodeRecord r;
    r.object_id = object.id;
    r.node = static_cast<std::int64_t>(n);
    r.kind = kernel::csg_node_kind_name(nodes[n].kind);
    r.label = nodes[n].label;
    r.parent = parent[n];
    r.children = Json(nodes[n].children).dump();
    if (nodes[n].kind == kernel::CsgNodeKind::Primitive) {
      r.primitive_type = kernel::primitive_type_name(nodes[n].primitive.type);
      r.parameters = primitive_parameters(nodes[n].primitive);
    }
    rows.csg_nodes.push_back(std::move(r));
  }
  const std::int64_t face_base = base[static_cast<int>(ShapeKind::Face)];
  for (std::size_t f = 0; f < object.model.face_sources.size(); ++f) {
    for (const kernel::FaceSource& s : object.model.face_sources[f]) {
      rows.face_sources.push_back(
          {face_base + static_cast<std::int64_t>(f), object.id, s.node, s.face});
    }
  }
  std::set<std::string> types;
  for (const PrimitiveInfo& p : object.primitives) {
    PrimitiveRecord r;
    r.object_id = object.id;
    if (p.node >= 0) r.node = p.node;
    r.primitive_id = p.id;
    r.type = p.type;
    r.inliers = p.inliers;
    r.fit_rms = p.rms;
    r.fit_coverage = p.coverage;
    rows.primitives.push_back(std::move(r));
    types.insert(p.type);
  }

  ObjectRecord o;
  o.object_id = object.id;
  o.cell = object.cell;
  o.shape_id = base[static_cast<int>(root.kind())];
  o.primitive_count = static_cast<std::int64_t>(object.primitives.size());
  for (const std::string& t : types)
    o.primitive_types += (o.primitive_types.empty() ? "" : ",") + t;
  const kernel::MassProperties mp = kernel::mass_properties(root);
  o.volume = mp.volume;
  o.area = mp.area;
  o.bounds = map_box(mp.bounds, options);
  o.valid = model_valid(object);
  const FitSummary fit = fit_summary(object.primitives);
  o.fit_rms = fit.rms;
  o.fit_coverage = fit.coverage;
  o.fit_within_2sigma = fit.within_2sigma;
  if (const auto& m = object.model_fit) {
    o.model_rmse = m->rmse;
    o.model_points = m->points;
    o.model_within_2sigma = m->within_2sigma;
  }
  auto boundary = boundary_polygons(root, maps[static_cast<int>(ShapeKind::Face)],
                                    maps[static_cast<int>(ShapeKind::Edge)], options,
                                    shared_mesh(object, options.chordal_tolerance));
  if (boundary.ok()) {
    o.boundary = std::move(boundary).value();
    o.has_geometry = !o.boundary.empty();
  } else {
    out.warnings.push_back("object " + object.id + ": no boundary geometry: " +
                           kernel::error_code_name(boundary.error().code) + ": " +
                           boundary.error().message);
  }
  add_building_columns(object, options, mp.bounds, o, out.warnings);
  rows.objects.push_back(std::move(o));
  out.ids = next_id - 1;
  return out;
}

void offset_ids(IndexRows& rows, std::int64_t offset) {
  auto move = [offset](std::int64_t& id) {
    if (id != 0) id += offset;
  };
  for (ShapeRecord& r : rows.shapes) move(r.id);
  for (ChildRecord& r : rows.children) {
    move(r.parent_id);
    move(r.child_id);
  }
  for (AncestorRecord& r : rows.ancestors) {
    move(r.shape_id);
    move(r.ancestor_id);
  }
  for (FaceSourceRecord& r : rows.face_sources) move(r.face_id);
  for (ObjectRecord& r : rows.objects) move(r.shape_id);
}

Result<IndexRows> build_index_rows(const std::vector<IndexObject>& objects,
                                   const IndexOptions& options, IndexStats& stats) {
  if (Failure st = check_objects(objects, options); !st.ok()) return st;
  IndexRows rows;
  std::int64_t next_id = 1;
  for (const IndexObject& object : objects) {
    ObjectRows part = object_rows(object, options);
    offset_ids(part.rows, next_id - 1);
    next_id += part.ids;
    append_rows(rows, part.rows);
    for (std::string& w : part.warnings) stats.warnings.push_back(std::move(w));
  }

  if (options.relations) rows.relations = relation_records(objects, options, stats);
  return rows;
}

}  // namespace detail

bool model_valid(const IndexObject& object) {
  return object.valid ? *object.valid : kernel::check_shape(object.model.shape).valid();
}

std::shared_ptr<const kernel::Mesh> shared_mesh(const IndexObject& object,
                                                double chordal_tolerance) {
  return object.mesh && object.mesh_tolerance == chordal_tolerance ? object.mesh : nullptr;
}

kernel::Result<std::shared_ptr<const kernel::Mesh>> model_mesh(const IndexObject& object,
                                                               double chordal_tolerance) {
  return kernel::shared_tessellation(object.model.shape, chordal_tolerance,
                                     shared_mesh(object, chordal_tolerance));
}

// Weights: inlier counts when any fitted primitive has them, else equal.
FitSummary fit_summary(const std::vector<PrimitiveInfo>& primitives) {
  double weight = 0.0, squares = 0.0, coverage = 0.0, near_weight = 0.0, near = 0.0;
  bool any = false;
  bool counted = std::any_of(primitives.begin(), primitives.end(), [](const PrimitiveInfo& p) {
    return p.rms && p.inliers && *p.inliers > 0;
  });
  for (const PrimitiveInfo& p : primitives) {
    if (!p.rms) continue;
    const double w = counted ? static_cast<double>(p.inliers.value_or(0)) : 1.0;
    any = true;
    weight += w;
    squares += w * *p.rms * *p.rms;
    coverage += w * p.coverage.value_or(0.0);
    if (p.within_2sigma) {
      near_weight += w;
      near += w * *p.within_2sigma;
    }
  }
  FitSummary out;
  if (!any || weight <= 0.0) return out;
  out.rms = std::sqrt(squares / weight);
  out.coverage = coverage / weight;
  if (near_weight > 0.0) out.within_2sigma = near / near_weight;
  return out;
}

namespace {

// The GeoPackage `write` makes at a temporary beside `path` (same file system, so the rename is
// atomic), renamed over `path` once closed and flushed; the temporary removed on failure.
Failure write_atomically(const std::filesystem::path& path,
                         const std::function<Failure(const std::string&)>& write) {
  std::error_code ec;
  const std::filesystem::path dir = path.has_parent_path() ? path.parent_path() : ".";
  std::filesystem::create_directories(dir, ec);
  if (ec) return {ErrorCode::Io, "cannot create directory " + dir.string() + ": " + ec.message()};
  const std::filesystem::path tmp = temp_path_beside(path, "tmp");
  Failure written;
  try {
    written = write(tmp.string());
  } catch (...) {
    std::filesystem::remove(tmp, ec);  // nothing half-written is left beside `path`
    throw;
  }
  if (!written.ok()) {
    std::filesystem::remove(tmp, ec);
    return written;
  }
  // The database is closed: commit flushes its bytes before the rename makes them visible.
  return commit_temp_file(tmp, path);
}

}  // namespace

Failure write_topology_index(const std::filesystem::path& path,
                             const std::vector<IndexObject>& objects, const IndexOptions& options,
                             IndexStats* stats) {
  IndexStats local;
  IndexStats& s = stats != nullptr ? *stats : local;
  s = IndexStats{};
  if (Failure st = detail::check_objects(objects, options); !st.ok()) return st;
  std::vector<detail::RelationRecord> relations;
  if (options.relations) relations = detail::relation_records(objects, options, s);
  // Streamed: each object's rows built on the options' threads, at most a few objects ahead
  // of the writer, and written in object order with their ids moved after the objects
  // before (the same file as build_index_rows + write_gpkg, row for row).
  if (Failure f = write_atomically(
          path,
          [&](const std::string& tmp) {
            detail::GpkgRowWriter writer;
            if (Failure opened = writer.open(tmp, options); !opened.ok()) {
              writer.finish({});
              return opened;
            }
            // The options' threads (0: one per core); the caller's own arena when it has
            // that many already (a cell's exports run in the run.threads arena).
            const int wanted =
                options.threads > 0 ? options.threads : tbb::info::default_concurrency();
            const auto threads = static_cast<std::size_t>(wanted);
            std::optional<tbb::task_arena> arena;
            if (tbb::this_task_arena::max_concurrency() != wanted) arena.emplace(wanted);
            std::size_t next = 0;
            std::int64_t next_id = 1;
            std::atomic<bool> failed{false};
            auto stream = [&] {
              tbb::parallel_pipeline(
                  2 * threads,
                  tbb::make_filter<void, std::size_t>(tbb::filter_mode::serial_in_order,
                                                      [&](tbb::flow_control& fc) -> std::size_t {
                                                        if (next == objects.size() ||
                                                            failed.load()) {
                                                          fc.stop();
                                                          return 0;
                                                        }
                                                        return next++;
                                                      }) &
                      tbb::make_filter<std::size_t, std::shared_ptr<detail::ObjectRows>>(
                          tbb::filter_mode::parallel,
                          [&](std::size_t i) {
                            return std::make_shared<detail::ObjectRows>(
                                detail::object_rows(objects[i], options));
                          }) &
                      tbb::make_filter<std::shared_ptr<detail::ObjectRows>, void>(
                          tbb::filter_mode::serial_in_order,
                          [&](const std::shared_ptr<detail::ObjectRows>& part) {
                            detail::offset_ids(part->rows, next_id - 1);
                            next_id += part->ids;
                            for (std::string& w : part->warnings) {
                              s.warnings.push_back(std::move(w));
                            }
                            const detail::IndexRows& r = part->rows;
                            s.objects += r.objects.size();
                            s.shapes += r.shapes.size();
                            s.children += r.children.size();
                            s.ancestors += r.ancestors.size();
                            s.csg_nodes += r.csg_nodes.size();
                            s.primitives += r.primitives.size();
                            if (!writer.add(r).ok()) failed = true;
                          }));
            };
            if (arena) {
              arena->execute(stream);
            } else {
              stream();
            }
            return writer.finish(relations);
          });
      !f.ok()) {
    return f;
  }
  s.relations = relations.size() / 2;  // rows come in both directions
  std::error_code ec;
  s.bytes = std::filesystem::file_size(path, ec);
  return {};
}

Failure merge_topology_indexes(const std::filesystem::path& path,
                               const std::vector<IndexPart>& parts,
                               const std::vector<IndexObject>& objects, const IndexOptions& options,
                               IndexStats* stats) {
  IndexStats local;
  IndexStats& s = stats != nullptr ? *stats : local;
  s = IndexStats{};
  std::vector<detail::RelationRecord> relations;
  if (options.relations) relations = detail::relation_records(objects, options, s);
  std::vector<detail::GpkgPart> gpkg_parts;
  for (const IndexPart& part : parts) gpkg_parts.push_back({part.path.string(), part.offset});
  std::vector<std::string> ids;
  for (const IndexObject& o : objects) ids.push_back(o.id);
  detail::GpkgCounts counts;
  if (Failure f = write_atomically(path,
                                   [&](const std::string& tmp) {
                                     return detail::merge_gpkgs(tmp, gpkg_parts, ids, relations,
                                                                options, counts);
                                   });
      !f.ok()) {
    return f;
  }
  s.objects = counts.objects;
  s.shapes = counts.shapes;
  s.children = counts.children;
  s.ancestors = counts.ancestors;
  s.relations = relations.size() / 2;  // rows come in both directions
  s.csg_nodes = counts.csg_nodes;
  s.primitives = counts.primitives;
  std::error_code ec;
  s.bytes = std::filesystem::file_size(path, ec);
  return {};
}

}  // namespace csgtile::worker
