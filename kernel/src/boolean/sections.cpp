// The Boolean engine: the sections of each pair of faces, added as edges of both.

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
#include "boolean/line_surface.h"
#include "boolean/marching.h"
#include "boolean/model.h"
#include "boolean/pcurve_fit.h"
#include "boolean/surface_intersection.h"
#include "boolean/tolerance.h"
#include "boolean/uv_geometry.h"
#include "csgtile/kernel/check.h"
#include "csgtile/kernel/explorer.h"

namespace csgtile::kernel::detail {

void BooleanEngine::boundary_hits(std::size_t f, const Curve2d& pc, double t0, double t1,
                                  int skip_edge, std::vector<Hit>& hits) {
  const BFace& face = model_.faces[f];
  const double pu = face.surface->u_period(), pv = face.surface->v_period();
  const int ku = pu > 0 ? 2 : 0, kv = pv > 0 ? 1 : 0;
  const double tol = uv_margin(f) * kCrossingUvSlacks;
  // Boundary uses (and their period copies) whose box stays clear of the curve's cannot
  // cross it: skipped without sampling (crossing_boxes_apart; the same hits).
  const std::vector<CrossingBox>& boxes = boundary_boxes(f);
  const std::vector<Vec2> curve_points = crossing_points(pc, t0, t1);  // sampled once
  const CrossingBox curve_box = crossing_box(pc, t0, t1, curve_points);
  std::size_t k = 0;
  for (const BLoop& loop : face.loops) {
    for (const BUse& u : loop) {
      const CrossingBox& use_box = boxes[k++];
      if (u.edge == skip_edge) continue;
      const BEdge& e = model_.edges[static_cast<std::size_t>(u.edge)];
      for (int i = -ku; i <= ku; ++i) {
        for (int j = -kv; j <= kv; ++j) {
          if (crossing_boxes_apart(curve_box, use_box, Vec2(i * pu, j * pv), tol)) continue;
          Curve2dPtr shifted = shift_pcurve(u.pcurve, Vec2(i * pu, j * pv));
          for (const Crossing& c :
               intersect_pcurves(pc, t0, t1, curve_points, *shifted, e.t0, e.t1, tol)) {
            hits.push_back({c.t, u.edge, c.s});
          }
        }
      }
    }
  }
}

const std::vector<CrossingBox>& BooleanEngine::boundary_boxes(std::size_t f) {
  if (boundary_boxes_.size() != model_.faces.size())
    boundary_boxes_.assign(model_.faces.size(), {});
  std::vector<CrossingBox>& boxes = boundary_boxes_[f];
  if (boxes.empty()) {
    for (const BLoop& loop : model_.faces[f].loops) {
      for (const BUse& u : loop) {
        const BEdge& e = model_.edges[static_cast<std::size_t>(u.edge)];
        boxes.push_back(crossing_box(*u.pcurve, e.t0, e.t1));
      }
    }
  }
  return boxes;
}

Status BooleanEngine::add_section(std::size_t fa, std::size_t fb, CurvePtr curve, double t0,
                                  double t1, int existing, const Curve2dPtr& hint_a,
                                  const Curve2dPtr& hint_b, double edge_tolerance) {
  // A closed section lying along a closed boundary edge of one face (a dome's equator on
  // its drum's rim): that edge lies in the other face. Matched here because the two
  // circles' vertices need not coincide, so find_edge cannot see they are one.
  if (existing < 0) {
    for (auto [own, other] : {std::pair{fa, fb}, std::pair{fb, fa}}) {
      const int e = closed_boundary_edge_along(own, *curve, t0, t1);
      if (e >= 0) {
        const BEdge be = model_.edges[static_cast<std::size_t>(e)];
        return add_section(other, own, be.curve, be.t0, be.t1, e);
      }
    }
  }
  const double fit_tol = fit_tolerance(options_.tolerance);
  Curve2dPtr pa = hint_a          ? hint_a
                  : existing >= 0 ? lying_pcurve(existing, fa)
                                  : fit_pcurve(*curve, t0, t1, *model_.faces[fa].surface, fit_tol);
  Curve2dPtr pb = existing >= 0 ? nullptr
                  : hint_b      ? hint_b
                                : fit_pcurve(*curve, t0, t1, *model_.faces[fb].surface, fit_tol);
  if (!pa || (existing < 0 && !pb)) {
    // A great circle through a sphere's poles folds in v there: fit each half apart.
    std::vector<double> folds;
    for (std::size_t f : {fa, fb}) {
      if (model_.faces[f].surface->kind() != SurfaceKind::Sphere) continue;
      const auto& sp = static_cast<const SphereSurface&>(*model_.faces[f].surface);
      for (double sign : {-1.0, 1.0}) {
        const Vec3 pole = sp.frame().origin + sign * sp.radius() * sp.frame().z;
        const double t = curve->closest_parameter(pole, t0, t1);
        const double span = param_slack(t1 - t0);
        if ((curve->point(t) - pole).norm() <= options_.tolerance && t > t0 + span &&
            t < t1 - span) {
          folds.push_back(t);
        }
      }
    }
    if (!folds.empty()) {
      std::sort(folds.begin(), folds.end());
      double start = t0;
      folds.push_back(t1);
      for (double end : folds) {
        if (auto st = add_section(fa, fb, curve, start, end, existing); !st.ok()) return st;
        start = end;
      }
      return {};
    }
    // No exact pcurve (a sphere framed for tracing): the section as a traced polyline.
    if (existing < 0 && curve->kind() != CurveKind::Polyline) {
      const double size = std::max(model_.faces[fa].box.size().norm(), options_.tolerance);
      const double sag = traced_sag(options_.tolerance, size);
      if (auto traced = sample_section(*curve, t0, t1, *model_.faces[fa].surface,
                                       *model_.faces[fb].surface, sag)) {
        const double n = static_cast<double>(traced->points.size() - 1);
        const double deviation = std::max(traced->deviation, options_.tolerance);
        auto polyline = std::make_shared<PolylineCurve>(std::move(traced->points), deviation);
        return add_section(fa, fb, polyline, 0.0, n, -1,
                           std::make_shared<Polyline2d>(std::move(traced->uv_a)),
                           std::make_shared<Polyline2d>(std::move(traced->uv_b)), deviation);
      }
    }
    return Status(ErrorCode::Unsupported, std::string("the section of a ") +
                                              surface_name(model_.faces[fa].surface->kind()) +
                                              " and a " +
                                              surface_name(model_.faces[fb].surface->kind()) +
                                              " has no exact pcurve in this version");
  }
  std::vector<Hit> hits;
  boundary_hits(fa, *pa, t0, t1, -1, hits);
  const std::size_t hits_on_a = hits.size();
  if (existing < 0) boundary_hits(fb, *pb, t0, t1, -1, hits);
  if (existing < 0 && curve->kind() == CurveKind::Polyline) {
    snap_traced_crossings(fa, fb, curve, pa, pb, t0, t1, hits, hits_on_a,
                          std::max(edge_tolerance, options_.tolerance));
    edge_tolerance =
        std::max(edge_tolerance, static_cast<const PolylineCurve&>(*curve).tolerance());
  } else {
    reuse_edge_vertices(*curve, t0, t1, hits);
  }
  std::vector<double> cuts{t0, t1};
  for (const Hit& h : hits) cuts.push_back(h.t);
  std::sort(cuts.begin(), cuts.end());
  const double min_span = param_slack(t1 - t0);
  for (std::size_t i = 0; i + 1 < cuts.size(); ++i) {
    const double c0 = cuts[i], c1 = cuts[i + 1];
    if (c1 - c0 <= min_span) continue;
    const double mid = 0.5 * (c0 + c1);
    auto shift_a = polygons_[fa].shift_inside(pa->point(mid), uv_margin(fa) * kInsideUvSlacks);
    std::optional<Vec2> shift_b = Vec2::Zero();
    if (existing < 0)
      shift_b = polygons_[fb].shift_inside(pb->point(mid), uv_margin(fb) * kInsideUvSlacks);
    if (existing < 0) {
      // The piece runs along a boundary edge of face `along`: that edge, or the part of it the
      // piece covers, splits face `split`. Inside one face only, it lies in the other's
      // boundary (an edge lying in a face). Inside both, it can still run along an edge an
      // earlier fuse made (a plane through that edge: a beam's end face snapped onto its
      // neighbour's), then found at its quarter points too, and is not a second edge beside it.
      auto split_by_edge = [&](std::size_t along, std::size_t split, bool quarters) {
        const int e = boundary_edge_through(along, curve->point(mid));
        if (e < 0 ||
            (quarters && (boundary_edge_through(along, curve->point(c0 + 0.25 * (c1 - c0))) != e ||
                          boundary_edge_through(along, curve->point(c0 + 0.75 * (c1 - c0))) != e)))
          return false;
        add_edge_part(split, e, curve->point(c0), curve->point(c1), curve->point(mid));
        return true;
      };
      if (shift_a.has_value() != shift_b.has_value()) {
        split_by_edge(shift_a ? fb : fa, shift_a ? fa : fb, false);
        continue;
      }
      if (shift_a && (split_by_edge(fa, fb, true) || split_by_edge(fb, fa, true))) continue;
    }
    if (!shift_a || !shift_b) continue;
    // Vertices at the piece's ends: split the boundary edges they fall on.
    const int v0 = vertex_on_curve(*curve, c0, hits);
    const int v1 = vertex_on_curve(*curve, c1, hits);
    int edge_id = existing;
    if (edge_id < 0) {
      edge_id = find_edge(v0, v1,
                          {curve->point(c0 + 0.25 * (c1 - c0)), curve->point(mid),
                           curve->point(c0 + 0.75 * (c1 - c0))});
      if (edge_id < 0) {
        BEdge e;
        e.curve = curve;
        e.t0 = c0;
        e.t1 = c1;
        e.v0 = v0;
        e.v1 = v1;
        e.tolerance = std::max(options_.tolerance, edge_tolerance);
        edge_id = model_.add_edge(std::move(e));
      }
    }
    if (existing >= 0) {
      BEdge& own = model_.edges[static_cast<std::size_t>(existing)];
      for (auto [c, v] : {std::pair{c0, v0}, std::pair{c1, v1}}) {
        if (c > own.t0 + min_span && c < own.t1 - min_span && v != own.v0 && v != own.v1) {
          own.splits.emplace_back(c, v);
        }
      }
    }
    const BEdge& e = model_.edges[static_cast<std::size_t>(edge_id)];
    if (existing >= 0) {
      // Only the part [c0, c1] of the existing edge lies inside fa; such partial pieces
      // are handled by splitting the edge at the hits (the part is then a sub-edge).
      if (std::abs(c0 - e.t0) > min_span || std::abs(c1 - e.t1) > min_span) {
        pending_partials_.push_back({fa, edge_id, c0, c1, shift_pcurve(pa, *shift_a)});
        continue;
      }
    }
    add_extra(fa, edge_id, refit_for(edge_id, fa, shift_pcurve(pa, *shift_a), curve));
    if (existing < 0)
      add_extra(fb, edge_id, refit_for(edge_id, fb, shift_pcurve(pb, *shift_b), curve));
  }
  return {};
}

std::optional<double> BooleanEngine::pierce_parameter(const BEdge& e, double s,
                                                      const Surface& surface) const {
  const double settled = kNewtonConvergedFraction * options_.tolerance;
  for (int k = 0; k < kPierceIterations; ++k) {
    const Vec3 x = e.curve->point(s);
    const Vec2 uv = surface.closest_parameters(x);
    const Vec3 n = surface.normal(uv.x(), uv.y());
    const double distance = (x - surface.point(uv.x(), uv.y())).dot(n);
    const Vec3 tangent = e.curve->derivative(s);
    const double rate = tangent.dot(n);
    if (!(std::abs(rate) > kGrazingCosine * tangent.norm())) return std::nullopt;
    const double next = std::clamp(s - distance / rate, e.t0, e.t1);
    if (std::abs(distance) <= settled) return next;  // one step past settling: at rounding level
    s = next;
  }
  return std::nullopt;
}

void BooleanEngine::snap_traced_crossings(std::size_t fa, std::size_t fb, CurvePtr& curve,
                                          Curve2dPtr& pa, Curve2dPtr& pb, double& t0, double& t1,
                                          std::vector<Hit>& hits, std::size_t hits_on_a,
                                          double reach) {
  if (pa->kind() != Curve2dKind::Polyline || pb->kind() != Curve2dKind::Polyline) return;
  const std::vector<Vec3>& points = static_cast<const PolylineCurve&>(*curve).points();
  const std::vector<Vec2>& uv_a = static_cast<const Polyline2d&>(*pa).points();
  const std::vector<Vec2>& uv_b = static_cast<const Polyline2d&>(*pb).points();
  if (uv_a.size() != points.size() || uv_b.size() != points.size()) return;
  const Surface& sa = *model_.faces[fa].surface;
  const Surface& sb = *model_.faces[fb].surface;
  const double last = static_cast<double>(points.size() - 1);
  const bool closed = points.front() == points.back();
  const double slack = param_slack(last);
  const ToleranceModel model{options_.tolerance, options_.tolerance};  // lengths only
  // A pierce point lies on both surfaces within the pierced edge's tolerance (an earlier
  // traced section is that far off the surfaces it joins); the polyline's deviation then
  // grows to cover it.
  double deviation = static_cast<const PolylineCurve&>(*curve).tolerance();
  auto on_surface = [&](const Surface& s, const Vec3& p, const Vec2& near,
                        double allowed) -> std::optional<Vec2> {
    Vec2 uv = s.closest_parameters(p);
    uv.x() = nearest_periodic(uv.x(), near.x(), s.u_period());
    uv.y() = nearest_periodic(uv.y(), near.y(), s.v_period());
    if (!ToleranceModel{allowed, allowed}.negligible((s.point(uv.x(), uv.y()) - p).norm()))
      return std::nullopt;
    return uv;
  };
  struct Snap {
    double t;  // old parameter; then the new one
    Vec3 point;
    Vec2 uv_a, uv_b;
  };
  std::vector<Snap> snaps;
  std::vector<int> snap_of_hit(hits.size(), -1);
  std::vector<double> pierced(hits.size(), 0.0);
  for (std::size_t k = 0; k < hits.size(); ++k) {
    const Hit& h = hits[k];
    const BEdge& e = model_.edges[static_cast<std::size_t>(h.edge)];
    if (e.degenerate()) continue;
    if (closed && (h.t <= slack || h.t >= last - slack)) continue;  // the loop's own seam vertex
    const auto s = pierce_parameter(e, h.s, k < hits_on_a ? sb : sa);
    if (!s) continue;
    const Vec3 p = e.curve->point(*s);
    if ((p - curve->point(h.t)).norm() > kTracedSnapReach * reach) continue;
    // One crossing found on two edges (at their common vertex) or twice: one snap.
    int same = -1;
    for (std::size_t j = 0; j < snaps.size() && same < 0; ++j) {
      if (model.negligible((snaps[j].point - p).norm())) same = static_cast<int>(j);
    }
    if (same < 0) {
      const double allowed = std::max(options_.tolerance, e.tolerance);
      const auto qa = on_surface(sa, p, pa->point(h.t), allowed);
      const auto qb = on_surface(sb, p, pb->point(h.t), allowed);
      if (!qa || !qb) continue;
      deviation = std::max(deviation, allowed);
      snaps.push_back({h.t, p, *qa, *qb});
      same = static_cast<int>(snaps.size()) - 1;
    }
    snap_of_hit[k] = same;
    pierced[k] = *s;
  }
  if (snaps.empty()) return;
  std::vector<std::size_t> order(snaps.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t x, std::size_t y) { return snaps[x].t < snaps[y].t; });
  // The new polyline: old vertices, with each snap inserted in its chord, or in place of
  // a vertex it falls on. `knots` maps old parameters to new ones (piecewise linear).
  std::vector<Vec3> new_points;
  std::vector<Vec2> new_a, new_b;
  std::vector<std::pair<double, double>> knots;
  std::size_t next = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double at = static_cast<double>(i);
    while (next < order.size() && snaps[order[next]].t < at - slack) {
      Snap& sn = snaps[order[next++]];
      knots.emplace_back(sn.t, static_cast<double>(new_points.size()));
      sn.t = static_cast<double>(new_points.size());
      new_points.push_back(sn.point);
      new_a.push_back(sn.uv_a);
      new_b.push_back(sn.uv_b);
    }
    knots.emplace_back(at, static_cast<double>(new_points.size()));
    if (next < order.size() && snaps[order[next]].t <= at + slack) {
      Snap& sn = snaps[order[next++]];
      sn.t = static_cast<double>(new_points.size());
      new_points.push_back(sn.point);
      new_a.push_back(sn.uv_a);
      new_b.push_back(sn.uv_b);
    } else {
      new_points.push_back(points[i]);
      new_a.push_back(uv_a[i]);
      new_b.push_back(uv_b[i]);
    }
  }
  auto remap = [&](double t) {
    auto it =
        std::upper_bound(knots.begin(), knots.end(), t,
                         [](double x, const std::pair<double, double>& k) { return x < k.first; });
    if (it == knots.begin()) return knots.front().second;
    if (it == knots.end()) return knots.back().second;
    const auto& [x0, y0] = *(it - 1);
    const auto& [x1, y1] = *it;
    return y0 + (y1 - y0) * (t - x0) / (x1 - x0);
  };
  t0 = remap(t0);
  t1 = remap(t1);
  for (std::size_t k = 0; k < hits.size(); ++k) {
    if (snap_of_hit[k] >= 0) {
      hits[k].t = snaps[static_cast<std::size_t>(snap_of_hit[k])].t;
      hits[k].s = pierced[k];
    } else {
      hits[k].t = remap(hits[k].t);
    }
  }
  curve = std::make_shared<PolylineCurve>(std::move(new_points), deviation);
  pa = std::make_shared<Polyline2d>(std::move(new_a));
  pb = std::make_shared<Polyline2d>(std::move(new_b));
}

