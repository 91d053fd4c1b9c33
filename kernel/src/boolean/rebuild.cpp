// The Boolean engine: the kept pieces rebuilt into faces, shells and solids.

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
#include "boolean/pcurve_fit.h"
#include "boolean/tolerance.h"
#include "check/check_internal.h"
#include "csgtile/kernel/check.h"
#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/mass_properties.h"
#include "mass/mass_internal.h"
#include "predicates/predicates.h"

namespace csgtile::kernel::detail {

namespace {

// A face of the result before it becomes a Shape.
struct RFace {
  int source_face;  // model face it comes from
  SurfacePtr surface;
  bool reversed;
  std::vector<BLoop> loops;
  bool alive = true;
  std::vector<FaceOrigin> origins;  // the input faces this face comes from (merges add)
};

// Joins the origins of a merged face into the surviving one, sorted and unique.
void absorb_origins(RFace& into, RFace& from) {
  into.origins.insert(into.origins.end(), from.origins.begin(), from.origins.end());
  from.origins.clear();
  std::sort(into.origins.begin(), into.origins.end());
  into.origins.erase(std::unique(into.origins.begin(), into.origins.end()), into.origins.end());
}

// Positions of a use of `edge` in a face: (loop, index).
std::optional<std::pair<std::size_t, std::size_t>> find_use(const RFace& f, int edge,
                                                            bool forward) {
  for (std::size_t l = 0; l < f.loops.size(); ++l) {
    for (std::size_t i = 0; i < f.loops[l].size(); ++i) {
      if (f.loops[l][i].edge == edge && f.loops[l][i].forward == forward)
        return std::make_pair(l, i);
    }
  }
  return std::nullopt;
}

// Loop rotated so that position i comes last.
BLoop rotated_to_end(const BLoop& loop, std::size_t i) {
  BLoop out;
  for (std::size_t k = 1; k <= loop.size(); ++k) out.push_back(loop[(i + k) % loop.size()]);
  return out;
}

// Joins two loops (or the two sides of one) along an edge used in opposite directions at
// (la, ia) and (lb, ib) of face f; the edge disappears. Loops that close on themselves
// split off; empty ones vanish.
void splice(RFace& f, std::size_t la, std::size_t ia, std::size_t lb, std::size_t ib) {
  if (la == lb) {
    BLoop loop = rotated_to_end(f.loops[la], ia);  // ... , e
    // Now find the opposite use in the rotated loop.
    std::size_t j = 0;
    while (j < loop.size() &&
           !(loop[j].edge == f.loops[la][ia].edge && loop[j].forward != f.loops[la][ia].forward))
      ++j;
    BLoop first(loop.begin(), loop.begin() + static_cast<std::ptrdiff_t>(j));
    BLoop second(loop.begin() + static_cast<std::ptrdiff_t>(j) + 1, loop.end() - 1);
    f.loops.erase(f.loops.begin() + static_cast<std::ptrdiff_t>(la));
    if (!first.empty()) f.loops.push_back(std::move(first));
    if (!second.empty()) f.loops.push_back(std::move(second));
    return;
  }
  BLoop a = rotated_to_end(f.loops[la], ia);
  BLoop b = rotated_to_end(f.loops[lb], ib);
  a.pop_back();
  b.pop_back();
  a.insert(a.end(), b.begin(), b.end());
  const std::size_t hi = std::max(la, lb), lo = std::min(la, lb);
  f.loops.erase(f.loops.begin() + static_cast<std::ptrdiff_t>(hi));
  f.loops.erase(f.loops.begin() + static_cast<std::ptrdiff_t>(lo));
  if (!a.empty()) f.loops.push_back(std::move(a));
}

// One plane with one outward side: the sides agree exactly (sign of nx·ny), the planes
// coincide within the tolerance model (parallel over its size, offset negligible).
bool same_plane(const Surface& x, bool xr, const Surface& y, bool yr, const ToleranceModel& d) {
  if (x.kind() != SurfaceKind::Plane || y.kind() != SurfaceKind::Plane) return false;
  const Frame& fx = static_cast<const PlaneSurface&>(x).frame();
  const Frame& fy = static_cast<const PlaneSurface&>(y).frame();
  const Vec3 nx = xr ? Vec3(-fx.z) : fx.z, ny = yr ? Vec3(-fy.z) : fy.z;
  return predicates::dot_sign(nx, ny) > 0 && d.parallel(nx, ny) &&
         d.negligible((fy.origin - fx.origin).dot(fx.z));
}

// 1. Pieces of one periodic face that meet across its seam become one face; a seam edge one
// face then uses both ways at one place bounds nothing and is spliced out.
void merge_across_seams(const BModel& model, std::vector<RFace>& faces) {
  for (std::size_t i = 0; i < faces.size(); ++i) {
    for (std::size_t j = 0; j < faces.size(); ++j) {
      if (i == j || !faces[i].alive || !faces[j].alive) continue;
      if (faces[i].source_face != faces[j].source_face || faces[i].surface->u_period() <= 0)
        continue;
      // Pieces that also meet along a real edge (a tangent line other faces use too) stay
      // two faces: only an edge that bounds nothing else may disappear.
      bool share_other = false;
      std::set<int> edges_i;
      for (const BLoop& loop : faces[i].loops) {
        for (const BUse& u : loop) {
          if (!model.edges[static_cast<std::size_t>(u.edge)].seam) edges_i.insert(u.edge);
        }
      }
      for (const BLoop& loop : faces[j].loops) {
        for (const BUse& u : loop) share_other = share_other || edges_i.count(u.edge) > 0;
      }
      if (share_other) continue;
      bool merged = true;
      while (merged && faces[j].alive) {
        merged = false;
        for (std::size_t l = 0; l < faces[i].loops.size() && !merged; ++l) {
          for (std::size_t k = 0; k < faces[i].loops[l].size() && !merged; ++k) {
            const BUse u = faces[i].loops[l][k];
            if (!model.edges[static_cast<std::size_t>(u.edge)].seam) continue;
            auto other = find_use(faces[j], u.edge, !u.forward);
            if (!other) continue;
            // Shift j's pcurves by whole periods so the shared seam coincides.
            const BEdge& e = model.edges[static_cast<std::size_t>(u.edge)];
            const double tm = 0.5 * (e.t0 + e.t1);
            const Vec2 offset =
                u.pcurve->point(tm) - faces[j].loops[other->first][other->second].pcurve->point(tm);
            for (BLoop& loop : faces[j].loops) {
              for (BUse& w : loop) w.pcurve = shift_pcurve(w.pcurve, offset);
            }
            const std::size_t base = faces[i].loops.size();
            for (BLoop& loop : faces[j].loops) faces[i].loops.push_back(std::move(loop));
            faces[j].loops.clear();
            faces[j].alive = false;
            absorb_origins(faces[i], faces[j]);
            splice(faces[i], l, k, base + other->first, other->second);
            merged = true;
          }
        }
      }
    }
  }
  // A seam edge that one face now uses in both directions at one place of its (u, v) plane
  // (its pieces met across the seam from both sides, or one piece reached round to itself)
  // bounds nothing either: it is spliced out too. Used a whole period apart it is the seam of
  // a band round the surface, and stays.
  for (RFace& f : faces) {
    if (!f.alive) continue;
    const double pu = f.surface->u_period(), pv = f.surface->v_period();
    if (pu <= 0 && pv <= 0) continue;
    auto whole_periods = [](double offset, double period) {
      return period > 0 ? std::round(offset / period) : 0.0;
    };
    bool spliced = true;
    while (spliced) {
      spliced = false;
      for (std::size_t l = 0; l < f.loops.size() && !spliced; ++l) {
        for (std::size_t k = 0; k < f.loops[l].size() && !spliced; ++k) {
          const BUse u = f.loops[l][k];
          const BEdge& e = model.edges[static_cast<std::size_t>(u.edge)];
          if (!e.seam || e.degenerate()) continue;
          const auto other = find_use(f, u.edge, !u.forward);
          if (!other) continue;
          const double tm = 0.5 * (e.t0 + e.t1);
          const Vec2 offset =
              u.pcurve->point(tm) - f.loops[other->first][other->second].pcurve->point(tm);
          if (whole_periods(offset.x(), pu) != 0 || whole_periods(offset.y(), pv) != 0) continue;
          splice(f, l, k, other->first, other->second);
          spliced = true;
        }
      }
    }
  }
}

// 2. Faces on one plane meeting along an edge are one face (the edge bounds nothing).
void merge_coplanar_faces(const BModel& model, std::vector<RFace>& faces, double tol) {
  BoundingBox extent;
  for (const BFace& f : model.faces) extent.add(f.box);
  const ToleranceModel planes{tol, std::max(extent.empty() ? 0.0 : extent.size().norm(), tol)};
  // The uses of each edge by the live faces (face ascending, then loop order), as the scan
  // below reads them; after each pass only the lists of edges the changed faces used before or
  // use now are brought up to date (a full rebuild per merge made this step quadratic).
  using UseList = std::vector<std::pair<std::size_t, bool>>;
  std::vector<UseList> uses(model.edges.size());
  for (std::size_t i = 0; i < faces.size(); ++i) {
    if (!faces[i].alive) continue;
    for (const BLoop& loop : faces[i].loops) {
      for (const BUse& u : loop) uses[static_cast<std::size_t>(u.edge)].emplace_back(i, u.forward);
    }
  }
  bool changed = true;
  while (changed) {
    changed = false;
    std::vector<std::size_t> touched;  // faces this pass changes
    std::vector<int> touched_edges;    // edges they used before or use after
    auto touch = [&](std::size_t f) {
      touched.push_back(f);
      for (const BLoop& loop : faces[f].loops) {
        for (const BUse& u : loop) touched_edges.push_back(u.edge);
      }
    };
    for (std::size_t edge_index = 0; edge_index < uses.size(); ++edge_index) {
      const int edge = static_cast<int>(edge_index);
      const UseList& list = uses[edge_index];  // as at the start of the pass
      if (list.size() != 2 || list[0].second == list[1].second) continue;
      const std::size_t i = list[0].first, j = list[1].first;
      if (!same_plane(*faces[i].surface, faces[i].reversed, *faces[j].surface, faces[j].reversed,
                      planes))
        continue;
      touch(i);
      if (i != j) {
        touch(j);
        // Refit j's pcurves on i's plane, then join.
        for (BLoop& loop : faces[j].loops) {
          for (BUse& w : loop) {
            const BEdge& e = model.edges[static_cast<std::size_t>(w.edge)];
            if (e.degenerate()) continue;
            auto pc = fit_pcurve(*e.curve, e.t0, e.t1, *faces[i].surface, fit_tolerance(tol));
            if (pc) w.pcurve = pc;
          }
        }
        for (BLoop& loop : faces[j].loops) faces[i].loops.push_back(std::move(loop));
        faces[j].loops.clear();
        faces[j].alive = false;
        absorb_origins(faces[i], faces[j]);
      }
      auto a = find_use(faces[i], edge, list[0].second);
      auto b = find_use(faces[i], edge, !list[0].second);
      if (!a || !b) continue;
      splice(faces[i], a->first, a->second, b->first, b->second);
      changed = true;
      break;
    }
    // Bring the lists up to date: entries of untouched faces stay, touched live faces give
    // theirs afresh; a stable sort by face restores the order a rebuild would give.
    std::sort(touched.begin(), touched.end());
    touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
    std::map<int, UseList> fresh;
    for (const std::size_t f : touched) {
      for (const BLoop& loop : faces[f].loops) {
        for (const BUse& u : loop) {
          touched_edges.push_back(u.edge);
          if (faces[f].alive) fresh[u.edge].emplace_back(f, u.forward);
        }
      }
    }
    std::sort(touched_edges.begin(), touched_edges.end());
    touched_edges.erase(std::unique(touched_edges.begin(), touched_edges.end()),
                        touched_edges.end());
    for (const int e : touched_edges) {
      UseList& list = uses[static_cast<std::size_t>(e)];
      UseList next;
      for (const auto& entry : list) {
        if (!std::binary_search(touched.begin(), touched.end(), entry.first)) next.push_back(entry);
      }
      if (auto it = fresh.find(e); it != fresh.end())
        next.insert(next.end(), it->second.begin(), it->second.end());
      std::stable_sort(next.begin(), next.end(),
                       [](const auto& x, const auto& y) { return x.first < y.first; });
      list = std::move(next);
    }
  }
}

// 3. Straight edges meeting end to end at a vertex nothing else uses become one edge.
void merge_collinear_edges(BModel& model, std::vector<RFace>& faces, double tol) {
  bool changed = true;
  while (changed) {
    changed = false;
    std::map<int, std::set<int>> vertex_edges;
    for (const RFace& f : faces) {
      if (!f.alive) continue;
      for (const BLoop& loop : f.loops) {
        for (const BUse& u : loop) {
          const BEdge& e = model.edges[static_cast<std::size_t>(u.edge)];
          vertex_edges[e.v0].insert(u.edge);
          vertex_edges[e.v1].insert(u.edge);
        }
      }
    }
    for (const auto& [v, edges] : vertex_edges) {
      if (edges.size() != 2) continue;
      const int e1 = *edges.begin(), e2 = *edges.rbegin();
      const BEdge& x = model.edges[static_cast<std::size_t>(e1)];
      const BEdge& y = model.edges[static_cast<std::size_t>(e2)];
      if (x.degenerate() || y.degenerate() || x.curve->kind() != CurveKind::Line ||
          y.curve->kind() != CurveKind::Line)
        continue;
      const int xa = x.v0 == v ? x.v1 : x.v0, yb = y.v0 == v ? y.v1 : y.v0;
      if (xa == yb) continue;
      const Vec3 pa = model.vertices[static_cast<std::size_t>(xa)].point;
      const Vec3 pb = model.vertices[static_cast<std::size_t>(yb)].point;
      const Vec3 pv = model.vertices[static_cast<std::size_t>(v)].point;
      const Vec3 d = pb - pa;
      if ((pv - pa).cross(d).norm() > tol * d.norm()) continue;
      BEdge merged;
      merged.curve = std::make_shared<LineCurve>(pa, d);
      merged.t0 = 0;
      merged.t1 = d.norm();
      merged.v0 = xa;
      merged.v1 = yb;
      merged.tolerance = std::max(x.tolerance, y.tolerance);
      const int id = model.add_edge(std::move(merged));
      // Replace "x then y" (or "y^-1 then x^-1") in every loop by the merged edge.
      for (RFace& f : faces) {
        if (!f.alive) continue;
        for (BLoop& loop : f.loops) {
          BLoop out;
          for (std::size_t k = 0; k < loop.size(); ++k) {
            const BUse& u = loop[k];
            if (u.edge != e1 && u.edge != e2) {
              out.push_back(u);
              continue;
            }
            const bool starts_at_a = use_start(model, u) == xa || use_start(model, u) == yb;
            if (!starts_at_a) continue;  // the second half: dropped, the first stands for both
            const bool forward = use_start(model, u) == xa;
            const BEdge& m = model.edges[static_cast<std::size_t>(id)];
            const BEdge& old = model.edges[static_cast<std::size_t>(u.edge)];
            const double old_mid = 0.5 * (old.t0 + old.t1);
            auto pc = aligned_fit(m, *f.surface, old.curve->point(old_mid),
                                  u.pcurve->point(old_mid), fit_tolerance(tol));
            out.push_back({id, forward, pc ? pc : u.pcurve});
          }
          loop = std::move(out);
        }
      }
      changed = true;
      break;
    }
  }
}

// The faces of the result as shapes, and the face of `faces` each one comes from.
struct FaceShapes {
  std::vector<Shape> shapes;
  std::vector<std::size_t> face_of;
};

// 4. Shapes: vertices, edges and faces, shared by index.
Result<FaceShapes> make_face_shapes(const BModel& model, const std::vector<RFace>& faces,
                                    double tol) {
  std::vector<double> vertex_tol(model.vertices.size(), tol);
  std::set<int> used_edges;
  for (const RFace& f : faces) {
    if (!f.alive) continue;
    for (const BLoop& loop : f.loops) {
      for (const BUse& u : loop) used_edges.insert(u.edge);
    }
  }
  for (int id : used_edges) {
    const BEdge& e = model.edges[static_cast<std::size_t>(id)];
    for (int end = 0; end < 2; ++end) {
      const int v = end == 0 ? e.v0 : e.v1;
      double gap = 0;
      if (!e.degenerate())
        gap = (e.curve->point(end == 0 ? e.t0 : e.t1) -
               model.vertices[static_cast<std::size_t>(v)].point)
                  .norm();
      vertex_tol[static_cast<std::size_t>(v)] =
          std::max({vertex_tol[static_cast<std::size_t>(v)], gap * 1.01, e.tolerance});
    }
  }
  std::map<int, Shape> vertex_shapes, edge_shapes;
  auto vertex_shape = [&](int v) -> Result<Shape> {
    if (auto it = vertex_shapes.find(v); it != vertex_shapes.end()) return it->second;
    auto s = ShapeFactory::vertex(model.vertices[static_cast<std::size_t>(v)].point,
                                  vertex_tol[static_cast<std::size_t>(v)]);
    if (s.ok()) vertex_shapes.emplace(v, s.value());
    return s;
  };
  auto edge_shape = [&](int id) -> Result<Shape> {
    if (auto it = edge_shapes.find(id); it != edge_shapes.end()) return it->second;
    const BEdge& e = model.edges[static_cast<std::size_t>(id)];
    auto v0 = vertex_shape(e.v0);
    auto v1 = vertex_shape(e.v1);
    if (!v0.ok()) return v0;
    if (!v1.ok()) return v1;
    Result<Shape> s =
        e.degenerate()
            ? ShapeFactory::degenerate_edge(v0.value(), e.t0, e.t1, e.tolerance)
            : ShapeFactory::edge(e.curve, e.t0, e.t1, v0.value(), v1.value(), e.tolerance);
    if (s.ok()) edge_shapes.emplace(id, s.value());
    return s;
  };
  FaceShapes out;
  for (std::size_t i = 0; i < faces.size(); ++i) {
    const RFace& f = faces[i];
    if (!f.alive || f.loops.empty()) continue;
    std::vector<Shape> wires;
    std::vector<std::vector<Curve2dPtr>> pcurves;
    // Outer loop first: by area, each loop's taken once (it samples the loop's pcurves).
    std::vector<double> area(f.loops.size());
    for (std::size_t k = 0; k < f.loops.size(); ++k) area[k] = loop_area(model, f.loops[k]);
    std::vector<std::size_t> order(f.loops.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t x, std::size_t y) { return area[x] > area[y]; });
    for (const std::size_t k : order) {
      const BLoop& loop = f.loops[k];
      std::vector<Shape> edges;
      std::vector<Curve2dPtr> curves;
      for (const BUse& u : loop) {
        auto e = edge_shape(u.edge);
        if (!e.ok()) return e.error();
        edges.push_back(u.forward ? e.value() : e.value().reversed());
        curves.push_back(u.pcurve);
      }
      auto w = ShapeFactory::wire(std::move(edges));
      if (!w.ok()) return w.error();
      wires.push_back(w.value());
      pcurves.push_back(std::move(curves));
    }
    auto face = ShapeFactory::face(f.surface, std::move(wires), std::move(pcurves), tol);
    if (!face.ok()) return face.error();
    out.shapes.push_back(
        face.value().oriented(f.reversed ? Orientation::Reversed : Orientation::Forward));
    out.face_of.push_back(i);
  }
  return out;
}

// 5. Shells: faces joined through edges that exactly two faces use (an edge shared by four
// faces is where two solids touch: it joins nothing); solids: each outer shell with the
// cavities it holds. `known_volumes` receives the solids whose volume was measured.
Result<Shape> make_solids(const BModel& model, const std::vector<RFace>& faces,
                          const FaceShapes& made, double tol,
                          std::vector<std::pair<Shape, double>>& known_volumes) {
  std::vector<std::size_t> parent(made.shapes.size());
  std::iota(parent.begin(), parent.end(), 0);
  std::function<std::size_t(std::size_t)> root = [&](std::size_t x) {
    return parent[x] == x ? x : parent[x] = root(parent[x]);
  };
  std::map<int, std::vector<std::size_t>> edge_users;
  for (std::size_t k = 0; k < made.shapes.size(); ++k) {
    std::set<int> mine;
    for (const BLoop& loop : faces[made.face_of[k]].loops) {
      for (const BUse& u : loop) {
        if (!model.edges[static_cast<std::size_t>(u.edge)].degenerate()) mine.insert(u.edge);
      }
    }
    for (int e : mine) edge_users[e].push_back(k);
  }
  for (const auto& [e, users] : edge_users) {
    if (users.size() == 2) parent[root(users[0])] = root(users[1]);
  }
  std::map<std::size_t, std::vector<Shape>> groups;
  for (std::size_t k = 0; k < made.shapes.size(); ++k) groups[root(k)].push_back(made.shapes[k]);
  struct ShellInfo {
    Shape shell;
    double volume;
    Shape probe;  // the shell as a solid of its own (volume is its mass_properties volume)
  };
  std::vector<ShellInfo> outer, cavities;
  for (auto& [r, list] : groups) {
    auto shell = ShapeFactory::shell(list);
    if (!shell.ok()) return shell.error();
    auto probe = ShapeFactory::solid({shell.value()});
    if (!probe.ok()) return probe.error();
    const double v = solid_volume(probe.value());  // mass_properties' volume (to rounding)
    if (std::abs(v) <= tol * tol * tol) continue;  // no volume: a leftover sheet
    (v > 0 ? outer : cavities).push_back({shell.value(), v, probe.value()});
  }
  std::vector<std::vector<Shape>> solid_shells;
  for (const ShellInfo& o : outer) solid_shells.push_back({o.shell});
  for (const ShellInfo& c : cavities) {
    // The smallest outer shell around the cavity.
    const Vec3 p = vertex_point(*Explorer(c.shell, ShapeKind::Vertex).begin());
    int best = -1;
    for (std::size_t k = 0; k < outer.size(); ++k) {
      auto cls = SolidClassifier::create(ShapeFactory::solid({outer[k].shell}).value(), tol);
      if (!cls.ok()) continue;
      if (cls->classify(p) != Containment::Inside) continue;
      if (best < 0 || outer[k].volume < outer[static_cast<std::size_t>(best)].volume)
        best = static_cast<int>(k);
    }
    if (best < 0) return Error{ErrorCode::InvalidShape, "a cavity of the result lies in no solid"};
    solid_shells[static_cast<std::size_t>(best)].push_back(c.shell);
  }
  std::vector<Shape> solids;
  for (std::size_t k = 0; k < solid_shells.size(); ++k) {
    if (solid_shells[k].size() == 1) {
      // Without cavities the solid is the probe: its volume is known (the checker's test).
      solids.push_back(outer[k].probe);
      known_volumes.emplace_back(outer[k].probe, outer[k].volume);
      continue;
    }
    auto s = ShapeFactory::solid(solid_shells[k]);
    if (!s.ok()) return s.error();
    solids.push_back(s.value());
  }
  return ShapeFactory::compound(std::move(solids));
}

}  // namespace

