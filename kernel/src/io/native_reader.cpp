// Native format reader for untrusted bytes. Order of checks: magic, version and flags (so a
// newer file is reported as such even though its checksum may cover other things), the
// checksum, the section framing, then each table in dependency order. Every count is
// bounded by the bytes left before anything is allocated, every index by its table, and
// every body goes through ShapeFactory, whose checks become CorruptData. Layout:
// native_layout.h.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <numbers>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "csgtile/kernel/native_format.h"
#include "io/byte_stream.h"
#include "io/native_layout.h"
#include "io/unit_direction.h"

namespace csgtile::kernel {

namespace {

using detail::ByteReader;
using detail::SectionTag;

Error corrupt(const std::string& message) {
  return Error{ErrorCode::CorruptData, "native format: " + message};
}

/// Payloads of the known sections (empty view = absent).
struct Sections {
  struct Payload {
    std::string_view bytes;
    std::size_t offset = 0;
    bool present = false;
  };
  Payload numbers, locations, curves, surfaces, pcurves, bodies;

  Payload* find(std::uint64_t tag) {
    switch (tag) {
      case static_cast<std::uint64_t>(SectionTag::Numbers):
        return &numbers;
      case static_cast<std::uint64_t>(SectionTag::Locations):
        return &locations;
      case static_cast<std::uint64_t>(SectionTag::Curves):
        return &curves;
      case static_cast<std::uint64_t>(SectionTag::Surfaces):
        return &surfaces;
      case static_cast<std::uint64_t>(SectionTag::Pcurves):
        return &pcurves;
      case static_cast<std::uint64_t>(SectionTag::Bodies):
        return &bodies;
      default:
        return nullptr;
    }
  }
};

/// Decodes the tables one section at a time; the first error stops everything.
class Decoder {
 public:
  std::optional<Error> numbers(const Sections::Payload& s);
  std::optional<Error> locations(const Sections::Payload& s);
  std::optional<Error> curves(const Sections::Payload& s);
  std::optional<Error> surfaces(const Sections::Payload& s);
  std::optional<Error> pcurves(const Sections::Payload& s);
  Result<Shape> bodies(const Sections::Payload& s);

 private:
  // Numbers are references into the table; the table holds finite values only.
  double number(ByteReader& in) {
    const std::uint64_t ref = in.varint();
    if (in.failed()) return 0.0;
    const std::uint64_t code = ref >> 1;
    std::size_t i = 0;
    if (code < detail::RecentNumbers::kCapacity) {
      if (code >= recent_.size()) {
        in.fail("recent number " + std::to_string(code) + " not yet defined");
        return 0.0;
      }
      i = recent_.at(static_cast<std::size_t>(code));
    } else if (code - detail::RecentNumbers::kCapacity < numbers_.size()) {
      i = static_cast<std::size_t>(code - detail::RecentNumbers::kCapacity);
    } else {
      in.fail("number index " + std::to_string(code - detail::RecentNumbers::kCapacity) +
              " out of range (" + std::to_string(numbers_.size()) + " entries)");
      return 0.0;
    }
    recent_.use(i);
    return (ref & 1U) != 0 ? -numbers_[i] : numbers_[i];
  }
  Vec2 vec2(ByteReader& in) {
    const double x = number(in);
    return {x, number(in)};
  }
  Vec3 vec3(ByteReader& in) {
    const double x = number(in);
    const double y = number(in);
    return {x, y, number(in)};
  }
  Frame frame(ByteReader& in) {
    Frame f;
    f.origin = vec3(in);
    f.x = vec3(in);
    f.y = vec3(in);
    f.z = vec3(in);
    return f;
  }
  /// A direction that normalisation will not turn into NaNs or leave at zero.
  static bool usable_direction(const Vec3& d) { return d.squaredNorm() > 0.0 && d.allFinite(); }
  /// Whether the direction a constructor made of `stored` is the one the writer would store
  /// `stored` for (unit_direction.h): then writing the shape again reproduces the file.
  /// Anything else (hand-made vectors, a platform flushing subnormals) is refused.
  static bool canonical(ByteReader& in, const Vec3& stored, const Vec3& direction) {
    const Vec3 again = detail::stored_unit_direction(direction);
    for (int i = 0; i < 3; ++i) {
      if (detail::double_bits(again[i]) != detail::double_bits(stored[i])) {
        in.fail("a stored direction is not in canonical form");
        return false;
      }
    }
    return true;
  }