void BooleanEngine::reuse_edge_vertices(const Curve& curve, double t0, double t1,
                                        std::vector<Hit>& hits) {
  const double tol = options_.tolerance;
  for (Hit& h : hits) {
    const BEdge& e = model_.edges[static_cast<std::size_t>(h.edge)];
    if (e.degenerate()) continue;
    const Vec3 p = curve.point(h.t);
    // The edge's vertices (its splits and its ends) with their parameters.
    auto for_each_vertex = [&](const auto& visit) {
      for (const auto& [s, v] : e.splits) visit(s, v);
      visit(e.t0, e.v0);
      visit(e.t1, e.v1);
    };
    double nearest = INFINITY;
    for_each_vertex([&](double, int v) {
      nearest = std::min(nearest, (model_.vertices[static_cast<std::size_t>(v)].point - p).norm());
    });
    if (nearest <= tol || nearest > kReuseReach * tol) continue;  // vertex_at finds it; none near
    double best = kReuseReach * tol;
    for_each_vertex([&](double s, int v) {
      const Vec3& w = model_.vertices[static_cast<std::size_t>(v)].point;
      const double d = (w - p).norm();
      if (d > best) return;
      const double t = curve.closest_parameter(w, t0, t1);
      if ((curve.point(t) - w).norm() > tol) return;
      best = d;
      h.t = t;
      h.s = s;
    });
  }
}

