// Boolean operations: orchestration (see csgtile/kernel/boolean.h for the method).

#include "csgtile/kernel/boolean.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <numbers>
#include <numeric>
#include <set>
#include <string>

#include "boolean/arguments.h"
#include "boolean/classifier.h"
#include "boolean/face_split.h"
#include "boolean/fuse_groups.h"
#include "boolean/fuse_tree.h"
#include "boolean/line_surface.h"
#include "boolean/marching.h"
#include "boolean/model.h"
#include "boolean/pcurve_fit.h"
#include "boolean/surface_intersection.h"
#include "boolean/tolerance.h"
#include "boolean/uv_geometry.h"
#include "check/check_internal.h"
#include "csgtile/kernel/check.h"
#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/mass_properties.h"
#include "mass/mass_internal.h"
#include "mesh/polygon_triangulation.h"
#include "predicates/predicates.h"

namespace csgtile::kernel {

const char* boolean_op_name(BooleanOp op) {
  switch (op) {
    case BooleanOp::Fuse:
      return "fuse";
    case BooleanOp::Common:
      return "common";
    case BooleanOp::Cut:
      return "cut";
  }
  return "unknown";
}

namespace {

using namespace detail;

const char* surface_name(SurfaceKind k) {
  static const char* kNames[] = {"plane", "cylinder",  "cone",      "sphere",
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

// A face piece after splitting, with its fate.
struct Piece {
  int face;  // index into model.faces
  Region region;
  bool keep = false;
  bool flip = false;  // orientation reversed in the result (cut: B's pieces)
};

class BooleanEngine {
 public:
  BooleanEngine(const Shape& a, const Shape& b, BooleanOp op, const BooleanOptions& options)
      : a_(a), b_(b), op_(op), options_(options), model_(options.tolerance) {}

  /// Per face of the last result (child-map order): the input faces it comes from.
  std::vector<std::vector<FaceOrigin>> take_origins() { return std::move(origins_); }

  Result<Shape> run() {
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

  Result<Interference> interference() {
    if (auto s = import_operand(model_, a_, 0); !s.ok()) return s.error();
    first_b_face_ = model_.faces.size();
    if (auto s = import_operand(model_, b_, 1); !s.ok()) return s.error();
    if (first_b_face_ == 0 || first_b_face_ == model_.faces.size()) return Interference::Disjoint;
    // Vertices within tolerance of each other are one model vertex: one used by both
    // operands is a contact point.
    const std::vector<int> operand_of_vertex = operand_of_vertices();
    if (std::find(operand_of_vertex.begin(), operand_of_vertex.end(), 2) !=
        operand_of_vertex.end()) {
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

 private:
  // Cancelled once options_.interrupt has fired (interrupt.h), naming the operation's stage.
  Status interrupted(const char* stage) const {
    if (!options_.interrupt.fired()) return {};
    return options_.interrupt.error(std::string("while ") + stage + " (boolean " +
                                    boolean_op_name(op_) + ")");
  }

  // Edges of the two operands that coincide (touching solids) become one edge, so the
  // result shares them.
  void unify_shared_edges() {
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

  // A full sphere's (u, v) frame is free: choose its axis so that every section with the
  // other operand is a latitude or a meridian (whose pcurves are exact lines), and turn its
  // seam away from the meridian planes. Spheres cut by surfaces with no common axis keep
  // their frame (their sections then report Unsupported).
  void reframe_spheres() {
    const double tol = options_.tolerance;
    for (std::size_t f = 0; f < model_.faces.size(); ++f) {
      BFace& face = model_.faces[f];
      if (face.surface->kind() != SurfaceKind::Sphere || face.loops.size() != 1 ||
          face.loops[0].size() != 4)
        continue;
      const auto& sphere = static_cast<const SphereSurface&>(*face.surface);
      const Vec3 center = sphere.frame().origin;
      const double r = sphere.radius();
      // Constraints from the overlapping faces of the other operand.
      std::vector<Vec3> axes;  // must be the sphere's axis (sphere centres, revolution axes)
      std::vector<std::pair<Vec3, bool>> planes;  // normal, passes through the centre
      bool impossible = false;
      const std::size_t lo = face.operand == 0 ? first_b_face_ : 0;
      const std::size_t hi = face.operand == 0 ? model_.faces.size() : first_b_face_;
      BoundingBox box = face.box;
      box.enlarge(tol);
      for (std::size_t g = lo; g < hi; ++g) {
        if (!box.intersects(model_.faces[g].box)) continue;
        const Surface& other = *model_.faces[g].surface;
        switch (other.kind()) {
          case SurfaceKind::Plane: {
            const Frame& pf = static_cast<const PlaneSurface&>(other).frame();
            const double distance = std::abs((center - pf.origin).dot(pf.z));
            if (distance >= r - tol) break;  // misses the sphere or touches it at a point
            planes.emplace_back(pf.z, distance <= tol);
            break;
          }
          case SurfaceKind::Sphere: {
            const Vec3 d = static_cast<const SphereSurface&>(other).frame().origin - center;
            if (d.norm() > tol) axes.push_back(d.normalized());
            break;
          }
          case SurfaceKind::Cylinder:
          case SurfaceKind::Cone:
          case SurfaceKind::Torus: {
            const Frame& of = other.kind() == SurfaceKind::Cylinder
                                  ? static_cast<const CylinderSurface&>(other).frame()
                              : other.kind() == SurfaceKind::Cone
                                  ? static_cast<const ConeSurface&>(other).frame()
                                  : static_cast<const TorusSurface&>(other).frame();
            const Vec3 w = center - of.origin;
            if ((w - w.dot(of.z) * of.z).norm() > tol) impossible = true;
            axes.push_back(of.z);
            break;
          }
          default:
            impossible = true;
        }
      }
      if (impossible) {
        reframe_for_tracing(face, lo, hi);
        continue;
      }
      // Directions compared over the sphere (the tolerance model of the section code).
      const ToleranceModel across{tol, std::max(2.0 * r, tol)};
      auto compatible = [&](const Vec3& z) {
        for (const Vec3& a : axes) {
          if (!across.parallel(a, z)) return false;
        }
        for (const auto& [n, through_center] : planes) {
          const bool latitude = across.parallel(n, z);
          const bool meridian = through_center && across.perpendicular(n, z);
          if (!latitude && !meridian) return false;
        }
        return true;
      };
      std::vector<Vec3> candidates{sphere.frame().z};
      for (const Vec3& a : axes) candidates.push_back(a);
      for (const auto& pl : planes) candidates.push_back(pl.first);
      std::optional<Vec3> z;
      for (const Vec3& c : candidates) {
        if (compatible(c.normalized())) {
          z = c.normalized();
          break;
        }
      }
      if (!z) {
        reframe_for_tracing(face, lo, hi);
        continue;
      }
      // Seam direction: away from every meridian plane.
      const Frame base = Frame::from_z(center, *z, sphere.frame().x);
      double best_angle = 0, best_score = -1;
      for (int k = 0; k < 16; ++k) {
        const double phi = 0.3 + k * 0.39;  // not a simple fraction of π
        const Vec3 x = std::cos(phi) * base.x + std::sin(phi) * base.y;
        double score = 1.0;
        for (const auto& [n, through_center] : planes) {
          if (through_center && across.perpendicular(n, *z))
            score = std::min(score, std::abs(x.dot(n)));
        }
        if (score > best_score + kSeamPreference) {
          best_score = score;
          best_angle = phi;
        }
      }
      Frame frame;
      frame.origin = center;
      frame.z = *z;
      frame.x = std::cos(best_angle) * base.x + std::sin(best_angle) * base.y;
      frame.y = frame.z.cross(frame.x);
      rebuild_full_sphere(face, frame, r);
    }
  }

  // A full sphere whose sections will be traced (no common axis): its poles, where its
  // (u, v) parameters are singular, are turned as far as possible from the other operand's
  // faces it meets (measured to their bounding boxes), so that no traced section passes a pole.
  void reframe_for_tracing(BFace& face, std::size_t lo, std::size_t hi) {
    const auto& sphere = static_cast<const SphereSurface&>(*face.surface);
    const Vec3 center = sphere.frame().origin;
    const double r = sphere.radius();
    BoundingBox box = face.box;
    box.enlarge(options_.tolerance);
    auto box_distance = [](const BoundingBox& b, const Vec3& p) {
      return (p - p.cwiseMax(b.min).cwiseMin(b.max)).norm();
    };
    const Vec3 directions[] = {{0, 0, 1},  {1, 0, 0},  {0, 1, 0}, {1, 1, 1},  {1, -1, 1},
                               {-1, 1, 1}, {1, 1, -1}, {1, 1, 0}, {1, -1, 0}, {1, 0, 1},
                               {1, 0, -1}, {0, 1, 1},  {0, 1, -1}};
    std::vector<Vec3> candidates{sphere.frame().z};  // the current frame wins ties
    for (const Vec3& d : directions) candidates.push_back(d.normalized());
    Vec3 best = sphere.frame().z;
    double best_score = -1.0;
    for (const Vec3& z : candidates) {
      double score = std::numeric_limits<double>::infinity();
      for (const Vec3& pole : {Vec3(center + r * z), Vec3(center - r * z)}) {
        for (std::size_t g = lo; g < hi; ++g) {
          if (!box.intersects(model_.faces[g].box)) continue;
          score = std::min(score, box_distance(model_.faces[g].box, pole));
        }
      }
      if (score > best_score) {
        best_score = score;
        best = z;
      }
    }
    rebuild_full_sphere(face, Frame::from_z(center, best, sphere.frame().x), r);
  }

  void rebuild_full_sphere(BFace& face, const Frame& frame, double r) {
    constexpr double kHalfPi = std::numbers::pi / 2, kTwoPi = 2 * std::numbers::pi;
    face.surface = std::make_shared<SphereSurface>(frame, r);
    const int south = model_.vertex_at(frame.origin - r * frame.z);
    const int north = model_.vertex_at(frame.origin + r * frame.z);
    Frame meridian;
    meridian.origin = frame.origin;
    meridian.x = frame.x;
    meridian.y = frame.z;
    meridian.z = meridian.x.cross(meridian.y);
    BEdge seam;
    seam.curve = std::make_shared<CircleCurve>(meridian, r);
    seam.t0 = -kHalfPi;
    seam.t1 = kHalfPi;
    seam.v0 = south;
    seam.v1 = north;
    seam.tolerance = options_.tolerance;
    seam.seam = true;
    BEdge pole_s, pole_n;
    pole_s.t0 = pole_n.t0 = 0;
    pole_s.t1 = pole_n.t1 = kTwoPi;
    pole_s.v0 = pole_s.v1 = south;
    pole_n.v0 = pole_n.v1 = north;
    pole_s.tolerance = pole_n.tolerance = options_.tolerance;
    const int es = model_.add_edge(seam), ps = model_.add_edge(pole_s),
              pn = model_.add_edge(pole_n);
    face.loops = {{{ps, true, std::make_shared<Line2d>(Vec2(0, -kHalfPi), Vec2(1, 0))},
                   {es, true, std::make_shared<Line2d>(Vec2(kTwoPi, 0), Vec2(0, 1))},
                   {pn, false, std::make_shared<Line2d>(Vec2(0, kHalfPi), Vec2(1, 0))},
                   {es, false, std::make_shared<Line2d>(Vec2(0, 0), Vec2(0, 1))}}};
  }

  // Per model vertex: the operand whose boundary edges use it (0 or 1), 2 when both do (a
  // contact point), -1 when none does.
  std::vector<int> operand_of_vertices() const {
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

  // A vertex of one operand lying inside an edge of the other (touching or overlapping
  // boundaries) splits that edge there.
  void split_at_touching_vertices() {
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

  double uv_margin(std::size_t face) const {
    const FacePolygon& p = polygons_[face];
    return uv_slack(std::max(p.max.x() - p.min.x(), p.max.y() - p.min.y()));
  }

  // Crossings of a curve (pcurve `pc` on face f) with f's boundary: (curve parameter, edge,
  // edge parameter) triples.
  struct Hit {
    double t;
    int edge;
    double s;
  };
  void boundary_hits(std::size_t f, const Curve2d& pc, double t0, double t1, int skip_edge,
                     std::vector<Hit>& hits) {
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

  // Crossing boxes of face f's boundary uses (loop order), kept while intersect_faces runs
  // (the loops do not change before split_edges).
  const std::vector<CrossingBox>& boundary_boxes(std::size_t f) {
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

  // Adds the part of a curve lying inside both faces (fa, fb) as section edges (or, with
  // `existing` >= 0, marks an existing edge of fb's boundary as lying in fa).
  // Traced sections bring their pcurves (`hint_a` on fa, `hint_b` on fb) and the tolerance
  // their edges need; closed-form ones get exact fitted pcurves and the model tolerance.
  Status add_section(std::size_t fa, std::size_t fb, CurvePtr curve, double t0, double t1,
                     int existing, const Curve2dPtr& hint_a = nullptr,
                     const Curve2dPtr& hint_b = nullptr, double edge_tolerance = 0.0) {
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
    Curve2dPtr pa =
        hint_a ? hint_a : fit_pcurve(*curve, t0, t1, *model_.faces[fa].surface, fit_tol);
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
      if (existing < 0 && shift_a.has_value() != shift_b.has_value()) {
        // The piece runs inside one face along an edge of the other (an edge lying in a
        // face): that edge, or the part of it the piece covers, splits the first face.
        const std::size_t inside = shift_a ? fa : fb, along = shift_a ? fb : fa;
        const int e = boundary_edge_through(along, curve->point(mid));
        if (e >= 0) add_edge_part(inside, e, curve->point(c0), curve->point(c1), curve->point(mid));
        continue;
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

  // Where boundary edge `e` pierces `surface`, by Newton's method on the signed distance from
  // e(s) to the surface, from s: the parameter, or nullopt when the edge grazes the surface
  // there or the iteration does not settle.
  std::optional<double> pierce_parameter(const BEdge& e, double s, const Surface& surface) const {
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

  // A traced section (a polyline whose chords stay within its deviation of the exact curve)
  // crosses a face boundary where its chord does: up to the deviation away from the point
  // where the boundary edge pierces the other face's surface, the point every other section
  // ending on that edge there (a neighbouring face's, a closed-form one) ends at as well. The
  // pieces would miss each other by micrometres and leave open ends and tiny edges. So each
  // crossing moves to the pierce point, which becomes a vertex of the polyline and of both
  // pcurves, and the boundary edge is split there. `reach` bounds the move (a pierce point
  // farther than that is another crossing: the hit stays as found). Hits [0, hits_on_a) lie
  // on fa's boundary (pierce fb's surface), the rest on fb's (pierce fa's).
  void snap_traced_crossings(std::size_t fa, std::size_t fb, CurvePtr& curve, Curve2dPtr& pa,
                             Curve2dPtr& pb, double& t0, double& t1, std::vector<Hit>& hits,
                             std::size_t hits_on_a, double reach) {
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
      auto it = std::upper_bound(
          knots.begin(), knots.end(), t,
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

  // A boundary edge of face f passing through p (within tolerance), or -1.
  int boundary_edge_through(std::size_t f, const Vec3& p) {
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

  // Adds the part of edge `e` between the points p0 and p1 to face f as a section edge,
  // splitting `e` at p0 and p1 when they are inside it.
  // `through` is a point of the part: on a closed edge (a circle from its vertex round to
  // it) it tells which of the two arcs between p0 and p1 is meant; an arc across the edge's
  // start vertex is added as its two pieces.
  void add_edge_part(std::size_t f, int e_id, const Vec3& p0, const Vec3& p1, const Vec3& through) {
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

  // The part [a, b] of edge `e_id` as a section edge of face f (see add_edge_part).
  void add_edge_range(std::size_t f, int e_id, double a, double b) {
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
    auto pc = fit_pcurve(*e.curve, e.t0, e.t1, *model_.faces[f].surface,
                         fit_tolerance(options_.tolerance));
    if (!pc) return;
    auto shift =
        polygons_[f].shift_inside(pc->point(0.5 * (a + b)), uv_margin(f) * kInsideUvSlacks);
    if (!shift) return;
    pc = shift_pcurve(pc, *shift);
    if (a <= e.t0 + span && b >= e.t1 - span) {
      add_extra(f, e_id, pc);
    } else {
      pending_partials_.push_back({f, e_id, a, b, pc});
    }
  }

  // The pcurve for `edge` on face f: the section pcurve when the edge is on the section's
  // curve, else refitted on the edge's own curve.
  Curve2dPtr refit_for(int edge, std::size_t f, const Curve2dPtr& pc, const CurvePtr& curve) {
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

  void add_extra(std::size_t f, int edge, Curve2dPtr pcurve) {
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

  // An existing edge between v0 and v1 through all of `probes`, or -1.
  // A closed boundary edge of face f that runs along the whole closed curve(t0..t1) (each
  // within tolerance of the other at 8 samples), or -1.
  int closed_boundary_edge_along(std::size_t f, const Curve& curve, double t0, double t1) {
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

  int find_edge(int v0, int v1, const std::vector<Vec3>& probes) {
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

  // The vertex at curve(t): an existing vertex within tolerance, else new; every boundary
  // edge hit there gets a split.
  int vertex_on_curve(const Curve& curve, double t, const std::vector<Hit>& hits) {
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

  // Whether face f's boundary (its vertices and the middles of its edges) lies on face g's
  // surface within the tolerance of each edge.
  bool lies_on(std::size_t f, std::size_t g) const {
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

  Status intersect_faces() {
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
          ssi =
              intersect_surfaces(*model_.faces[fa].surface, *model_.faces[fb].surface, whole, tol);
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

  // Section curves of one face may cross each other inside it (the two ellipses of a
  // Steinmetz pair meet on the axes): both edges are split at each crossing.
  void split_crossing_sections() {
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

  // Applies the splits gathered on edges: each split edge becomes a chain of sub-edges, and
  // every use of it (boundary loops, extras) the chain of sub-uses.
  void split_edges() {
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

  Status split_faces(std::vector<Piece>& pieces) {
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

  // Points inside a piece: in its largest triangles (up to `count`), at uneven barycentric
  // weights so that they do not fall on the lines and corners other geometry is built on
  // (a centroid of a split face can be exactly the end of the other operand's edge). The
  // triangles are those of the piece's sampled outline, whose chords of curved pcurves can
  // cut across a thin piece (an annulus a few hundredths of its radius wide): each point is
  // checked against the piece's arcs, and the outline is sampled finer until enough points
  // pass (a point outside the piece would classify a neighbour instead).
  std::vector<Vec3> interior_points(const Piece& piece, std::size_t count) {
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

  Vec3 outward_normal(const Piece& piece, const Vec3& p) {
    const BFace& f = model_.faces[static_cast<std::size_t>(piece.face)];
    const Vec2 uv = f.surface->closest_parameters(p);
    const Vec3 n = f.surface->normal(uv.x(), uv.y());
    return f.reversed ? Vec3(-n) : n;
  }

  Status classify(std::vector<Piece>& pieces) {
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

  Result<Shape> build(std::vector<Piece>& pieces);

  struct PendingPartial {
    std::size_t face;
    int edge;
    double t0, t1;
    Curve2dPtr pcurve;
  };

  Shape a_, b_;
  BooleanOp op_;
  BooleanOptions options_;
  BModel model_;
  std::size_t first_b_face_ = 0;
  std::vector<std::vector<FaceOrigin>> origins_;  // set by build()
  std::vector<FacePolygon> polygons_;
  std::vector<std::pair<std::size_t, std::size_t>> coincident_;
  std::vector<PendingPartial> pending_partials_;
  std::vector<std::vector<CrossingBox>> boundary_boxes_;  // see boundary_boxes()
};

}  // namespace

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
  // 1. Pieces of one periodic face that meet across its seam become one face.
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
          if (!model_.edges[static_cast<std::size_t>(u.edge)].seam) edges_i.insert(u.edge);
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
            if (!model_.edges[static_cast<std::size_t>(u.edge)].seam) continue;
            auto other = find_use(faces[j], u.edge, !u.forward);
            if (!other) continue;
            // Shift j's pcurves by whole periods so the shared seam coincides.
            const BEdge& e = model_.edges[static_cast<std::size_t>(u.edge)];
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
          const BEdge& e = model_.edges[static_cast<std::size_t>(u.edge)];
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
  // 2. Faces on one plane meeting along an edge are one face (the edge bounds nothing).
  BoundingBox extent;
  for (const BFace& f : model_.faces) extent.add(f.box);
  const ToleranceModel planes{tol, std::max(extent.empty() ? 0.0 : extent.size().norm(), tol)};
  // The uses of each edge by the live faces (face ascending, then loop order), as the scan
  // below reads them; after each pass only the lists of edges the changed faces used before or
  // use now are brought up to date (a full rebuild per merge made this step quadratic).
  using UseList = std::vector<std::pair<std::size_t, bool>>;
  std::vector<UseList> uses(model_.edges.size());
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
            const BEdge& e = model_.edges[static_cast<std::size_t>(w.edge)];
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
  // 3. Straight edges meeting end to end at a vertex nothing else uses become one edge.
  changed = true;
  while (changed) {
    changed = false;
    std::map<int, std::set<int>> vertex_edges;
    for (const RFace& f : faces) {
      if (!f.alive) continue;
      for (const BLoop& loop : f.loops) {
        for (const BUse& u : loop) {
          const BEdge& e = model_.edges[static_cast<std::size_t>(u.edge)];
          vertex_edges[e.v0].insert(u.edge);
          vertex_edges[e.v1].insert(u.edge);
        }
      }
    }
    for (const auto& [v, edges] : vertex_edges) {
      if (edges.size() != 2) continue;
      const int e1 = *edges.begin(), e2 = *edges.rbegin();
      const BEdge& x = model_.edges[static_cast<std::size_t>(e1)];
      const BEdge& y = model_.edges[static_cast<std::size_t>(e2)];
      if (x.degenerate() || y.degenerate() || x.curve->kind() != CurveKind::Line ||
          y.curve->kind() != CurveKind::Line)
        continue;
      const int xa = x.v0 == v ? x.v1 : x.v0, yb = y.v0 == v ? y.v1 : y.v0;
      if (xa == yb) continue;
      const Vec3 pa = model_.vertices[static_cast<std::size_t>(xa)].point;
      const Vec3 pb = model_.vertices[static_cast<std::size_t>(yb)].point;
      const Vec3 pv = model_.vertices[static_cast<std::size_t>(v)].point;
      const Vec3 d = pb - pa;
      if ((pv - pa).cross(d).norm() > tol * d.norm()) continue;
      BEdge merged;
      merged.curve = std::make_shared<LineCurve>(pa, d);
      merged.t0 = 0;
      merged.t1 = d.norm();
      merged.v0 = xa;
      merged.v1 = yb;
      merged.tolerance = std::max(x.tolerance, y.tolerance);
      const int id = model_.add_edge(std::move(merged));
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
            const bool starts_at_a = use_start(model_, u) == xa || use_start(model_, u) == yb;
            if (!starts_at_a) continue;  // the second half: dropped, the first stands for both
            const bool forward = use_start(model_, u) == xa;
            const BEdge& m = model_.edges[static_cast<std::size_t>(id)];
            const BEdge& old = model_.edges[static_cast<std::size_t>(u.edge)];
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

  // 4. Shapes: vertices, edges and faces, shared by index.
  std::vector<double> vertex_tol(model_.vertices.size(), tol);
  std::set<int> used_edges;
  for (const RFace& f : faces) {
    if (!f.alive) continue;
    for (const BLoop& loop : f.loops) {
      for (const BUse& u : loop) used_edges.insert(u.edge);
    }
  }
  for (int id : used_edges) {
    const BEdge& e = model_.edges[static_cast<std::size_t>(id)];
    for (int end = 0; end < 2; ++end) {
      const int v = end == 0 ? e.v0 : e.v1;
      double gap = 0;
      if (!e.degenerate())
        gap = (e.curve->point(end == 0 ? e.t0 : e.t1) -
               model_.vertices[static_cast<std::size_t>(v)].point)
                  .norm();
      vertex_tol[static_cast<std::size_t>(v)] =
          std::max({vertex_tol[static_cast<std::size_t>(v)], gap * 1.01, e.tolerance});
    }
  }
  std::map<int, Shape> vertex_shapes, edge_shapes;
  auto vertex_shape = [&](int v) -> Result<Shape> {
    if (auto it = vertex_shapes.find(v); it != vertex_shapes.end()) return it->second;
    auto s = ShapeFactory::vertex(model_.vertices[static_cast<std::size_t>(v)].point,
                                  vertex_tol[static_cast<std::size_t>(v)]);
    if (s.ok()) vertex_shapes.emplace(v, s.value());
    return s;
  };
  auto edge_shape = [&](int id) -> Result<Shape> {
    if (auto it = edge_shapes.find(id); it != edge_shapes.end()) return it->second;
    const BEdge& e = model_.edges[static_cast<std::size_t>(id)];
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
  std::vector<Shape> face_shapes;
  std::vector<std::size_t> face_of_shape;
  for (std::size_t i = 0; i < faces.size(); ++i) {
    const RFace& f = faces[i];
    if (!f.alive || f.loops.empty()) continue;
    std::vector<Shape> wires;
    std::vector<std::vector<Curve2dPtr>> pcurves;
    // Outer loop first.
    std::vector<BLoop> loops = f.loops;
    std::stable_sort(loops.begin(), loops.end(), [&](const BLoop& x, const BLoop& y) {
      return loop_area2(model_, x) > loop_area2(model_, y);
    });
    for (const BLoop& loop : loops) {
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
    face_shapes.push_back(
        face.value().oriented(f.reversed ? Orientation::Reversed : Orientation::Forward));
    face_of_shape.push_back(i);
  }

  // 5. Shells: faces joined through edges that exactly two faces use (an edge shared by
  // four faces is where two solids touch: it joins nothing).
  std::vector<std::size_t> parent(face_shapes.size());
  std::iota(parent.begin(), parent.end(), 0);
  std::function<std::size_t(std::size_t)> root = [&](std::size_t x) {
    return parent[x] == x ? x : parent[x] = root(parent[x]);
  };
  std::map<int, std::vector<std::size_t>> edge_users;
  for (std::size_t k = 0; k < face_shapes.size(); ++k) {
    std::set<int> mine;
    for (const BLoop& loop : faces[face_of_shape[k]].loops) {
      for (const BUse& u : loop) {
        if (!model_.edges[static_cast<std::size_t>(u.edge)].degenerate()) mine.insert(u.edge);
      }
    }
    for (int e : mine) edge_users[e].push_back(k);
  }
  for (const auto& [e, users] : edge_users) {
    if (users.size() == 2) parent[root(users[0])] = root(users[1]);
  }
  std::map<std::size_t, std::vector<Shape>> groups;
  for (std::size_t k = 0; k < face_shapes.size(); ++k) groups[root(k)].push_back(face_shapes[k]);
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
  std::vector<std::pair<Shape, double>> known_volumes;  // solids whose volume is measured
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
  auto result = ShapeFactory::compound(std::move(solids));
  if (!result.ok()) return result;
  // Face history: each face of the result (child-map order) with the input faces it holds.
  const ShapeIndex result_faces = map_child_shapes(result.value(), ShapeKind::Face);
  origins_.assign(result_faces.size(), {});
  for (std::size_t k = 0; k < face_shapes.size(); ++k) {
    const std::size_t at = result_faces.find(face_shapes[k]);
    if (at != ShapeIndex::npos) origins_[at] = faces[face_of_shape[k]].origins;
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

const char* interference_name(Interference i) {
  switch (i) {
    case Interference::Disjoint:
      return "disjoint";
    case Interference::BoundariesMeet:
      return "boundaries_meet";
    case Interference::Nested:
      return "nested";
  }
  return "?";
}

Result<Interference> solid_interference(const Shape& a, const Shape& b,
                                        const BooleanOptions& options) {
  if (a.is_null() || b.is_null())
    return Error{ErrorCode::InvalidArgument, "solid_interference: null shape"};
  BoundingBox ba = bounding_box(a), bb = bounding_box(b);
  ba.enlarge(options.tolerance);
  if (!ba.intersects(bb)) return Interference::Disjoint;
  auto pa = detail::prepare_argument(a, options);
  if (!pa.ok()) return pa.error();
  auto pb = detail::prepare_argument(b, options);
  if (!pb.ok()) return pb.error();
  return detail::run_interference(pa.value().shape, pb.value().shape, options);
}

namespace detail {

Result<Interference> run_interference(const Shape& a, const Shape& b,
                                      const BooleanOptions& options) {
  return BooleanEngine(a, b, BooleanOp::Common, options).interference();
}

Result<Shape> run_engine(const Shape& a, const Shape& b, BooleanOp op,
                         const BooleanOptions& options,
                         std::vector<std::vector<FaceOrigin>>* origins) {
  BooleanEngine engine(a, b, op, options);
  auto shape = engine.run();
  if (shape.ok() && origins != nullptr) *origins = engine.take_origins();
  return shape;
}

}  // namespace detail

Result<Shape> boolean_operation(const Shape& a, const Shape& b, BooleanOp op,
                                const BooleanOptions& options) {
  auto pa = detail::prepare_argument(a, options);
  if (!pa.ok()) return pa.error();
  auto pb = detail::prepare_argument(b, options);
  if (!pb.ok()) return pb.error();
  return detail::run_engine(pa.value().shape, pb.value().shape, op, options, nullptr);
}

Result<BooleanResult> boolean_operation_with_history(const Shape& a, const Shape& b, BooleanOp op,
                                                     const BooleanOptions& options) {
  auto pa = detail::prepare_argument(a, options);
  if (!pa.ok()) return pa.error();
  auto pb = detail::prepare_argument(b, options);
  if (!pb.ok()) return pb.error();
  BooleanResult out;
  auto shape = detail::run_engine(pa.value().shape, pb.value().shape, op, options, &out.origins);
  if (!shape.ok()) return shape.error();
  out.shape = shape.value();
  detail::restate_origins(out.origins, pa.value(), pb.value());
  return out;
}

namespace detail {

std::vector<std::vector<std::size_t>> fuse_groups(const std::vector<Shape>& shapes,
                                                  double tolerance) {
  const std::size_t n = shapes.size();
  std::vector<BoundingBox> boxes(n);
  for (std::size_t i = 0; i < n; ++i) {
    boxes[i] = bounding_box(shapes[i]);
    boxes[i].enlarge(tolerance);
  }
  // Sweep along x: candidate pairs are boxes whose x-intervals overlap.
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return boxes[a].min.x() < boxes[b].min.x() || (boxes[a].min.x() == boxes[b].min.x() && a < b);
  });
  std::vector<std::size_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  std::function<std::size_t(std::size_t)> root = [&](std::size_t x) {
    return parent[x] == x ? x : parent[x] = root(parent[x]);
  };
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t a = order[i];
    for (std::size_t j = i + 1; j < n && boxes[order[j]].min.x() <= boxes[a].max.x(); ++j) {
      const std::size_t b = order[j];
      if (boxes[a].intersects(boxes[b])) {
        const std::size_t ra = root(a), rb = root(b);
        parent[std::max(ra, rb)] = std::min(ra, rb);
      }
    }
  }
  std::map<std::size_t, std::vector<std::size_t>> groups;  // keyed by smallest member: input order
  for (std::size_t i = 0; i < n; ++i) groups[root(i)].push_back(i);
  std::vector<std::vector<std::size_t>> out;
  out.reserve(groups.size());
  for (auto& [r, members] : groups) out.push_back(std::move(members));
  return out;
}

}  // namespace detail

Result<Shape> boolean_fuse_all(const std::vector<Shape>& inputs, const BooleanOptions& options) {
  // Arguments prepared once; partial results are engine results, ready as they are.
  std::vector<Shape> shapes;
  shapes.reserve(inputs.size());
  for (const Shape& s : inputs) {
    auto p = detail::prepare_argument(s, options);
    if (!p.ok()) return p.error();
    shapes.push_back(p.value().shape);
  }
  std::vector<Shape> out;
  for (const auto& members : detail::fuse_groups(shapes, options.tolerance)) {
    std::vector<Shape> group;
    for (std::size_t i : members) group.push_back(shapes[i]);
    if (group.size() == 1) {
      for (const Shape& s : Explorer(group[0], ShapeKind::Solid)) out.push_back(s);
      continue;
    }
    // A balanced tree of fuses (boolean/fuse_tree.h).
    auto fused = detail::fuse_tree(group, [&](const Shape& x, const Shape& y) {
      return detail::run_engine(x, y, BooleanOp::Fuse, options, nullptr);
    });
    if (!fused.ok()) return fused;
    for (const Shape& s : Explorer(fused.value(), ShapeKind::Solid)) out.push_back(s);
  }
  return ShapeFactory::compound(std::move(out));
}

Result<Shape> boolean_fold(const std::vector<Shape>& shapes, BooleanOp op,
                           const BooleanOptions& options) {
  if (shapes.empty()) return ShapeFactory::compound({});
  auto first = detail::prepare_argument(shapes.front(), options);
  if (!first.ok()) return first.error();
  Shape acc = first.value().shape;
  for (std::size_t i = 1; i < shapes.size(); ++i) {
    auto next = detail::prepare_argument(shapes[i], options);
    if (!next.ok()) return next.error();
    // An empty intermediate result: common stays empty, cut stays empty.
    if (map_child_shapes(acc, ShapeKind::Solid).size() == 0) {
      if (op != BooleanOp::Fuse) return acc;
      acc = next.value().shape;
      continue;
    }
    auto r = detail::run_engine(acc, next.value().shape, op, options, nullptr);
    if (!r.ok()) return r;
    acc = r.value();
  }
  if (acc.kind() != ShapeKind::Compound) return ShapeFactory::compound({acc});
  return acc;
}

}  // namespace csgtile::kernel
