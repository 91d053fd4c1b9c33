#include "csgtile/kernel/check.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <unordered_map>

#include "check/check_internal.h"
#include "csgtile/kernel/explorer.h"
#include "mass/mass_internal.h"

namespace csgtile::kernel {

const char* check_status_name(CheckStatus status) {
  switch (status) {
    case CheckStatus::NullShape:
      return "null_shape";
    case CheckStatus::InvalidLocation:
      return "invalid_location";
    case CheckStatus::ToleranceOrder:
      return "tolerance_order";
    case CheckStatus::VertexOffCurve:
      return "vertex_off_curve";
    case CheckStatus::EdgeOffFace:
      return "edge_off_face";
    case CheckStatus::OpenWire:
      return "open_wire";
    case CheckStatus::SelfIntersection:
      return "self_intersection";
    case CheckStatus::FreeEdge:
      return "free_edge";
    case CheckStatus::OpenShell:
      return "open_shell";
    case CheckStatus::EdgeSameOrientationTwice:
      return "edge_same_orientation_twice";
    case CheckStatus::NonManifoldEdge:
      return "non_manifold_edge";
    case CheckStatus::BadFaceOrientation:
      return "bad_face_orientation";
    case CheckStatus::EulerPoincareMismatch:
      return "euler_poincare_mismatch";
  }
  return "unknown";
}

bool CheckReport::has(CheckStatus status) const {
  return std::any_of(issues.begin(), issues.end(),
                     [&](const CheckIssue& i) { return i.status == status; });
}

namespace {

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

// Start and end vertex of an edge as oriented in its wire.
Shape start_vertex(const Shape& edge) {
  return edge.child(edge.orientation() == Orientation::Reversed ? 1 : 0);
}
Shape end_vertex(const Shape& edge) {
  return edge.child(edge.orientation() == Orientation::Reversed ? 0 : 1);
}

// Side of q with respect to the line o → p: +1 left, −1 right, 0 on it (floating point).
int orient(const Vec2& o, const Vec2& p, const Vec2& q) {
  const double v = (p.x() - o.x()) * (q.y() - o.y()) - (p.y() - o.y()) * (q.x() - o.x());
  return (v > 0) - (v < 0);
}

// Proper crossing of two segments (touching at endpoints does not count: loops meet at
// shared vertices).
bool segments_cross(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) {
  const int o1 = orient(a, b, c), o2 = orient(a, b, d), o3 = orient(c, d, a), o4 = orient(c, d, b);
  return o1 * o2 < 0 && o3 * o4 < 0;
}

// A side of a face's sampled boundary polygon: the chord of its pcurve over [t0, t1]
// (walking direction), or an exactly straight piece (curve null).
struct Chord {
  Vec2 a, b;
  const Curve2d* curve = nullptr;
  double t0 = 0, t1 = 0;
};

// Refinements a face's crossing test may spend confirming crossings of chords.
constexpr int kChordRefinements = 4096;
// Halvings of a chord at most (its bulge then far below any tolerance).
constexpr int kChordDepth = 40;

// Whether the curves behind two chords properly cross. Chords of curved pcurves are halved
// while they cross: a crossing of the sampled polygon that is only the bulge of an arc past a
// nearby straight side (a box edge piercing a cap disc just inside its rim) disappears, a real
// one persists down to the depth. Spending the budget counts as crossing.
bool chords_cross(const Chord& x, const Chord& y, int depth, int& budget) {
  if (!segments_cross(x.a, x.b, y.a, y.b)) return false;
  if ((x.curve == nullptr && y.curve == nullptr) || depth == 0 || --budget < 0) return true;
  auto halves = [](const Chord& c) -> std::vector<Chord> {
    if (c.curve == nullptr) return {c};
    const double tm = 0.5 * (c.t0 + c.t1);
    const Vec2 m = c.curve->point(tm);
    return {Chord{c.a, m, c.curve, c.t0, tm}, Chord{m, c.b, c.curve, tm, c.t1}};
  };
  for (const Chord& hx : halves(x)) {
    for (const Chord& hy : halves(y)) {
      if (chords_cross(hx, hy, depth - 1, budget)) return true;
    }
  }
  return false;
}

class Checker {
 public:
  Checker(CheckReport& report, const std::vector<std::pair<Shape, double>>& known_volumes)
      : report_(report) {
    for (const auto& [solid, v] : known_volumes)
      known_volumes_.emplace(solid.body_id(), std::pair{solid, v});
  }

  void run(const Shape& root) {
    if (root.is_null()) {
      add(CheckStatus::NullShape, "the shape is null");
      return;
    }
    check_locations(root);
    const ShapeIndex edges = map_child_shapes(root, ShapeKind::Edge);
    for (std::size_t i = 0; i < edges.size(); ++i) check_edge(edges[i], i);
    const ShapeIndex faces = map_child_shapes(root, ShapeKind::Face);
    for (std::size_t i = 0; i < faces.size(); ++i) check_face(faces[i], i);
    const ShapeIndex solids = map_child_shapes(root, ShapeKind::Solid);
    for (std::size_t i = 0; i < solids.size(); ++i) check_solid(solids[i], i);
  }