  CurvePtr curve(ByteReader& in);
  SurfacePtr surface(ByteReader& in);
  Curve2dPtr pcurve(ByteReader& in);
  /// A reference from body `from` (appended to child_bodies_); nullopt after a failure
  /// recorded in `in`.
  std::optional<Shape> ref(ByteReader& in, std::uint64_t head, std::size_t from);
  std::optional<Shape> body(ByteReader& in, std::size_t index, std::string& factory_error);

  std::vector<double> numbers_;
  std::vector<Location> locations_;
  std::vector<CurvePtr> curves_;
  std::vector<SurfacePtr> surfaces_;
  std::vector<Curve2dPtr> pcurves_;
  std::vector<Shape> bodies_;
  std::vector<int> depth_;
  /// Body indices of the references read since the last body began (nesting depth).
  std::vector<std::size_t> child_bodies_;
  /// Reset at the start of every section, as the writer does.
  detail::RecentNumbers recent_;
};

/// Turns a reader failure, or bytes left over, into CorruptData naming the section.
std::optional<Error> finish(const ByteReader& in, const char* section) {
  if (in.failed()) return corrupt(std::string(section) + " section: " + in.error());
  if (!in.at_end()) {
    return corrupt(std::string(section) + " section: " + std::to_string(in.remaining()) +
                   " unexpected trailing bytes (at byte " + std::to_string(in.offset()) + ")");
  }
  return std::nullopt;
}

std::optional<Error> Decoder::numbers(const Sections::Payload& s) {
  if (!s.present) return std::nullopt;
  ByteReader in(s.bytes, s.offset);
  const std::uint64_t n = in.varint();
  // Each entry takes at least its half-byte length.
  if (!in.failed() && n > 2 * static_cast<std::uint64_t>(in.remaining())) {
    in.fail("number count " + std::to_string(n) + " exceeds the input");
  }
  if (in.failed()) return finish(in, "numbers");
  std::vector<std::uint8_t> lengths(static_cast<std::size_t>(n));
  for (std::size_t i = 0; i < lengths.size(); i += 2) {
    const std::uint8_t packed = in.byte();
    lengths[i] = static_cast<std::uint8_t>(packed & 0x0FU);
    if (i + 1 < lengths.size()) lengths[i + 1] = static_cast<std::uint8_t>(packed >> 4);
  }
  numbers_.reserve(lengths.size());
  for (std::size_t i = 0; i < lengths.size() && !in.failed(); ++i) {
    if (lengths[i] > 8) {
      in.fail("number " + std::to_string(i) + " has length " + std::to_string(lengths[i]));
      break;
    }
    std::uint64_t bits = 0;
    for (int b = 8 - lengths[i]; b < 8; ++b) bits |= std::uint64_t{in.byte()} << (8 * b);
    const double v = detail::bits_double(bits);
    if (!in.failed() && ((bits & detail::kSignBit) != 0 || !std::isfinite(v))) {
      in.fail("number " + std::to_string(i) + " is negative or not finite");
    }
    numbers_.push_back(v);
  }
  return finish(in, "numbers");
}

std::optional<Error> Decoder::locations(const Sections::Payload& s) {
  if (!s.present) return std::nullopt;
  recent_ = {};
  ByteReader in(s.bytes, s.offset);
  const std::size_t n = in.count(13, "location");
  locations_.reserve(n);
  for (std::size_t i = 0; i < n && !in.failed(); ++i) {
    Eigen::Matrix3d rotation;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) rotation(r, c) = number(in);
    }
    const double scale = number(in);
    const Vec3 translation = vec3(in);
    if (in.failed()) break;
    auto location = Location::from_parts(rotation, scale, translation);
    if (!location.ok()) {
      in.fail("location " + std::to_string(i) + ": " + location.error().message);
      break;
    }
    locations_.push_back(location.value());
  }
  return finish(in, "locations");
}

