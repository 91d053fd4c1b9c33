#pragma once
/// \file
/// Topology (paper §2): the eight shape kinds, shared immutable bodies, and Shape — a cheap
/// value made of a body, a Location and an Orientation.

#include <cstdint>
#include <memory>
#include <variant>
#include <vector>

#include "csgtile/kernel/curve.h"
#include "csgtile/kernel/curve2d.h"
#include "csgtile/kernel/location.h"
#include "csgtile/kernel/orientation.h"
#include "csgtile/kernel/result.h"
#include "csgtile/kernel/surface.h"

namespace csgtile::kernel {

/// Paper Table 1, from the most complex kind to the simplest. A shape's children are of a
/// strictly simpler kind, except compounds (anything) and compsolids (solids).
enum class ShapeKind : std::uint8_t {
  Compound = 0,
  CompSolid = 1,
  Solid = 2,
  Shell = 3,
  Face = 4,
  Wire = 5,
  Edge = 6,
  Vertex = 7
};
inline constexpr int kShapeKindCount = 8;

/// "compound", "compsolid", "solid", "shell", "face", "wire", "edge", "vertex".
const char* shape_kind_name(ShapeKind kind);

class ShapeBody;

/// A reference to a shared topological body, placed by a Location and oriented.
///
/// Copying a Shape copies a pointer and a transform; the body is never modified after it is
/// built, so shapes are safe to share between threads. Three equality levels:
/// - shares_body(): the same body (OpenCASCADE's "partner");
/// - is_same(): the same body and location (the same sub-shape of a model);
/// - operator==: the same body, location and orientation.
class Shape {
 public:
  /// The null shape.
  Shape() = default;

  bool is_null() const { return body_ == nullptr; }
  /// Precondition for everything below: !is_null().
  ShapeKind kind() const;
  const Location& location() const { return location_; }
  Orientation orientation() const { return orientation_; }
  const ShapeBody& body() const { return *body_; }
  /// Identity of the body (stable for the body's lifetime; not for ordering outputs).
  const void* body_id() const { return body_.get(); }

  /// Number of direct children of the body.
  std::size_t child_count() const;
  /// The i-th child as seen through this shape: location = this.location * child.location,
  /// orientation = compose(this.orientation, child.orientation).
  Shape child(std::size_t i) const;
  /// All children as seen through this shape.
  std::vector<Shape> children() const;

  /// The same body with another location / orientation.
  Shape located(const Location& location) const;
  /// Moves the shape: location becomes `by * location()`.
  Shape moved(const Location& by) const;
  Shape oriented(Orientation orientation) const;
  Shape reversed() const { return oriented(kernel::reversed(orientation_)); }
  /// Orientation becomes compose(parent, orientation()).
  Shape composed(Orientation parent) const { return oriented(compose(parent, orientation_)); }

  bool shares_body(const Shape& other) const { return body_ == other.body_; }
  bool is_same(const Shape& other) const {
    return body_ == other.body_ && location_ == other.location_;
  }
  bool operator==(const Shape& other) const {
    return is_same(other) && orientation_ == other.orientation_;
  }
  bool operator!=(const Shape& other) const { return !(*this == other); }

  /// Hash consistent with is_same() (orientation ignored).
  std::size_t hash() const;

 private:
  friend class ShapeFactory;
  Shape(std::shared_ptr<const ShapeBody> body, const Location& location, Orientation o)
      : body_(std::move(body)), location_(location), orientation_(o) {}

