#include "boolean/model.h"

#include <array>
#include <cmath>

#include "boolean/pcurve_fit.h"
#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/mass_properties.h"
#include "geometry/geometry_internal.h"

namespace csgtile::kernel::detail {

int BModel::vertex_at(const Vec3& p) {
  const double cell = std::max(tolerance_ * 4.0, 1e-12);
  const Vec3 q = p / cell;
  const long long cx = std::llround(std::floor(q.x()));
  const long long cy = std::llround(std::floor(q.y()));
  const long long cz = std::llround(std::floor(q.z()));
  // A vertex within the tolerance (a quarter cell) lies in a neighbouring cell only on the
  // side where p is that close to the cell's wall. The margin covers the rounding of the
  // cell coordinates: a few units in the last place of t (cells of 4e-6 m at 1e5 m: 2.5e10).
  auto neighbours = [&](double t, long long c) {
    const double f = t - static_cast<double>(c);
    const double near = 0.25 + 1e-3 + 1e-14 * std::abs(t);
    return std::array<long long, 2>{f <= near ? -1 : 0, f >= 1.0 - near ? 1 : 0};
  };
  const auto sx = neighbours(q.x(), cx), sy = neighbours(q.y(), cy), sz = neighbours(q.z(), cz);
  int best = -1;
  double best_d = tolerance_;
  for (long long dx = sx[0]; dx <= sx[1]; ++dx) {
    for (long long dy = sy[0]; dy <= sy[1]; ++dy) {
      for (long long dz = sz[0]; dz <= sz[1]; ++dz) {
        auto it = grid_.find(cell_key(cx + dx, cy + dy, cz + dz));
        if (it == grid_.end()) continue;
        for (int v : it->second) {
          const double d = (vertices[static_cast<std::size_t>(v)].point - p).norm();
          if (d <= best_d) {
            best_d = d;
            best = v;
          }
        }
      }
    }
  }
  if (best >= 0) return best;
  vertices.push_back({p, tolerance_});
  const int id = static_cast<int>(vertices.size()) - 1;
  grid_[cell_key(cx, cy, cz)].push_back(id);
  return id;
}

namespace {

// A face's polyline pcurve carried into the world frame of its transformed surface: angle
// parameters stay, length parameters scale with the location (surface.h: plane u and v,
// cylinder and cone v). Null for other pcurves or surfaces.
Curve2dPtr carried_pcurve(const Curve2dPtr& pcurve, SurfaceKind kind, double scale) {
  if (!pcurve || pcurve->kind() != Curve2dKind::Polyline) return nullptr;
  if (scale == 1.0) return pcurve;
  double su = 1.0, sv = 1.0;
  switch (kind) {
    case SurfaceKind::Plane:
      su = sv = scale;
      break;
    case SurfaceKind::Cylinder:
    case SurfaceKind::Cone:
      sv = scale;
      break;
    case SurfaceKind::Sphere:
    case SurfaceKind::Torus:
      break;
    default:
      return nullptr;
  }
  std::vector<Vec2> points = static_cast<const Polyline2d&>(*pcurve).points();
  for (Vec2& p : points) p = Vec2(p.x() * su, p.y() * sv);
  return std::make_shared<Polyline2d>(std::move(points));
}

}  // namespace

Status import_operand(BModel& model, const Shape& shape, int operand) {
  if (shape.is_null()) return Status(ErrorCode::InvalidArgument, "a Boolean argument is null");
  if (map_child_shapes(shape, ShapeKind::Solid).size() == 0) {
    return Status(
        ErrorCode::InvalidArgument,
        std::string("a Boolean argument must hold solids, got a ") + shape_kind_name(shape.kind()));
  }
  const double fit_tolerance = model.tolerance() * 1e-2;
  ShapeIndex edge_index;
  std::vector<int> edge_ids;  // edge_index position -> model edge id
  auto edge_id = [&](const Shape& edge) -> Result<int> {
    const std::size_t before = edge_index.size();
    const std::size_t k = edge_index.add(edge);
    if (k < before) return edge_ids[k];
    const EdgeData& d = *edge.body().edge();
    BEdge e;
    const Location& loc = edge.location();
    const double k_param = d.curve ? detail::moved_parameter_scale(*d.curve, loc) : 1.0;
    e.t0 = d.first * k_param;
    e.t1 = d.last * k_param;
    e.tolerance = std::max(d.tolerance * loc.scale(), model.tolerance());
    if (d.curve) e.curve = d.curve->transformed(loc);
    const Shape start = edge.oriented(Orientation::Forward).child(0);
    const Shape end = edge.oriented(Orientation::Forward).child(1);
    e.v0 = model.vertex_at(vertex_point(start));
    e.v1 = model.vertex_at(vertex_point(end));
    const int id = model.add_edge(std::move(e));
    edge_ids.push_back(id);
    return id;
  };

  const ShapeIndex faces = map_child_shapes(shape, ShapeKind::Face);
  for (std::size_t fi = 0; fi < faces.size(); ++fi) {
    // Faces are taken once each; their orientation comes from the first use in the walk.
    const Shape& face = faces[fi];
    if (face.orientation() != Orientation::Forward && face.orientation() != Orientation::Reversed)
      continue;
    const FaceData& fd = *face.body().face();
    BFace bf;
    bf.surface = fd.surface->transformed(face.location());
    bf.reversed = face.orientation() == Orientation::Reversed;
    bf.operand = operand;
    bf.source = static_cast<int>(fi);
    bf.box = bounding_box(face);
    const Shape body_face = face.oriented(Orientation::Forward);
    for (std::size_t w = 0; w < body_face.child_count(); ++w) {
      const Shape wire = body_face.child(w);
      BLoop loop;
      for (std::size_t k = 0; k < wire.child_count(); ++k) {
        const Shape edge = wire.child(k);
        auto id = edge_id(edge);
        if (!id.ok()) return id.error();
        BEdge& e = model.edges[static_cast<std::size_t>(id.value())];
        BUse use{id.value(), edge.orientation() != Orientation::Reversed, nullptr};
        if (e.degenerate()) {
          // A pole or apex: u runs with the parameter, v is fixed where the point is.
          const auto& old = static_cast<const Line2d&>(*fd.pcurves[w][k]);
          const Vec2 at =
              bf.surface->closest_parameters(model.vertices[static_cast<std::size_t>(e.v0)].point);
          use.pcurve = std::make_shared<Line2d>(Vec2(old.origin().x(), at.y()), old.direction());
        } else {
          use.pcurve = fit_pcurve(*e.curve, e.t0, e.t1, *bf.surface, fit_tolerance);
          // An edge lying in its face only within its own tolerance (a fuse made it an edge of
          // a plane fitted 4e-8 off its twin's): the pcurve that stays within it.
          if (!use.pcurve) use.pcurve = fit_pcurve(*e.curve, e.t0, e.t1, *bf.surface, e.tolerance);
          if (!use.pcurve) {
            // A traced section edge (polyline) keeps the face's own pcurve, carried into the
            // world frame and accepted within the edge's tolerance.
            Curve2dPtr own =
                carried_pcurve(fd.pcurves[w][k], bf.surface->kind(), face.location().scale());
            if (own && pcurve_deviation(*e.curve, *own, e.t0, e.t1, *bf.surface) <= e.tolerance) {
              use.pcurve = std::move(own);
              loop.push_back(std::move(use));
              continue;
            }
            return Status(ErrorCode::Unsupported,
                          "an edge of an argument has no exact pcurve on its face");
          }
          // Keep the face's own (u, v) window (a seam is used at u = 0 and at u = 2π): shift
          // the refitted pcurve by whole periods onto the original one.
          const EdgeData& d = *edge.body().edge();
          const double mid_body = 0.5 * (d.first + d.last);
          const double mid_world = 0.5 * (e.t0 + e.t1);
          const Vec2 old_uv = fd.pcurves[w][k]->point(mid_body);
          const Vec2 new_uv = use.pcurve->point(mid_world);
          Vec2 offset = Vec2::Zero();
          const double pu = bf.surface->u_period(), pv = bf.surface->v_period();
          if (pu > 0) offset.x() = pu * std::round((old_uv.x() - new_uv.x()) / pu);
          if (pv > 0) offset.y() = pv * std::round((old_uv.y() - new_uv.y()) / pv);
          use.pcurve = shift_pcurve(use.pcurve, offset);
        }
        loop.push_back(std::move(use));
      }
      bf.loops.push_back(std::move(loop));
    }
    // A seam is an edge used twice by one face (at both ends of a periodic parameter).
    std::map<int, int> uses_in_face;
    for (const BLoop& face_loop : bf.loops) {
      for (const BUse& u : face_loop) ++uses_in_face[u.edge];
    }
    for (const auto& [edge, count] : uses_in_face) {
      if (count == 2) model.edges[static_cast<std::size_t>(edge)].seam = true;
    }
    model.faces.push_back(std::move(bf));
  }
  return {};
}

}  // namespace csgtile::kernel::detail