CurvePtr Decoder::curve(ByteReader& in) {
  const std::uint8_t kind = in.byte();
  switch (kind) {
    case static_cast<std::uint8_t>(CurveKind::Line): {
      const Vec3 origin = vec3(in);
      const Vec3 direction = vec3(in);
      if (in.failed()) return nullptr;
      if (!usable_direction(direction)) {
        in.fail("line direction is zero");
        return nullptr;
      }
      auto line = std::make_shared<LineCurve>(origin, direction);
      if (!canonical(in, direction, line->direction())) return nullptr;
      return line;
    }
    case static_cast<std::uint8_t>(CurveKind::Circle): {
      const Frame f = frame(in);
      const double radius = number(in);
      if (in.failed()) return nullptr;
      if (!(radius > 0.0)) {
        in.fail("circle radius is not > 0");
        return nullptr;
      }
      return std::make_shared<CircleCurve>(f, radius);
    }
    case static_cast<std::uint8_t>(CurveKind::Ellipse): {
      const Frame f = frame(in);
      const double major = number(in);
      const double minor = number(in);
      if (in.failed()) return nullptr;
      if (!(major >= minor && minor > 0.0)) {
        in.fail("ellipse radii break major >= minor > 0");
        return nullptr;
      }
      return std::make_shared<EllipseCurve>(f, major, minor);
    }
    case static_cast<std::uint8_t>(CurveKind::Polyline): {
      const std::size_t n = in.count(3, "polyline point");
      if (!in.failed() && n < 2) in.fail("polyline has fewer than 2 points");
      std::vector<Vec3> points;
      points.reserve(n);
      for (std::size_t i = 0; i < n && !in.failed(); ++i) points.push_back(vec3(in));
      const double tolerance = number(in);
      if (in.failed()) return nullptr;
      return std::make_shared<PolylineCurve>(std::move(points), tolerance);
    }
    case static_cast<std::uint8_t>(CurveKind::Trig): {
      const Vec3 center = vec3(in);
      const Vec3 a = vec3(in);
      const Vec3 b = vec3(in);
      if (in.failed()) return nullptr;
      if (!(a.cross(b).squaredNorm() > 0.0)) {
        in.fail("trig curve has parallel semi-diameters");
        return nullptr;
      }
      return std::make_shared<TrigCurve>(center, a, b);
    }
    default:
      in.fail("unknown curve kind " + std::to_string(kind));
      return nullptr;
  }
}

std::optional<Error> Decoder::curves(const Sections::Payload& s) {
  if (!s.present) return std::nullopt;
  recent_ = {};
  ByteReader in(s.bytes, s.offset);
  const std::size_t n = in.count(1, "curve");
  curves_.reserve(n);
  for (std::size_t i = 0; i < n && !in.failed(); ++i) curves_.push_back(curve(in));
  return finish(in, "curves");
}