int BooleanEngine::boundary_edge_through(std::size_t f, const Vec3& p) {
  for (const BLoop& loop : model_.faces[f].loops) {
    for (const BUse& u : loop) {
      const BEdge& e = model_.edges[static_cast<std::size_t>(u.edge)];
      if (e.degenerate()) continue;
      const double t = e.curve->closest_parameter(p, e.t0, e.t1);
      if ((e.curve->point(t) - p).norm() <= options_.tolerance) return u.edge;
    }
  }
  return -1;
}

void BooleanEngine::add_edge_part(std::size_t f, int e_id, const Vec3& p0, const Vec3& p1,
                                  const Vec3& through) {
  const BEdge& e = model_.edges[static_cast<std::size_t>(e_id)];
  double a = e.curve->closest_parameter(p0, e.t0, e.t1),
         b = e.curve->closest_parameter(p1, e.t0, e.t1);
  if (a > b) std::swap(a, b);
  const double span = param_slack(e.t1 - e.t0);
  if (e.v0 == e.v1 && !e.degenerate()) {
    const double t = e.curve->closest_parameter(through, e.t0, e.t1);
    if (b - a <= span) {
      if (std::abs(t - a) <= span) return;  // a piece of no length
      a = e.t0;  // both ends at the vertex, its middle elsewhere: the whole loop
      b = e.t1;
    } else if (t < a - span || t > b + span) {
      const double t0 = e.t0, t1 = e.t1;
      add_edge_range(f, e_id, b, t1);
      add_edge_range(f, e_id, t0, a);
      return;
    }
  }
  add_edge_range(f, e_id, a, b);
}