 private:
  void add(CheckStatus status, std::string message) {
    report_.issues.push_back({status, std::move(message)});
  }

  static bool similarity(const Location& l) {
    const double dev = (l.rotation().transpose() * l.rotation() - Eigen::Matrix3d::Identity())
                           .cwiseAbs()
                           .maxCoeff();
    return !(!(l.scale() > 0) || dev > 1e-9 || l.rotation().determinant() < 0);
  }

  void check_locations(const Shape& root) {
    std::vector<Shape> stack{root};
    std::size_t visited = 0;
    while (!stack.empty() && visited < 10'000'000) {
      Shape s = std::move(stack.back());
      stack.pop_back();
      ++visited;
      const Location& l = s.location();
      // The identity (almost every child reference) is a similarity by construction.
      if (!l.is_identity() && !similarity(l)) {
        add(CheckStatus::InvalidLocation, std::string("a ") + shape_kind_name(s.kind()) +
                                              " has a location that is not a similarity");
        return;
      }
      for (std::size_t i = 0; i < s.child_count(); ++i) {
        if (s.body().children()[i].is_null()) {
          add(CheckStatus::NullShape,
              std::string("a ") + shape_kind_name(s.kind()) + " has a null child");
          return;
        }
        stack.push_back(s.child(i));
      }
    }
  }

  void check_edge(const Shape& edge, std::size_t index) {
    const EdgeData& d = *edge.body().edge();
    const double et = tolerance(edge);
    const std::string name = "edge " + std::to_string(index);
    for (std::size_t k = 0; k < edge.child_count(); ++k) {
      const Shape v = edge.child(k);
      const double vt = tolerance(v);
      if (vt < et) {
        add(CheckStatus::ToleranceOrder,
            name + ": tolerance " + num(et) + " exceeds its vertex tolerance " + num(vt));
      }
      if (d.degenerate()) continue;
      const double t = k == 0 ? d.first : d.last;
      const Vec3 p = edge.location().apply_point(d.curve->point(t));
      const double gap = (p - vertex_point(v)).norm();
      if (gap > vt * (1 + 1e-9) + 1e-12) {
        add(CheckStatus::VertexOffCurve,
            name + ": end " + std::to_string(k) + " is " + num(gap) + " from its vertex");
      }
    }
  }

  void check_face(const Shape& face, std::size_t index) {
    const FaceData& d = *face.body().face();
    const std::string name = "face " + std::to_string(index);
    const double ft = tolerance(face);
    const Shape body_face = face.oriented(Orientation::Forward);
    std::vector<Chord> chords;
    for (std::size_t w = 0; w < body_face.child_count(); ++w) {
      const Shape wire = body_face.child(w);
      const std::size_t first_chord = chords.size();
      const std::size_t n = wire.child_count();
      for (std::size_t e = 0; e < n; ++e) {
        const Shape edge = wire.child(e);
        const EdgeData& ed = *edge.body().edge();
        const double et = tolerance(edge);
        if (et < ft) {
          add(CheckStatus::ToleranceOrder,
              name + ": tolerance " + num(ft) + " exceeds an edge tolerance " + num(et));
        }
        if (!end_vertex(edge).is_same(start_vertex(wire.child((e + 1) % n)))) {
          add(CheckStatus::OpenWire,
              name + ": wire " + std::to_string(w) + " is open after edge " + std::to_string(e));
        }
        // The pcurve must follow the 3D curve within the edge tolerance.
        const Curve2d& pc = *d.pcurves[w][e];
        const int samples = pc.kind() == Curve2dKind::Line && !ed.degenerate() &&
                                    ed.curve->kind() == CurveKind::Line
                                ? 2
                                : 16;
        double worst = 0.0;
        std::vector<Vec2> pts;
        std::vector<double> ts;
        for (int k = 0; k <= samples; ++k) {
          const double t = ed.first + (ed.last - ed.first) * k / samples;
          const Vec2 uv = pc.point(t);
          pts.push_back(uv);
          ts.push_back(t);
          const Vec3 on_surface = face.location().apply_point(d.surface->point(uv.x(), uv.y()));
          const Vec3 on_curve = ed.degenerate() ? vertex_point(edge.child(0))
                                                : edge.location().apply_point(ed.curve->point(t));
          worst = std::max(worst, (on_surface - on_curve).norm());
        }
        if (worst > et * (1 + 1e-9) + 1e-12) {
          add(CheckStatus::EdgeOffFace, name + ": an edge strays " + num(worst) +
                                            " from the surface (tolerance " + num(et) + ")");
        }
        if (edge.orientation() == Orientation::Reversed) {
          std::reverse(pts.begin(), pts.end());
          std::reverse(ts.begin(), ts.end());
        }
        // Polylines are sampled at points that need not be their vertices: no straight chords.
        const bool straight = pc.kind() == Curve2dKind::Line;
        for (std::size_t k = 0; k + 1 < pts.size(); ++k) {
          chords.push_back({pts[k], pts[k + 1], straight ? nullptr : &pc, ts[k], ts[k + 1]});
        }
      }
      // Each edge's last chord ends where the next edge's first one starts: consecutive sides
      // share their point exactly, as the sampled polygon's do.
      for (std::size_t k = first_chord; k < chords.size(); ++k) {
        chords[k].b = chords[k + 1 < chords.size() ? k + 1 : first_chord].a;
      }
    }
    check_loops_cross(chords, name);
  }