SurfacePtr Decoder::surface(ByteReader& in) {
  const std::uint8_t kind = in.byte();
  auto positive = [&in](double v, const char* what) {
    if (!in.failed() && !(v > 0.0)) in.fail(std::string(what) + " is not > 0");
    return !in.failed();
  };
  switch (kind) {
    case static_cast<std::uint8_t>(SurfaceKind::Plane): {
      const Frame f = frame(in);
      if (in.failed()) return nullptr;
      return std::make_shared<PlaneSurface>(f);
    }
    case static_cast<std::uint8_t>(SurfaceKind::Cylinder): {
      const Frame f = frame(in);
      const double radius = number(in);
      if (!positive(radius, "cylinder radius")) return nullptr;
      return std::make_shared<CylinderSurface>(f, radius);
    }
    case static_cast<std::uint8_t>(SurfaceKind::Cone): {
      const Frame f = frame(in);
      const double radius = number(in);
      const double semi_angle = number(in);
      if (in.failed()) return nullptr;
      if (!(std::abs(semi_angle) < 0.5 * std::numbers::pi)) {
        in.fail("cone semi-angle is not in (-pi/2, pi/2)");
        return nullptr;
      }
      return std::make_shared<ConeSurface>(f, radius, semi_angle);
    }
    case static_cast<std::uint8_t>(SurfaceKind::Sphere): {
      const Frame f = frame(in);
      const double radius = number(in);
      if (!positive(radius, "sphere radius")) return nullptr;
      return std::make_shared<SphereSurface>(f, radius);
    }
    case static_cast<std::uint8_t>(SurfaceKind::Torus): {
      const Frame f = frame(in);
      const double major = number(in);
      const double minor = number(in);
      if (!positive(major, "torus major radius") || !positive(minor, "torus minor radius")) {
        return nullptr;
      }
      return std::make_shared<TorusSurface>(f, major, minor);
    }
    case static_cast<std::uint8_t>(SurfaceKind::Extrusion): {
      const std::size_t basis = in.index(curves_.size(), "curve");
      const Vec3 direction = vec3(in);
      if (in.failed()) return nullptr;
      if (!usable_direction(direction)) {
        in.fail("extrusion direction is zero");
        return nullptr;
      }
      auto extrusion = std::make_shared<ExtrusionSurface>(curves_[basis], direction);
      if (!canonical(in, direction, extrusion->direction())) return nullptr;
      return extrusion;
    }
    case static_cast<std::uint8_t>(SurfaceKind::Revolution): {
      const std::size_t meridian = in.index(curves_.size(), "curve");
      const Vec3 origin = vec3(in);
      const Vec3 direction = vec3(in);
      if (in.failed()) return nullptr;
      if (!usable_direction(direction)) {
        in.fail("revolution axis direction is zero");
        return nullptr;
      }
      auto revolution = std::make_shared<RevolutionSurface>(curves_[meridian], origin, direction);
      if (!canonical(in, direction, revolution->axis_direction())) return nullptr;
      return revolution;
    }
    default:
      in.fail("unknown surface kind " + std::to_string(kind));
      return nullptr;
  }
}

std::optional<Error> Decoder::surfaces(const Sections::Payload& s) {
  if (!s.present) return std::nullopt;
  recent_ = {};
  ByteReader in(s.bytes, s.offset);
  const std::size_t n = in.count(1, "surface");
  surfaces_.reserve(n);
  for (std::size_t i = 0; i < n && !in.failed(); ++i) surfaces_.push_back(surface(in));
  return finish(in, "surfaces");
}

Curve2dPtr Decoder::pcurve(ByteReader& in) {
  const std::uint8_t kind = in.byte();
  switch (kind) {
    case detail::kPcurveLine: {
      const Vec2 origin = vec2(in);
      const Vec2 direction = vec2(in);
      if (in.failed()) return nullptr;
      return std::make_shared<Line2d>(origin, direction);
    }
    case detail::kPcurveCircle:
    case detail::kPcurveClockwiseCircle: {
      const Vec2 center = vec2(in);
      const double radius = number(in);
      if (in.failed()) return nullptr;
      if (!(radius > 0.0)) {
        in.fail("pcurve circle radius is not > 0");
        return nullptr;
      }
      return std::make_shared<Circle2d>(center, radius, kind == detail::kPcurveCircle ? 1 : -1);
    }
    case detail::kPcurvePolyline: {
      const std::size_t n = in.count(2, "pcurve polyline point");
      if (!in.failed() && n < 2) in.fail("pcurve polyline has fewer than 2 points");
      std::vector<Vec2> points;
      points.reserve(n);
      for (std::size_t i = 0; i < n && !in.failed(); ++i) points.push_back(vec2(in));
      if (in.failed()) return nullptr;
      return std::make_shared<Polyline2d>(std::move(points));
    }
    case detail::kPcurveTrig: {
      const Vec2 c = vec2(in);
      const Vec2 a = vec2(in);
      const Vec2 b = vec2(in);
      const Vec2 d = vec2(in);
      if (in.failed()) return nullptr;
      return std::make_shared<Trig2d>(c, a, b, d);
    }
    default:
      in.fail("unknown pcurve kind " + std::to_string(kind));
      return nullptr;
  }
}