void BooleanEngine::add_edge_range(std::size_t f, int e_id, double a, double b) {
  const BEdge e = model_.edges[static_cast<std::size_t>(e_id)];
  const double span = param_slack(e.t1 - e.t0);
  if (b - a <= span) return;
  for (double t : {a, b}) {
    if (t > e.t0 + span && t < e.t1 - span) {
      const int v = model_.vertex_at(e.curve->point(t));
      if (v != e.v0 && v != e.v1)
        model_.edges[static_cast<std::size_t>(e_id)].splits.emplace_back(t, v);
    }
  }
  auto pc = lying_pcurve(e_id, f, a, b);
  if (!pc) return;
  auto shift = polygons_[f].shift_inside(pc->point(0.5 * (a + b)), uv_margin(f) * kInsideUvSlacks);
  if (!shift) return;
  pc = shift_pcurve(pc, *shift);
  if (a <= e.t0 + span && b >= e.t1 - span) {
    add_extra(f, e_id, pc);
  } else {
    pending_partials_.push_back({f, e_id, a, b, pc});
  }
}

Curve2dPtr BooleanEngine::lying_pcurve(int edge, std::size_t f, double a, double b) {
  BEdge& e = model_.edges[static_cast<std::size_t>(edge)];
  const Surface& surface = *model_.faces[f].surface;
  const double t0 = std::max(a, e.t0), t1 = std::min(b, e.t1);
  if (auto exact = fit_pcurve(*e.curve, t0, t1, surface, fit_tolerance(options_.tolerance)))
    return exact;
  auto within = fit_pcurve(*e.curve, t0, t1, surface, std::max(options_.tolerance, e.tolerance));
  if (within)
    e.tolerance = std::max(e.tolerance, pcurve_deviation(*e.curve, *within, t0, t1, surface));
  return within;
}

