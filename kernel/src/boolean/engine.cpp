// The Boolean engine's run: importing the operands, shared edges, touching vertices.

#include "boolean/engine.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <numbers>
#include <numeric>
#include <set>
#include <string>
#include "boolean/classifier.h"
#include "boolean/model.h"
#include "boolean/pcurve_fit.h"
#include "boolean/tolerance.h"
#include "boolean/uv_geometry.h"
#include "csgtile/kernel/explorer.h"

namespace csgtile::kernel::detail {

const char* surface_name(SurfaceKind k) {
  static const char* const kNames[] = {"plane", "cylinder",  "cone",      "sphere",
                                       "torus", "extrusion", "revolution"};
  return kNames[static_cast<int>(k)];
}

// The pcurve of `edge` on `surface`, shifted by whole periods so that at `point` it lands
// where `old_uv` is (a seam is used at u = 0 and at u = 2π: the side must be kept).
Curve2dPtr aligned_fit(const BEdge& edge, const Surface& surface, const Vec3& point,
                       const Vec2& old_uv, double tolerance) {
  auto pc = fit_pcurve(*edge.curve, edge.t0, edge.t1, surface, tolerance);
  if (!pc) return nullptr;
  const Vec2 new_uv = pc->point(edge.curve->closest_parameter(point, edge.t0, edge.t1));
  Vec2 offset = Vec2::Zero();
  if (surface.u_period() > 0)
    offset.x() = surface.u_period() * std::round((old_uv.x() - new_uv.x()) / surface.u_period());
  if (surface.v_period() > 0)
    offset.y() = surface.v_period() * std::round((old_uv.y() - new_uv.y()) / surface.v_period());
  return shift_pcurve(pc, offset);
}

Result<Shape> BooleanEngine::run() {
  if (auto s = import_operand(model_, a_, 0); !s.ok()) return s.error();
  first_b_face_ = model_.faces.size();
  if (auto s = import_operand(model_, b_, 1); !s.ok()) return s.error();
  reframe_spheres();
  polygons_.resize(model_.faces.size());
  for (std::size_t i = 0; i < model_.faces.size(); ++i)
    polygons_[i] = face_polygon(model_, model_.faces[i]);
  unify_shared_edges();
  split_at_touching_vertices();
  if (auto s = intersect_faces(); !s.ok()) return s.error();
  split_crossing_sections();
  split_edges();
  unify_shared_edges();  // pieces of the two operands' edges may coincide only after splitting
  std::vector<Piece> pieces;
  if (auto s = split_faces(pieces); !s.ok()) return s.error();
  if (auto s = classify(pieces); !s.ok()) return s.error();
  if (auto s = interrupted("assembling the result"); !s.ok()) return s.error();
  return build(pieces);
}

Result<Interference> BooleanEngine::interference() {
  if (auto s = import_operand(model_, a_, 0); !s.ok()) return s.error();
  first_b_face_ = model_.faces.size();
  if (auto s = import_operand(model_, b_, 1); !s.ok()) return s.error();
  if (first_b_face_ == 0 || first_b_face_ == model_.faces.size()) return Interference::Disjoint;
  // Vertices within tolerance of each other are one model vertex: one used by both
  // operands is a contact point.
  const std::vector<int> operand_of_vertex = operand_of_vertices();
  if (std::find(operand_of_vertex.begin(), operand_of_vertex.end(), 2) != operand_of_vertex.end()) {
    return Interference::BoundariesMeet;
  }
  reframe_spheres();
  polygons_.resize(model_.faces.size());
  for (std::size_t i = 0; i < model_.faces.size(); ++i)
    polygons_[i] = face_polygon(model_, model_.faces[i]);
  split_at_touching_vertices();
  if (auto s = intersect_faces(); !s.ok()) return s.error();
  for (const BFace& f : model_.faces) {
    if (!f.extra.empty()) return Interference::BoundariesMeet;
  }
  // No boundary contact: nested or apart. One boundary point of each decides.
  for (const auto& [inner, outer] : {std::pair{&a_, &b_}, std::pair{&b_, &a_}}) {
    Explorer vertices(*inner, ShapeKind::Vertex);
    if (vertices.begin() == vertices.end()) continue;
    auto classifier = SolidClassifier::create(*outer, options_.tolerance);
    if (!classifier.ok()) return classifier.error();
    if (classifier->classify(vertex_point(*vertices.begin())) != Containment::Outside)
      return Interference::Nested;
  }
  return Interference::Disjoint;
}

Status BooleanEngine::interrupted(const char* stage) const {
  if (!options_.interrupt.fired()) return {};
  return options_.interrupt.error(std::string("while ") + stage + " (boolean " +
                                  boolean_op_name(op_) + ")");
}

void BooleanEngine::unify_shared_edges() {
  std::map<std::pair<int, int>, std::vector<int>> by_ends;
  for (std::size_t i = 0; i < model_.edges.size(); ++i) {
    const BEdge& e = model_.edges[i];
    if (e.degenerate()) continue;
    by_ends[{std::min(e.v0, e.v1), std::max(e.v0, e.v1)}].push_back(static_cast<int>(i));
  }
  std::map<int, int> replace;
  for (auto& [ends, list] : by_ends) {
    for (std::size_t i = 0; i < list.size(); ++i) {
      for (std::size_t j = 0; j < i; ++j) {
        if (replace.count(list[j])) continue;
        const BEdge& x = model_.edges[static_cast<std::size_t>(list[i])];
        const BEdge& y = model_.edges[static_cast<std::size_t>(list[j])];
        const Vec3 mx = x.curve->point(0.5 * (x.t0 + x.t1));
        const double t = y.curve->closest_parameter(mx, y.t0, y.t1);
        if ((y.curve->point(t) - mx).norm() <= options_.tolerance && ends.first != ends.second) {
          replace[list[i]] = list[j];
          break;
        }
      }
    }
  }
  if (replace.empty()) return;
  for (BFace& f : model_.faces) {
    std::vector<BLoop*> lists;
    for (BLoop& loop : f.loops) lists.push_back(&loop);
    lists.push_back(&f.extra);
    for (BLoop* list : lists) {
      for (BUse& u : *list) {
        auto it = replace.find(u.edge);
        if (it == replace.end()) continue;
        const BEdge& from = model_.edges[static_cast<std::size_t>(u.edge)];
        const BEdge& to = model_.edges[static_cast<std::size_t>(it->second)];
        const bool same_direction = from.v0 == to.v0;
        const double mid = 0.5 * (from.t0 + from.t1);
        auto pc = aligned_fit(to, *f.surface, from.curve->point(mid), u.pcurve->point(mid),
                              fit_tolerance(options_.tolerance));
        if (!pc) continue;  // keep the separate edge (the checker speaks if it matters)
        u.edge = it->second;
        u.forward = same_direction ? u.forward : !u.forward;
        u.pcurve = pc;
      }
    }
    // A section edge that turned out to be a boundary edge (or a repeat) is not extra.
    std::set<int> seen;
    for (const BLoop& loop : f.loops) {
      for (const BUse& u : loop) seen.insert(u.edge);
    }
    std::vector<BUse> extra;
    for (const BUse& u : f.extra) {
      if (seen.insert(u.edge).second) extra.push_back(u);
    }
    f.extra = std::move(extra);
  }
}

std::vector<int> BooleanEngine::operand_of_vertices() const {
  std::vector<int> operand(model_.vertices.size(), -1);
  for (const BFace& f : model_.faces) {
    for (const BLoop& loop : f.loops) {
      for (const BUse& u : loop) {
        const BEdge& e = model_.edges[static_cast<std::size_t>(u.edge)];
        for (int v : {e.v0, e.v1}) {
          int& o = operand[static_cast<std::size_t>(v)];
          o = (o == -1 || o == f.operand) ? f.operand : 2;
        }
      }
    }
  }
  return operand;
}

void BooleanEngine::split_at_touching_vertices() {
  const double tol = options_.tolerance;
  const std::vector<int> operand_of_vertex = operand_of_vertices();
  std::vector<int> operand_of_edge(model_.edges.size(), -1);
  for (const BFace& f : model_.faces) {
    for (const BLoop& loop : f.loops) {
      for (const BUse& u : loop) operand_of_edge[static_cast<std::size_t>(u.edge)] = f.operand;
    }
  }
  for (std::size_t ei = 0; ei < model_.edges.size(); ++ei) {
    BEdge& e = model_.edges[ei];
    if (e.degenerate() || operand_of_edge[ei] < 0) continue;
    BoundingBox box = e.curve->bounds(e.t0, e.t1);
    box.enlarge(tol);
    for (std::size_t v = 0; v < model_.vertices.size(); ++v) {
      const int o = operand_of_vertex[v];
      if (o == operand_of_edge[ei] || o < 0 || static_cast<int>(v) == e.v0 ||
          static_cast<int>(v) == e.v1)
        continue;
      const Vec3& p = model_.vertices[v].point;
      if (!box.contains(p)) continue;
      const double t = e.curve->closest_parameter(p, e.t0, e.t1);
      if ((e.curve->point(t) - p).norm() > tol) continue;
      const double span = param_slack(e.t1 - e.t0);
      if (t <= e.t0 + span || t >= e.t1 - span) continue;
      e.splits.emplace_back(t, static_cast<int>(v));
    }
  }
}

double BooleanEngine::uv_margin(std::size_t face) const {
  const FacePolygon& p = polygons_[face];
  return uv_slack(std::max(p.max.x() - p.min.x(), p.max.y() - p.min.y()));
}

}  // namespace csgtile::kernel::detail