std::optional<Error> Decoder::pcurves(const Sections::Payload& s) {
  if (!s.present) return std::nullopt;
  recent_ = {};
  ByteReader in(s.bytes, s.offset);
  const std::size_t n = in.count(1, "pcurve");
  pcurves_.reserve(n);
  for (std::size_t i = 0; i < n && !in.failed(); ++i) pcurves_.push_back(pcurve(in));
  return finish(in, "pcurves");
}

std::optional<Shape> Decoder::ref(ByteReader& in, std::uint64_t head, std::size_t from) {
  if (in.failed()) return std::nullopt;
  const std::uint64_t delta = head >> detail::kRefShift;
  if (delta == 0 || delta > from) {
    in.fail("reference to body " + std::to_string(from) + " - " + std::to_string(delta) +
            " is not an earlier body");
    return std::nullopt;
  }
  const auto orientation = static_cast<Orientation>(head & detail::kRefOrientationMask);
  Location location;
  if ((head & detail::kRefHasLocation) != 0) {
    const std::size_t l = in.index(locations_.size(), "location");
    if (in.failed()) return std::nullopt;
    location = locations_[l];
  }
  child_bodies_.push_back(static_cast<std::size_t>(from - delta));
  return bodies_[from - delta].located(location).oriented(orientation);
}