Curve2dPtr BooleanEngine::refit_for(int edge, std::size_t f, const Curve2dPtr& pc,
                                    const CurvePtr& curve) {
  const BEdge& e = model_.edges[static_cast<std::size_t>(edge)];
  if (e.curve == curve) return pc;
  const Vec3 mid = e.curve->point(0.5 * (e.t0 + e.t1));
  const double lo = curve->period() > 0 ? 0.0 : -1e300,
               hi = curve->period() > 0 ? curve->period() : 1e300;
  const Vec2 old_uv = pc->point(curve->closest_parameter(mid, lo, hi));
  auto fitted =
      aligned_fit(e, *model_.faces[f].surface, mid, old_uv, fit_tolerance(options_.tolerance));
  return fitted ? fitted : pc;
}

void BooleanEngine::add_extra(std::size_t f, int edge, Curve2dPtr pcurve) {
  BFace& face = model_.faces[f];
  for (const BUse& u : face.extra) {
    if (u.edge == edge) return;
  }
  for (const BLoop& loop : face.loops) {
    for (const BUse& u : loop) {
      if (u.edge == edge) return;  // already on the boundary
    }
  }
  face.extra.push_back({edge, true, std::move(pcurve)});
}

int BooleanEngine::closed_boundary_edge_along(std::size_t f, const Curve& curve, double t0,
                                              double t1) {
  const double tol = options_.tolerance;
  if ((curve.point(t0) - curve.point(t1)).norm() > tol) return -1;
  for (const BLoop& loop : model_.faces[f].loops) {
    for (const BUse& u : loop) {
      const BEdge& e = model_.edges[static_cast<std::size_t>(u.edge)];
      if (e.degenerate() || e.v0 != e.v1) continue;
      bool along = true;
      for (int k = 0; k < 8 && along; ++k) {
        const Vec3 p = curve.point(t0 + (t1 - t0) * (k + 0.5) / 8);
        const Vec3 q = e.curve->point(e.t0 + (e.t1 - e.t0) * (k + 0.5) / 8);
        along = (e.curve->point(e.curve->closest_parameter(p, e.t0, e.t1)) - p).norm() <= tol &&
                (curve.point(curve.closest_parameter(q, t0, t1)) - q).norm() <= tol;
      }
      if (along) return u.edge;
    }
  }
  return -1;
}

