#include "csgtile/kernel/shape.h"

#include <cmath>
#include <string>

namespace csgtile::kernel {

const char* shape_kind_name(ShapeKind kind) {
  switch (kind) {
    case ShapeKind::Compound:
      return "compound";
    case ShapeKind::CompSolid:
      return "compsolid";
    case ShapeKind::Solid:
      return "solid";
    case ShapeKind::Shell:
      return "shell";
    case ShapeKind::Face:
      return "face";
    case ShapeKind::Wire:
      return "wire";
    case ShapeKind::Edge:
      return "edge";
    case ShapeKind::Vertex:
      return "vertex";
  }
  return "unknown";
}

ShapeKind Shape::kind() const { return body_->kind(); }

std::size_t Shape::child_count() const { return body_ ? body_->children().size() : 0; }

Shape Shape::child(std::size_t i) const {
  const Shape& c = body_->children()[i];
  return Shape(c.body_, location_ * c.location_, compose(orientation_, c.orientation_));
}

std::vector<Shape> Shape::children() const {
  std::vector<Shape> out;
  out.reserve(child_count());
  for (std::size_t i = 0; i < child_count(); ++i) out.push_back(child(i));
  return out;
}

Shape Shape::located(const Location& location) const {
  return Shape(body_, location, orientation_);
}
Shape Shape::moved(const Location& by) const { return Shape(body_, by * location_, orientation_); }
Shape Shape::oriented(Orientation orientation) const {
  return Shape(body_, location_, orientation);
}

std::size_t Shape::hash() const {
  const std::size_t h = std::hash<const void*>{}(body_.get());
  return h ^ (location_.hash() + 0x9e3779b97f4a7c15ULL + (h << 6) + (h >> 2));
}

// ---- factory -------------------------------------------------------------------------------

namespace {
std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}
bool bad_tolerance(double t) { return !(t >= 0.0) || !std::isfinite(t); }
}  // namespace

Result<Shape> ShapeFactory::vertex(const Vec3& point, double tolerance) {
  if (!point.allFinite()) return Error{ErrorCode::InvalidArgument, "vertex point is not finite"};
  if (bad_tolerance(tolerance)) {
    return Error{ErrorCode::InvalidArgument, "vertex tolerance must be finite and >= 0"};
  }
  auto body = std::make_shared<ShapeBody>();
  body->kind_ = ShapeKind::Vertex;
  body->geometry_ = VertexData{point, tolerance};
  return Shape(std::move(body), Location(), Orientation::Forward);
}

Result<Shape> ShapeFactory::edge(CurvePtr curve, double first, double last, const Shape& start,
                                 const Shape& end, double tolerance) {
  if (!curve) return Error{ErrorCode::InvalidArgument, "edge needs a curve"};
  if (!(first < last) || !std::isfinite(first) || !std::isfinite(last)) {
    return Error{ErrorCode::InvalidArgument,
                 "edge parameter range [" + num(first) + ", " + num(last) + "] is empty"};
  }
  if (bad_tolerance(tolerance)) {
    return Error{ErrorCode::InvalidArgument, "edge tolerance must be finite and >= 0"};
  }
  const Shape* ends[2] = {&start, &end};
  const double params[2] = {first, last};
  for (int i = 0; i < 2; ++i) {
    const Shape& v = *ends[i];
    if (v.is_null() || v.kind() != ShapeKind::Vertex) {
      return Error{ErrorCode::InvalidArgument, "edge ends must be vertices"};
    }
    const double vt = kernel::tolerance(v);
    if (tolerance > vt) {
      return Error{ErrorCode::InvalidArgument,
                   "edge tolerance " + num(tolerance) + " exceeds its vertex tolerance " + num(vt)};
    }
    const double gap = (curve->point(params[i]) - vertex_point(v)).norm();
    if (gap > vt) {
      return Error{ErrorCode::InvalidArgument,
                   std::string("edge ") + (i == 0 ? "start" : "end") + " is " + num(gap) +
                       " from its vertex, more than the vertex tolerance " + num(vt)};
    }
  }
  auto body = std::make_shared<ShapeBody>();
  body->kind_ = ShapeKind::Edge;
  body->children_ = {start.oriented(Orientation::Forward), end.oriented(Orientation::Reversed)};
  body->geometry_ = EdgeData{std::move(curve), first, last, tolerance};
  return Shape(std::move(body), Location(), Orientation::Forward);
}

Result<Shape> ShapeFactory::degenerate_edge(const Shape& vertex, double first, double last,
                                            double tolerance) {
  if (vertex.is_null() || vertex.kind() != ShapeKind::Vertex) {
    return Error{ErrorCode::InvalidArgument, "a degenerate edge needs a vertex"};
  }
  if (!(first < last) || bad_tolerance(tolerance) || tolerance > kernel::tolerance(vertex)) {
    return Error{ErrorCode::InvalidArgument, "degenerate edge has a bad range or tolerance"};
  }
  auto body = std::make_shared<ShapeBody>();
  body->kind_ = ShapeKind::Edge;
  body->children_ = {vertex.oriented(Orientation::Forward), vertex.oriented(Orientation::Reversed)};
  body->geometry_ = EdgeData{nullptr, first, last, tolerance};
  return Shape(std::move(body), Location(), Orientation::Forward);
}