std::optional<Shape> Decoder::body(ByteReader& in, std::size_t index, std::string& factory_error) {
  const std::uint64_t head = in.varint();
  const auto kind = static_cast<ShapeKind>(head & detail::kBodyKindMask);
  const std::uint64_t child_count = head >> detail::kBodyHeadShift;
  // Every reference takes at least one byte.
  if (!in.failed() && child_count > in.remaining()) in.fail("child count exceeds the input");
  if (in.failed()) return std::nullopt;

  auto read_children = [&](std::vector<Shape>& out) {
    out.reserve(static_cast<std::size_t>(child_count));
    for (std::uint64_t c = 0; c < child_count && !in.failed(); ++c) {
      if (auto child = ref(in, in.varint(), index)) out.push_back(std::move(*child));
    }
    return !in.failed();
  };
  auto factory = [&](Result<Shape> made) -> std::optional<Shape> {
    if (made.ok()) return std::move(made).value();
    factory_error = made.error().message;
    return std::nullopt;
  };

  std::vector<Shape> children;
  switch (kind) {
    case ShapeKind::Vertex: {
      const Vec3 point = vec3(in);
      const double tolerance = number(in);
      if (!in.failed() && child_count != 0) in.fail("a vertex has no children");
      if (in.failed()) return std::nullopt;
      return factory(ShapeFactory::vertex(point, tolerance));
    }
    case ShapeKind::Edge: {
      const std::uint64_t curve_ref = in.varint();
      const double first = number(in);
      const double last = number(in);
      const double tolerance = number(in);
      if (!in.failed() && child_count != 2) in.fail("an edge has two children");
      if (!in.failed() && curve_ref > curves_.size()) in.fail("edge curve index out of range");
      if (!read_children(children)) return std::nullopt;
      // ShapeFactory makes the start Forward and the end Reversed; other values would not
      // survive a round trip.
      if (children[0].orientation() != Orientation::Forward ||
          children[1].orientation() != Orientation::Reversed) {
        in.fail("edge vertices must be Forward then Reversed");
        return std::nullopt;
      }
      if (curve_ref == 0) {
        if (!children[0].is_same(children[1])) {
          in.fail("a degenerate edge has one vertex at both ends");
          return std::nullopt;
        }
        return factory(ShapeFactory::degenerate_edge(children[0], first, last, tolerance));
      }
      return factory(ShapeFactory::edge(curves_[curve_ref - 1], first, last, children[0],
                                        children[1], tolerance));
    }
    case ShapeKind::Face: {
      const std::size_t surface = in.index(surfaces_.size(), "surface");
      const double tolerance = number(in);
      if (!read_children(children)) return std::nullopt;
      std::size_t uses = 0;
      for (const Shape& wire : children) {
        if (wire.kind() != ShapeKind::Wire) {
          in.fail("a face is bounded by wires");
          return std::nullopt;
        }
        uses += wire.child_count();
      }
      // A run k + 1 names pcurves k .. k + uses − 1; 0 is followed by one index per use.
      const std::uint64_t run = in.varint();
      if (!in.failed() && run == 0 && uses > in.remaining()) {
        in.fail("pcurve count exceeds the input");
      }
      if (!in.failed() && run != 0 &&
          (run - 1 > pcurves_.size() || uses > pcurves_.size() - (run - 1))) {
        in.fail("pcurve run out of range");
      }
      std::vector<std::vector<Curve2dPtr>> pcurves(children.size());
      std::size_t next = run == 0 ? 0 : static_cast<std::size_t>(run - 1);
      for (std::size_t w = 0; w < children.size() && !in.failed(); ++w) {
        const std::size_t edges = children[w].child_count();
        pcurves[w].reserve(edges);
        for (std::size_t e = 0; e < edges && !in.failed(); ++e) {
          const std::size_t p = run == 0 ? in.index(pcurves_.size(), "pcurve") : next++;
          if (!in.failed()) pcurves[w].push_back(pcurves_[p]);
        }
      }
      if (in.failed()) return std::nullopt;
      return factory(ShapeFactory::face(surfaces_[surface], std::move(children), std::move(pcurves),
                                        tolerance));
    }
    case ShapeKind::Wire:
      if (!read_children(children)) return std::nullopt;
      return factory(ShapeFactory::wire(std::move(children)));
    case ShapeKind::Shell:
      if (!read_children(children)) return std::nullopt;
      return factory(ShapeFactory::shell(std::move(children)));
    case ShapeKind::Solid:
      if (!read_children(children)) return std::nullopt;
      return factory(ShapeFactory::solid(std::move(children)));
    case ShapeKind::CompSolid:
      if (!read_children(children)) return std::nullopt;
      return factory(ShapeFactory::compsolid(std::move(children)));
    case ShapeKind::Compound:
      if (!read_children(children)) return std::nullopt;
      return factory(ShapeFactory::compound(std::move(children)));
  }
  in.fail("unknown shape kind");
  return std::nullopt;
}

Result<Shape> Decoder::bodies(const Sections::Payload& s) {
  if (!s.present) return corrupt("the body section is missing");
  recent_ = {};
  ByteReader in(s.bytes, s.offset);
  const std::size_t n = in.count(1, "body");
  bodies_.reserve(n);
  depth_.reserve(n);
  for (std::size_t i = 0; i < n && !in.failed(); ++i) {
    const std::size_t start = in.offset();
    child_bodies_.clear();
    std::string factory_error;
    std::optional<Shape> made = body(in, i, factory_error);
    if (!made) {
      if (!factory_error.empty()) {
        return corrupt("bodies section: body " + std::to_string(i) + " (at byte " +
                       std::to_string(start) + ") is rejected: " + factory_error);
      }
      if (!in.failed()) in.fail("body " + std::to_string(i) + " is invalid");
      break;
    }
    // Depth from the children's (they precede this body), bounded: destroying a deeply
    // nested shape recurses once per level.
    int depth = 1;
    for (const std::size_t child : child_bodies_) depth = std::max(depth, depth_[child] + 1);
    if (depth > detail::kMaxNestingDepth) {
      in.fail("body " + std::to_string(i) + " nests deeper than " +
              std::to_string(detail::kMaxNestingDepth) + " levels");
      break;
    }
    bodies_.push_back(std::move(*made));
    depth_.push_back(depth);
  }
  Shape root;
  if (!in.failed()) {
    const std::uint64_t head = in.varint();
    if (!in.failed() && head != 0) {
      if (auto r = ref(in, head, bodies_.size())) root = std::move(*r);
    }
  }
  if (auto error = finish(in, "bodies")) return *error;
  return root;
}

}  // namespace