int BooleanEngine::find_edge(int v0, int v1, const std::vector<Vec3>& probes) {
  for (std::size_t i = 0; i < model_.edges.size(); ++i) {
    const BEdge& e = model_.edges[i];
    if (e.degenerate()) continue;
    if (!((e.v0 == v0 && e.v1 == v1) || (e.v0 == v1 && e.v1 == v0))) continue;
    bool on = true;
    for (const Vec3& p : probes) {
      const double t = e.curve->closest_parameter(p, e.t0, e.t1);
      on = on && (e.curve->point(t) - p).norm() <= options_.tolerance;
    }
    if (on) return static_cast<int>(i);
  }
  return -1;
}

int BooleanEngine::vertex_on_curve(const Curve& curve, double t, const std::vector<Hit>& hits) {
  const Vec3 p = curve.point(t);
  const int v = model_.vertex_at(p);
  for (const Hit& h : hits) {
    if (std::abs(h.t - t) > param_slack(std::abs(t))) continue;
    BEdge& e = model_.edges[static_cast<std::size_t>(h.edge)];
    // Parameters this close can still name points apart on a fast curve (the section of a
    // plane almost parallel to a cylinder's axis runs kilometres per radian): the hit is
    // this vertex only where its point on the edge is.
    if (!e.degenerate() &&
        (e.curve->point(h.s) - p).norm() > std::max(options_.tolerance, e.tolerance))
      continue;
    // A pole (degenerate edge) is split in its parameter where a meridian reaches it.
    if (!e.degenerate() && (v == e.v0 || v == e.v1)) continue;
    e.splits.emplace_back(h.s, v);
  }
  return v;
}

