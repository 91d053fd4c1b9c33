// The Boolean engine (internal): the state of one Boolean operation between two solids and
// its phases, each in its own file — engine.cpp (the run, shared edges, touching vertices),
// sphere_reframe.cpp, sections.cpp (face-face sections), pieces.cpp (edge and face
// splitting, classification), rebuild.cpp (the result's faces, shells and solids).
// boolean.cpp holds the public entry points (csgtile/kernel/boolean.h).
#pragma once

#include <cstddef>
#include <limits>
#include <optional>
#include <utility>
#include <vector>

#include "boolean/face_split.h"
#include "boolean/model.h"
#include "boolean/uv_geometry.h"
#include "csgtile/kernel/boolean.h"

namespace csgtile::kernel::detail {

// The name of a surface kind, for messages.
const char* surface_name(SurfaceKind k);

// The pcurve of `edge` on `surface`, shifted by whole periods so that at `point` it lands
// where `old_uv` is (a seam is used at u = 0 and at u = 2π: the side must be kept).
Curve2dPtr aligned_fit(const BEdge& edge, const Surface& surface, const Vec3& point,
                       const Vec2& old_uv, double tolerance);

// A face piece after splitting, with its fate.
struct Piece {
  int face = 0;  // index into model.faces
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

  Result<Shape> run();

  Result<Interference> interference();

 private:
  // Cancelled once options_.interrupt has fired (interrupt.h), naming the operation's stage.
  Status interrupted(const char* stage) const;

  // Edges of the two operands that coincide (touching solids) become one edge, so the
  // result shares them.
  void unify_shared_edges();

  // A full sphere's (u, v) frame is free: choose its axis so that every section with the
  // other operand is a latitude or a meridian (whose pcurves are exact lines), and turn its
  // seam away from the meridian planes. Spheres cut by surfaces with no common axis keep
  // their frame (their sections then report Unsupported).
  void reframe_spheres();

  // A full sphere whose sections will be traced (no common axis): its poles, where its
  // (u, v) parameters are singular, are turned as far as possible from the other operand's
  // faces it meets (measured to their bounding boxes), so that no traced section passes a pole.
  void reframe_for_tracing(BFace& face, std::size_t lo, std::size_t hi);

  void rebuild_full_sphere(BFace& face, const Frame& frame, double r);

  // Per model vertex: the operand whose boundary edges use it (0 or 1), 2 when both do (a
  // contact point), -1 when none does.
  std::vector<int> operand_of_vertices() const;

  // A vertex of one operand lying inside an edge of the other (touching or overlapping
  // boundaries) splits that edge there.
  void split_at_touching_vertices();

  double uv_margin(std::size_t face) const;

  // Crossings of a curve (pcurve `pc` on face f) with f's boundary: (curve parameter, edge,
  // edge parameter) triples.
  struct Hit {
    double t;
    int edge;
    double s;
  };
  void boundary_hits(std::size_t f, const Curve2d& pc, double t0, double t1, int skip_edge,
                     std::vector<Hit>& hits);

  // Crossing boxes of face f's boundary uses (loop order), kept while intersect_faces runs
  // (the loops do not change before split_edges).
  const std::vector<CrossingBox>& boundary_boxes(std::size_t f);

  // Adds the part of a curve lying inside both faces (fa, fb) as section edges (or, with
  // `existing` >= 0, marks an existing edge of fb's boundary as lying in fa).
  // Traced sections bring their pcurves (`hint_a` on fa, `hint_b` on fb) and the tolerance
  // their edges need; closed-form ones get exact fitted pcurves and the model tolerance.
  Status add_section(std::size_t fa, std::size_t fb, CurvePtr curve, double t0, double t1,
                     int existing, const Curve2dPtr& hint_a = nullptr,
                     const Curve2dPtr& hint_b = nullptr, double edge_tolerance = 0.0);

  // Where boundary edge `e` pierces `surface`, by Newton's method on the signed distance from
  // e(s) to the surface, from s: the parameter, or nullopt when the edge grazes the surface
  // there or the iteration does not settle.
  std::optional<double> pierce_parameter(const BEdge& e, double s, const Surface& surface) const;

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
                             std::size_t hits_on_a, double reach);

