// The Boolean engine: edges and faces split along the sections; pieces classified.

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
#include "boolean/face_split.h"
#include "boolean/model.h"
#include "boolean/tolerance.h"
#include "boolean/uv_geometry.h"
#include "csgtile/kernel/check.h"
#include "csgtile/kernel/explorer.h"
#include "mesh/polygon_triangulation.h"
#include "predicates/predicates.h"

namespace csgtile::kernel::detail {

void BooleanEngine::split_crossing_sections() {
  for (std::size_t f = 0; f < model_.faces.size(); ++f) {
    const std::vector<BUse> extra = model_.faces[f].extra;
    const double tol = uv_margin(f) * kCrossingUvSlacks;
    // Pairs whose boxes stay apart cannot cross (crossing_boxes_apart): skipped unsampled.
    std::vector<std::vector<Vec2>> points;  // each sampled once
    std::vector<CrossingBox> boxes;
    for (const BUse& u : extra) {
      const BEdge& e = model_.edges[static_cast<std::size_t>(u.edge)];
      points.push_back(e.degenerate() ? std::vector<Vec2>{}
                                      : crossing_points(*u.pcurve, e.t0, e.t1));
      boxes.push_back(e.degenerate() ? CrossingBox{}
                                     : crossing_box(*u.pcurve, e.t0, e.t1, points.back()));
    }
    for (std::size_t i = 0; i < extra.size(); ++i) {
      for (std::size_t j = i + 1; j < extra.size(); ++j) {
        const BEdge& a = model_.edges[static_cast<std::size_t>(extra[i].edge)];
        const BEdge& b = model_.edges[static_cast<std::size_t>(extra[j].edge)];
        if (a.degenerate() || b.degenerate()) continue;
        if (crossing_boxes_apart(boxes[i], boxes[j], Vec2::Zero(), tol)) continue;
        for (const Crossing& c : intersect_pcurves(*extra[i].pcurve, a.t0, a.t1, points[i],
                                                   *extra[j].pcurve, b.t0, b.t1, tol)) {
          const double sa = param_slack(a.t1 - a.t0), sb = param_slack(b.t1 - b.t0);
          const bool inner_a = c.t > a.t0 + sa && c.t < a.t1 - sa;
          const bool inner_b = c.s > b.t0 + sb && c.s < b.t1 - sb;
          if (!inner_a && !inner_b) continue;
          const int v = model_.vertex_at(a.curve->point(c.t));
          if (inner_a && v != a.v0 && v != a.v1)
            model_.edges[static_cast<std::size_t>(extra[i].edge)].splits.emplace_back(c.t, v);
          if (inner_b && v != b.v0 && v != b.v1)
            model_.edges[static_cast<std::size_t>(extra[j].edge)].splits.emplace_back(c.s, v);
        }
      }
    }
  }
}

void BooleanEngine::split_edges() {
  std::map<int, std::vector<int>> chains;  // edge -> sub-edges in parameter order
  const std::size_t count = model_.edges.size();
  for (std::size_t i = 0; i < count; ++i) {
    if (model_.edges[i].splits.empty()) continue;
    // A copy: adding sub-edges below reallocates the edge table.
    BEdge e = model_.edges[i];
    std::sort(e.splits.begin(), e.splits.end());
    std::vector<std::pair<double, int>> cuts{{e.t0, e.v0}};
    const double eps = param_slack(e.t1 - e.t0);
    for (const auto& [t, v] : e.splits) {
      if (t <= e.t0 + eps || t >= e.t1 - eps) continue;
      if (e.degenerate() ? t - cuts.back().first <= eps : v == cuts.back().second) continue;
      cuts.emplace_back(t, v);
    }
    cuts.emplace_back(e.t1, e.v1);
    if (cuts.size() <= 2) continue;
    std::vector<int> chain;
    for (std::size_t k = 0; k + 1 < cuts.size(); ++k) {
      if (!e.degenerate() && cuts[k].second == cuts[k + 1].second) continue;
      BEdge sub;
      sub.curve = e.curve;
      sub.t0 = cuts[k].first;
      sub.t1 = cuts[k + 1].first;
      sub.v0 = cuts[k].second;
      sub.v1 = cuts[k + 1].second;
      sub.tolerance = e.tolerance;
      sub.seam = e.seam;
      chain.push_back(model_.add_edge(std::move(sub)));
    }
    chains[static_cast<int>(i)] = chain;
  }
  auto expand = [&](const BUse& u, std::vector<BUse>& out) {
    auto it = chains.find(u.edge);
    if (it == chains.end()) {
      out.push_back(u);
      return;
    }
    std::vector<int> chain = it->second;
    if (!u.forward) std::reverse(chain.begin(), chain.end());
    for (int sub : chain) out.push_back({sub, u.forward, u.pcurve});
  };
  for (BFace& f : model_.faces) {
    for (BLoop& loop : f.loops) {
      BLoop next;
      for (const BUse& u : loop) expand(u, next);
      loop = std::move(next);
    }
    std::vector<BUse> extra;
    for (const BUse& u : f.extra) expand(u, extra);
    f.extra = std::move(extra);
  }
  // Partial pieces of existing edges that lie in a coincident face: now whole sub-edges.
  for (const PendingPartial& p : pending_partials_) {
    auto it = chains.find(p.edge);
    if (it == chains.end()) continue;
    for (int sub : it->second) {
      const BEdge& s = model_.edges[static_cast<std::size_t>(sub)];
      const double mid = 0.5 * (s.t0 + s.t1);
      if (mid > p.t0 && mid < p.t1) add_extra(p.face, sub, p.pcurve);
    }
  }
}

Status BooleanEngine::split_faces(std::vector<Piece>& pieces) {
  for (std::size_t f = 0; f < model_.faces.size(); ++f) {
    if (auto s = interrupted("splitting faces"); !s.ok()) return s;
    auto regions = split_face(model_, model_.faces[f]);
    if (!regions.ok()) {
      // Name the face: which argument, which of its faces, on what surface.
      const BFace& face = model_.faces[f];
      return Error{regions.error().code,
                   regions.error().message + " in face " + std::to_string(face.source) + " (" +
                       surface_name(face.surface->kind()) + ") of the " +
                       (face.operand == 0 ? "first" : "second") + " argument"};
    }
    for (Region& r : regions.value()) pieces.push_back({static_cast<int>(f), std::move(r)});
  }
  return {};
}

std::vector<Vec3> BooleanEngine::interior_points(const Piece& piece, std::size_t count) {
  const BFace& face = model_.faces[static_cast<std::size_t>(piece.face)];
  BFace outline;
  outline.surface = face.surface;
  outline.loops = piece.region.loops;
  const FacePolygon exact = face_polygon(model_, outline);
  const double margin =
      uv_slack(std::max(exact.max.x() - exact.min.x(), exact.max.y() - exact.min.y())) *
      kInsideUvSlacks;
  std::vector<Vec2> found, unchecked;  // unchecked: the first outline's points (if none pass)
  for (int samples = kInteriorSamples; found.size() < count && samples <= kInteriorSamplesMax;
       samples *= kInteriorRefine) {
    std::vector<std::vector<Vec2>> loops;
    for (const BLoop& loop : piece.region.loops) {
      std::vector<Vec2> pts;
      for (const BUse& u : loop) {
        auto s = sample_use(model_, u, samples);
        pts.insert(pts.end(), s.begin(), s.end() - 1);
      }
      loops.push_back(std::move(pts));
    }
    const PolygonTriangulation tri = triangulate_polygon(loops);
    std::vector<Vec2> flat;
    for (const auto& l : loops) flat.insert(flat.end(), l.begin(), l.end());
    std::vector<std::pair<double, Vec2>> by_area;
    for (const auto& t : tri.triangles) {
      const Vec2 &p = flat[t[0]], &q = flat[t[1]], &r = flat[t[2]];
      const double area = std::abs((q - p).x() * (r - p).y() - (q - p).y() * (r - p).x());
      if (area > 0) by_area.emplace_back(area, 0.29 * p + 0.33 * q + 0.38 * r);
    }
    std::stable_sort(by_area.begin(), by_area.end(),
                     [](const auto& x, const auto& y) { return x.first > y.first; });
    found.clear();
    for (std::size_t i = 0; i < by_area.size() && found.size() < count; ++i) {
      if (samples == kInteriorSamples && unchecked.size() < count)
        unchecked.push_back(by_area[i].second);
      if (exact.inside(by_area[i].second, margin).value_or(false))
        found.push_back(by_area[i].second);
    }
  }
  if (found.empty()) found = unchecked;
  std::vector<Vec3> out;
  for (const Vec2& uv : found) out.push_back(face.surface->point(uv.x(), uv.y()));
  return out;
}

Vec3 BooleanEngine::outward_normal(const Piece& piece, const Vec3& p) {
  const BFace& f = model_.faces[static_cast<std::size_t>(piece.face)];
  const Vec2 uv = f.surface->closest_parameters(p);
  const Vec3 n = f.surface->normal(uv.x(), uv.y());
  return f.reversed ? Vec3(-n) : n;
}

Status BooleanEngine::classify(std::vector<Piece>& pieces) {
  auto ca = SolidClassifier::create(a_, options_.tolerance);
  auto cb = SolidClassifier::create(b_, options_.tolerance);
  if (!ca.ok()) return ca.error();
  if (!cb.ok()) return cb.error();
  for (Piece& piece : pieces) {
    if (auto s = interrupted("classifying face pieces"); !s.ok()) return s;
    const bool from_a = static_cast<std::size_t>(piece.face) < first_b_face_;
    const SolidClassifier& other = from_a ? cb.value() : ca.value();
    const std::vector<Vec3> candidates = interior_points(piece, 3);
    if (candidates.empty()) continue;  // a degenerate sliver bounds nothing
    // The first point off the other solid's boundary decides; a piece whose points are all
    // on it lies on one of its faces.
    std::optional<Vec3> p;
    Containment c = Containment::OnBoundary;
    for (const Vec3& q : candidates) {
      c = other.classify(q);
      p = q;
      if (c != Containment::OnBoundary) break;
    }
    if (c == Containment::OnBoundary) p = candidates.front();
    bool in = c == Containment::Inside, out = c == Containment::Outside;
    bool on_same = false, on_opposite = false;
    if (c == Containment::OnBoundary) {
      auto n = other.boundary_normal(*p);
      if (!n) return Status(ErrorCode::InvalidShape, "a boundary point has no normal");
      (predicates::dot_sign(outward_normal(piece, *p), *n) > 0 ? on_same : on_opposite) = true;
    }
    switch (op_) {
      case BooleanOp::Fuse:
        piece.keep = out || (on_same && from_a);
        break;
      case BooleanOp::Common:
        piece.keep = in || (on_same && from_a);
        break;
      case BooleanOp::Cut:
        piece.keep = from_a ? (out || on_opposite) : in;
        piece.flip = !from_a;
        break;
    }
  }
  return {};
}

}  // namespace csgtile::kernel::detail