bool BooleanEngine::lies_on(std::size_t f, std::size_t g) const {
  const Surface& surface = *model_.faces[g].surface;
  auto near = [&](const Vec3& p, double allowed) {
    const Vec2 uv = surface.closest_parameters(p);
    return (surface.point(uv.x(), uv.y()) - p).norm() <= allowed;
  };
  for (const BLoop& loop : model_.faces[f].loops) {
    for (const BUse& u : loop) {
      const BEdge& e = model_.edges[static_cast<std::size_t>(u.edge)];
      if (e.degenerate()) continue;
      const double allowed = std::max(options_.tolerance, e.tolerance);
      if (!near(e.curve->point(e.t0), allowed) ||
          !near(e.curve->point(0.5 * (e.t0 + e.t1)), allowed))
        return false;
    }
  }
  return true;
}

Status BooleanEngine::intersect_faces() {
  const double tol = options_.tolerance;
  boundary_boxes_.clear();
  for (std::size_t fa = 0; fa < first_b_face_; ++fa) {
    if (auto s = interrupted("intersecting faces"); !s.ok()) return s;
    for (std::size_t fb = first_b_face_; fb < model_.faces.size(); ++fb) {
      BoundingBox ba = model_.faces[fa].box, bb = model_.faces[fb].box;
      ba.enlarge(tol);
      bb.enlarge(tol);
      if (!ba.intersects(bb)) continue;
      BoundingBox clip;
      clip.min = ba.min.cwiseMax(bb.min);
      clip.max = ba.max.cwiseMin(bb.max);
      SsiResult ssi =
          intersect_surfaces(*model_.faces[fa].surface, *model_.faces[fb].surface, clip, tol);
      if (ssi.kind == SsiKind::Coincident && !(lies_on(fa, fb) && lies_on(fb, fa))) {
        // One within tolerance over the sliver where the faces' boxes meet (two planes at
        // 4° sharing one corner, their boxes touching along a line), yet apart over the
        // faces: decided again over both faces' extent, where they cross.
        BoundingBox whole = ba;
        whole.add(bb);
        ssi = intersect_surfaces(*model_.faces[fa].surface, *model_.faces[fb].surface, whole, tol);
      }
      if (ssi.kind == SsiKind::Unsupported) return Status(ErrorCode::Unsupported, ssi.reason);
      if (ssi.kind == SsiKind::Coincident) {
        coincident_.emplace_back(fa, fb);
        continue;
      }
      for (const SectionCurve& c : ssi.curves) {
        if (auto s = add_section(fa, fb, c.curve, c.first, c.last, -1, c.pcurve_a, c.pcurve_b,
                                 c.deviation);
            !s.ok())
          return s;
      }
    }
  }
  // Coincident faces: each one's boundary edges that lie inside the other split it.
  for (const auto& [fa, fb] : coincident_) {
    for (auto [from, into] : {std::pair{fb, fa}, std::pair{fa, fb}}) {
      std::set<int> seen;
      for (const BLoop& loop : model_.faces[from].loops) {
        for (const BUse& u : loop) {
          const BEdge e = model_.edges[static_cast<std::size_t>(u.edge)];
          if (e.degenerate() || !seen.insert(u.edge).second) continue;
          if (auto s = add_section(into, from, e.curve, e.t0, e.t1, u.edge); !s.ok()) return s;
        }
      }
    }
  }
  return {};
}

}  // namespace csgtile::kernel::detail