  // A section crossing a boundary edge at a grazing angle (a plane almost parallel to a
  // disc, a section almost along a rim) is found at points up to tolerance / sin(angle) apart
  // by the different sections that end there. A hit with no vertex of its edge within
  // tolerance moves to the nearest of the edge's vertices (its ends and splits) within
  // kReuseReach tolerances that lies on the section within tolerance: one vertex where the
  // sections meet, not two a few tolerances apart joined by sliver edges.
  void reuse_edge_vertices(const Curve& curve, double t0, double t1, std::vector<Hit>& hits);

  // A boundary edge of face f passing through p (within tolerance), or -1.
  int boundary_edge_through(std::size_t f, const Vec3& p);

  // Adds the part of edge `e` between the points p0 and p1 to face f as a section edge,
  // splitting `e` at p0 and p1 when they are inside it.
  // `through` is a point of the part: on a closed edge (a circle from its vertex round to
  // it) it tells which of the two arcs between p0 and p1 is meant; an arc across the edge's
  // start vertex is added as its two pieces.
  void add_edge_part(std::size_t f, int e_id, const Vec3& p0, const Vec3& p1, const Vec3& through);

  // The part [a, b] of edge `e_id` as a section edge of face f (see add_edge_part).
  void add_edge_range(std::size_t f, int e_id, double a, double b);

  // The pcurve for `edge` on face f: the section pcurve when the edge is on the section's
  // curve, else refitted on the edge's own curve.
  Curve2dPtr refit_for(int edge, std::size_t f, const Curve2dPtr& pc, const CurvePtr& curve);

  void add_extra(std::size_t f, int edge, Curve2dPtr pcurve);

  // The pcurve of an existing edge found lying in face f over its parameters [a, b] (the
  // whole edge by default; a part where the edge grazes f and leaves it beyond): exact
  // (fitted within fit_tolerance), else — the edge lies in f only within the tolerance, as a
  // boundary edge of a plane fitted 4e-8 off its twin does — the one that stays within the
  // edge's own tolerance (at least the model's), the edge's tolerance grown to its deviation.
  // Null when the edge leaves f by more than that over [a, b].
  Curve2dPtr lying_pcurve(int edge, std::size_t f,
                          double a = -std::numeric_limits<double>::infinity(),
                          double b = std::numeric_limits<double>::infinity());

  // A closed boundary edge of face f that runs along the whole closed curve(t0..t1) (each
  // within tolerance of the other at 8 samples), or -1.
  int closed_boundary_edge_along(std::size_t f, const Curve& curve, double t0, double t1);

  // An existing edge between v0 and v1 through all of `probes`, or -1.
  int find_edge(int v0, int v1, const std::vector<Vec3>& probes);

  // The vertex at curve(t): an existing vertex within tolerance, else new; every boundary
  // edge hit there gets a split.
  int vertex_on_curve(const Curve& curve, double t, const std::vector<Hit>& hits);

  // Whether face f's boundary (its vertices and the middles of its edges) lies on face g's
  // surface within the tolerance of each edge.
  bool lies_on(std::size_t f, std::size_t g) const;

  Status intersect_faces();

  // Section curves of one face may cross each other inside it (the two ellipses of a
  // Steinmetz pair meet on the axes): both edges are split at each crossing.
  void split_crossing_sections();

  // Applies the splits gathered on edges: each split edge becomes a chain of sub-edges, and
  // every use of it (boundary loops, extras) the chain of sub-uses.
  void split_edges();

  Status split_faces(std::vector<Piece>& pieces);

  // Points inside a piece: in its largest triangles (up to `count`), at uneven barycentric
  // weights so that they do not fall on the lines and corners other geometry is built on
  // (a centroid of a split face can be exactly the end of the other operand's edge). The
  // triangles are those of the piece's sampled outline, whose chords of curved pcurves can
  // cut across a thin piece (an annulus a few hundredths of its radius wide): each point is
  // checked against the piece's arcs, and the outline is sampled finer until enough points
  // pass (a point outside the piece would classify a neighbour instead).
  std::vector<Vec3> interior_points(const Piece& piece, std::size_t count);

  Vec3 outward_normal(const Piece& piece, const Vec3& p);

  Status classify(std::vector<Piece>& pieces);

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

}  // namespace csgtile::kernel::detail