Result<Shape> ShapeFactory::make(ShapeKind kind, std::vector<Shape> children,
                                 ShapeKind allowed_child) {
  for (const Shape& c : children) {
    if (c.is_null() || c.kind() != allowed_child) {
      return Error{ErrorCode::InvalidArgument,
                   std::string("a ") + shape_kind_name(kind) + " is made of " +
                       shape_kind_name(allowed_child) + "s, got " +
                       (c.is_null() ? "a null shape" : shape_kind_name(c.kind()))};
    }
  }
  auto body = std::make_shared<ShapeBody>();
  body->kind_ = kind;
  body->children_ = std::move(children);
  return Shape(std::move(body), Location(), Orientation::Forward);
}

Result<Shape> ShapeFactory::wire(std::vector<Shape> edges) {
  return make(ShapeKind::Wire, std::move(edges), ShapeKind::Edge);
}

Result<Shape> ShapeFactory::face(SurfacePtr surface, std::vector<Shape> wires,
                                 std::vector<std::vector<Curve2dPtr>> pcurves, double tolerance) {
  if (!surface) return Error{ErrorCode::InvalidArgument, "face needs a surface"};
  if (bad_tolerance(tolerance)) {
    return Error{ErrorCode::InvalidArgument, "face tolerance must be finite and >= 0"};
  }
  if (pcurves.size() != wires.size()) {
    return Error{ErrorCode::InvalidArgument, "face needs one pcurve list per wire"};
  }
  for (std::size_t w = 0; w < wires.size(); ++w) {
    if (wires[w].is_null() || wires[w].kind() != ShapeKind::Wire) {
      return Error{ErrorCode::InvalidArgument, "a face is bounded by wires"};
    }
    if (pcurves[w].size() != wires[w].child_count()) {
      return Error{ErrorCode::InvalidArgument, "face needs one pcurve per edge use"};
    }
    for (std::size_t e = 0; e < pcurves[w].size(); ++e) {
      if (!pcurves[w][e]) return Error{ErrorCode::InvalidArgument, "face has a null pcurve"};
      const double et = kernel::tolerance(wires[w].child(e));
      if (tolerance > et) {
        return Error{ErrorCode::InvalidArgument,
                     "face tolerance " + num(tolerance) + " exceeds an edge tolerance " + num(et)};
      }
    }
  }
  auto result = make(ShapeKind::Face, std::move(wires), ShapeKind::Wire);
  if (!result.ok()) return result;
  auto body = std::const_pointer_cast<ShapeBody>(result.value().body_);
  body->geometry_ = FaceData{std::move(surface), tolerance, std::move(pcurves)};
  return result;
}

Result<Shape> ShapeFactory::shell(std::vector<Shape> faces) {
  return make(ShapeKind::Shell, std::move(faces), ShapeKind::Face);
}
Result<Shape> ShapeFactory::solid(std::vector<Shape> shells) {
  return make(ShapeKind::Solid, std::move(shells), ShapeKind::Shell);
}
Result<Shape> ShapeFactory::compsolid(std::vector<Shape> solids) {
  return make(ShapeKind::CompSolid, std::move(solids), ShapeKind::Solid);
}
Result<Shape> ShapeFactory::compound(std::vector<Shape> shapes) {
  for (const Shape& s : shapes) {
    if (s.is_null())
      return Error{ErrorCode::InvalidArgument, "a compound cannot hold a null shape"};
  }
  auto body = std::make_shared<ShapeBody>();
  body->kind_ = ShapeKind::Compound;
  body->children_ = std::move(shapes);
  return Shape(std::move(body), Location(), Orientation::Forward);
}

// ---- geometry seen through a shape -----------------------------------------------------------

Vec3 vertex_point(const Shape& vertex) {
  return vertex.location().apply_point(vertex.body().vertex()->point);
}

double tolerance(const Shape& shape) {
  const ShapeBody& b = shape.body();
  const double s = shape.location().scale();
  if (b.vertex()) return b.vertex()->tolerance * s;
  if (b.edge()) return b.edge()->tolerance * s;
  if (b.face()) return b.face()->tolerance * s;
  return 0.0;
}

double vertex_parameter(const Shape& edge, const Shape& vertex) {
  const EdgeData& e = *edge.body().edge();
  // The vertex as seen through the edge has the edge's orientation composed in; undo it to
  // get its orientation inside the edge body, which is what ties it to first or last.
  Orientation in_body = vertex.orientation();
  if (edge.orientation() == Orientation::Reversed) in_body = reversed(in_body);
  return in_body == Orientation::Reversed ? e.last : e.first;
}

}  // namespace csgtile::kernel