  // The sampled loops' sides pairwise (O(k²)); crossings confirmed by chords_cross. A pair
  // whose second side has both ends on one side of the first's line is not asked: that is
  // segments_cross's first test, on which chords_cross would return false at once (the same
  // verdicts, the same refinement budget). Consecutive sides share their point exactly, so
  // its side is reused.
  void check_loops_cross(const std::vector<Chord>& chords, const std::string& name) {
    int budget = kChordRefinements;
    for (std::size_t i = 0; i < chords.size(); ++i) {
      const Chord& x = chords[i];
      int end_side = 0;
      for (std::size_t j = i + 1; j < chords.size(); ++j) {
        const Chord& y = chords[j];
        const int start_side =
            j > i + 1 && y.a == chords[j - 1].b ? end_side : orient(x.a, x.b, y.a);
        end_side = orient(x.a, x.b, y.b);
        if (start_side * end_side >= 0) continue;
        if (chords_cross(x, y, kChordDepth, budget)) {
          add(CheckStatus::SelfIntersection, name + ": its boundary loops cross");
          return;
        }
      }
    }
  }

  void check_solid(const Shape& solid, std::size_t index) {
    const std::string name = "solid " + std::to_string(index);
    for (std::size_t s = 0; s < solid.child_count(); ++s) {
      const Shape shell = solid.child(s);
      struct Use {
        int forward = 0, reversed = 0;
      };
      ShapeIndex edge_keys;
      std::vector<Use> uses;
      for (const Shape& face : Explorer(shell, ShapeKind::Face)) {
        for (const Shape& edge : Explorer(face, ShapeKind::Edge)) {
          if (edge.body().edge()->degenerate()) continue;
          const std::size_t k = edge_keys.add(edge);
          if (k == uses.size()) uses.emplace_back();
          if (edge.orientation() == Orientation::Forward) ++uses[k].forward;
          if (edge.orientation() == Orientation::Reversed) ++uses[k].reversed;
        }
      }
      bool closed = true;
      for (std::size_t k = 0; k < uses.size(); ++k) {
        const int total = uses[k].forward + uses[k].reversed;
        const std::string where =
            name + " shell " + std::to_string(s) + " edge " + std::to_string(k);
        if (total == 1) {
          add(CheckStatus::FreeEdge, where + " bounds one face only");
          closed = false;
        } else if (total > 2) {
          add(CheckStatus::NonManifoldEdge, where + " bounds " + std::to_string(total) + " faces");
        } else if (uses[k].forward != 1) {
          add(CheckStatus::EdgeSameOrientationTwice,
              where + " is used twice in the same direction");
        }
      }
      if (!closed) {
        add(CheckStatus::OpenShell, name + " shell " + std::to_string(s) + " is open");
        continue;
      }
      const auto counts = count_shapes(shell);
      const long v = static_cast<long>(counts[static_cast<int>(ShapeKind::Vertex)]);
      const long e = static_cast<long>(uses.size());
      const long f = static_cast<long>(counts[static_cast<int>(ShapeKind::Face)]);
      const long l = static_cast<long>(counts[static_cast<int>(ShapeKind::Wire)]);
      const long chi = v - e + f - (l - f);
      if (chi % 2 != 0 || chi > 2) {
        add(CheckStatus::EulerPoincareMismatch,
            name + " shell " + std::to_string(s) +
                ": V - E + F - (L - F) = " + std::to_string(chi) + " is not 2(1 - genus)");
      }
    }
    if (!report_.has(CheckStatus::OpenShell) && volume(solid) <= 0.0) {
      add(CheckStatus::BadFaceOrientation, name + " encloses a non-positive volume");
    }
  }

  // The solid's volume (detail::solid_volume: mass_properties' to rounding), or the caller's
  // copy of it (the same function on the same solid).
  double volume(const Shape& solid) const {
    const auto it = known_volumes_.find(solid.body_id());
    if (it != known_volumes_.end() && it->second.first == solid) return it->second.second;
    return detail::solid_volume(solid);
  }

  CheckReport& report_;
  std::unordered_map<const void*, std::pair<Shape, double>> known_volumes_;  // by body
};

}  // namespace

CheckReport check_shape(const Shape& shape) {
  CheckReport report;
  Checker(report, {}).run(shape);
  return report;
}

namespace detail {

CheckReport check_shape_with_volumes(const Shape& shape,
                                     const std::vector<std::pair<Shape, double>>& known) {
  CheckReport report;
  Checker(report, known).run(shape);
  return report;
}

}  // namespace detail

}  // namespace csgtile::kernel