Result<Shape> BooleanEngine::build(std::vector<Piece>& pieces) {
  const double tol = options_.tolerance;
  std::vector<RFace> faces;
  for (const Piece& p : pieces) {
    if (!p.keep) continue;
    const BFace& f = model_.faces[static_cast<std::size_t>(p.face)];
    faces.push_back({p.face,
                     f.surface,
                     f.reversed != p.flip,
                     p.region.loops,
                     true,
                     {FaceOrigin{f.operand, f.source}}});
  }
  merge_across_seams(model_, faces);
  merge_coplanar_faces(model_, faces, tol);
  merge_collinear_edges(model_, faces, tol);
  auto made = make_face_shapes(model_, faces, tol);
  if (!made.ok()) return made.error();
  std::vector<std::pair<Shape, double>> known_volumes;  // solids whose volume is measured
  auto result = make_solids(model_, faces, made.value(), tol, known_volumes);
  if (!result.ok()) return result;
  // Face history: each face of the result (child-map order) with the input faces it holds.
  const ShapeIndex result_faces = map_child_shapes(result.value(), ShapeKind::Face);
  origins_.assign(result_faces.size(), {});
  for (std::size_t k = 0; k < made.value().shapes.size(); ++k) {
    const std::size_t at = result_faces.find(made.value().shapes[k]);
    if (at != ShapeIndex::npos) origins_[at] = faces[made.value().face_of[k]].origins;
  }
  if (options_.check_result) {
    const CheckReport report = check_shape_with_volumes(result.value(), known_volumes);
    if (!report.valid()) {
      return Error{ErrorCode::InvalidShape, std::string("the ") + boolean_op_name(op_) +
                                                " result fails the checker: " +
                                                check_status_name(report.issues.front().status) +
                                                ": " + report.issues.front().message};
    }
  }
  return result;
}

}  // namespace csgtile::kernel::detail