  std::shared_ptr<const ShapeBody> body_;
  Location location_;
  Orientation orientation_ = Orientation::Forward;
};

/// Hasher for unordered containers keyed by is_same().
struct ShapeSameHash {
  std::size_t operator()(const Shape& s) const { return s.hash(); }
};
struct ShapeSameEqual {
  bool operator()(const Shape& a, const Shape& b) const { return a.is_same(b); }
};

/// Geometry of a vertex body, in the body's frame.
struct VertexData {
  Vec3 point;
  double tolerance;
};

/// Geometry of an edge body: its curve restricted to [first, last]. A degenerate edge (a
/// sphere pole, a cone apex) has no curve; it stands for a point of its vertex.
struct EdgeData {
  CurvePtr curve;  ///< null for a degenerate edge
  double first;
  double last;
  double tolerance;
  bool degenerate() const { return curve == nullptr; }
};

/// Geometry of a face body: its surface, and one pcurve per edge use, indexed
/// [wire position][edge position in that wire], parametrised like the edge's curve.
struct FaceData {
  SurfacePtr surface;
  double tolerance;
  std::vector<std::vector<Curve2dPtr>> pcurves;
};

/// The shared, immutable topological body.
class ShapeBody {
 public:
  ShapeKind kind() const { return kind_; }
  const std::vector<Shape>& children() const { return children_; }
  /// Non-null for vertices, edges and faces respectively.
  const VertexData* vertex() const { return std::get_if<VertexData>(&geometry_); }
  const EdgeData* edge() const { return std::get_if<EdgeData>(&geometry_); }
  const FaceData* face() const { return std::get_if<FaceData>(&geometry_); }

 private:
  friend class ShapeFactory;
  ShapeKind kind_ = ShapeKind::Compound;
  std::vector<Shape> children_;
  /// Held in the body (one allocation per body, not two).
  std::variant<std::monostate, VertexData, EdgeData, FaceData> geometry_;
};

/// Creates bodies. Every function checks kinds and the tolerance order face ≤ edge ≤
/// vertex, and returns a Forward shape at the identity location.
class ShapeFactory {
 public:
  /// Error: InvalidArgument for a non-finite point or a negative tolerance.
  static Result<Shape> vertex(const Vec3& point, double tolerance);
  /// Edge on `curve` over [first, last] from `start` to `end` (vertex shapes, used as given
  /// but re-oriented Forward / Reversed). start may equal end (closed edge).
  /// Errors: InvalidArgument (first >= last, wrong kinds, vertex farther from the curve end
  /// than its tolerance, edge tolerance above a vertex tolerance).
  static Result<Shape> edge(CurvePtr curve, double first, double last, const Shape& start,
                            const Shape& end, double tolerance);
  /// Degenerate edge at `vertex` over the parameter range [first, last].
  static Result<Shape> degenerate_edge(const Shape& vertex, double first, double last,
                                       double tolerance);
  /// Wire of edges as given (their orientations kept). Error: a child that is not an edge.
  static Result<Shape> wire(std::vector<Shape> edges);
  /// Face on `surface` bounded by `wires` (outer first); `pcurves[w][e]` for the e-th edge of
  /// wire w. Errors: counts that do not match, an edge tolerance below the face tolerance.
  static Result<Shape> face(SurfacePtr surface, std::vector<Shape> wires,
                            std::vector<std::vector<Curve2dPtr>> pcurves, double tolerance);
  static Result<Shape> shell(std::vector<Shape> faces);
  static Result<Shape> solid(std::vector<Shape> shells);
  static Result<Shape> compsolid(std::vector<Shape> solids);
  static Result<Shape> compound(std::vector<Shape> shapes);

 private:
  static Result<Shape> make(ShapeKind kind, std::vector<Shape> children, ShapeKind allowed_child);
};

// ---- geometry seen through a shape (location applied) ------------------------------------

/// Point of a vertex in the shape's frame (location applied).
Vec3 vertex_point(const Shape& vertex);
/// Tolerance of a vertex, edge or face, scaled by the location's scale.
double tolerance(const Shape& shape);

/// Parameter on `edge`'s curve where `vertex` (one of its children) sits: first for a
/// Forward use, last for a Reversed one.
double vertex_parameter(const Shape& edge, const Shape& vertex);

}  // namespace csgtile::kernel