Result<Shape> read_native(std::string_view bytes) {
  detail::NativeExtra none;
  return detail::read_native_with(bytes, none);
}

Result<Shape> detail::read_native_with(std::string_view bytes, NativeExtra& extra) {
  constexpr std::size_t kMagicSize = sizeof detail::kNativeMagic;
  if (bytes.size() < kMagicSize ||
      bytes.substr(0, kMagicSize) != std::string_view(detail::kNativeMagic, kMagicSize)) {
    return corrupt("bad magic (not a csgtile native file)");
  }
  ByteReader header(bytes.substr(kMagicSize), kMagicSize);
  const std::uint64_t version = header.varint();
  const std::uint64_t flags = header.varint();
  if (!header.failed() && version != kNativeFormatVersion) {
    return Error{ErrorCode::UnsupportedVersion,
                 "native format: version " + std::to_string(version) +
                     " (this build reads version " + std::to_string(kNativeFormatVersion) + ")"};
  }
  if (!header.failed() && flags != 0) {
    return Error{ErrorCode::UnsupportedVersion,
                 "native format: unknown flags " + std::to_string(flags)};
  }
  const std::size_t body_start = header.offset();
  if (header.failed() || bytes.size() < body_start + detail::kNativeChecksumSize) {
    return corrupt("truncated header");
  }

  const std::size_t checked_size = bytes.size() - detail::kNativeChecksumSize;
  ByteReader trailer(bytes.substr(checked_size), checked_size);
  const std::uint32_t stored = trailer.u32le();
  const std::uint32_t computed = crc32c(bytes.substr(0, checked_size));
  if (stored != computed) {
    return corrupt("checksum mismatch (file truncated or damaged)");
  }

  Sections sections;
  ByteReader framing(bytes.substr(body_start, checked_size - body_start), body_start);
  std::uint64_t previous_tag = 0;
  bool first = true;
  while (!framing.failed() && !framing.at_end()) {
    const std::size_t section_start = framing.offset();
    const std::uint64_t tag = framing.varint();
    const std::uint64_t length = framing.varint();
    if (!framing.failed() && length > framing.remaining())
      framing.fail("section overruns the file");
    if (framing.failed()) break;
    const std::size_t payload_offset = framing.offset();
    const std::string_view payload = framing.take(static_cast<std::size_t>(length));
    if (!first && tag <= previous_tag) {
      return corrupt("section tag " + std::to_string(tag) + " (at byte " +
                     std::to_string(section_start) + ") is out of order or repeated");
    }
    first = false;
    previous_tag = tag;
    if (Sections::Payload* known = sections.find(tag)) {
      *known = {payload, payload_offset, true};
    } else if (extra.tag != 0 && tag == extra.tag) {
      extra.payload = payload;
      extra.offset = payload_offset;
      extra.present = true;
    } else if (!detail::is_optional_tag(tag)) {
      return Error{ErrorCode::UnsupportedVersion,
                   "native format: required section " + std::to_string(tag) + " (at byte " +
                       std::to_string(section_start) + ") is unknown to this reader"};
    }  // unknown optional sections are skipped
  }
  if (framing.failed()) return corrupt("section framing: " + framing.error());

  Decoder decoder;
  if (auto e = decoder.numbers(sections.numbers)) return *e;
  if (auto e = decoder.locations(sections.locations)) return *e;
  if (auto e = decoder.curves(sections.curves)) return *e;
  if (auto e = decoder.surfaces(sections.surfaces)) return *e;
  if (auto e = decoder.pcurves(sections.pcurves)) return *e;
  return decoder.bodies(sections.bodies);
}

}  // namespace csgtile::kernel
