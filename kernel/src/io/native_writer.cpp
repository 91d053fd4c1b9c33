// Native format writer: gathers the tables a shape references (bodies in post-order,
// geometry and locations in first-use order), then encodes them twice — once to count how
// often each number is used, once to emit with the most used numbers on the shortest
// indices. Layout: native_layout.h.

#include <algorithm>
#include <array>
#include <compare>
#include <cstdint>
#include <map>
#include <string>
#include <unordered_map>
#include <vector>

#include "csgtile/kernel/native_format.h"
#include "io/byte_stream.h"
#include "io/native_layout.h"
#include "io/unit_direction.h"

namespace csgtile::kernel {

namespace {

using detail::ByteWriter;
using detail::double_bits;
using detail::SectionTag;

// ---- locations --------------------------------------------------------------------------

/// The exact bits of a location, in the order they are written.
using LocationKey = std::array<std::uint64_t, 13>;

LocationKey location_key(const Location& location) {
  LocationKey key{};
  std::size_t k = 0;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) key[k++] = double_bits(location.rotation()(i, j));
  }
  key[k++] = double_bits(location.scale());
  for (int i = 0; i < 3; ++i) key[k++] = double_bits(location.translation()[i]);
  return key;
}

// ---- tables -----------------------------------------------------------------------------

/// Everything a shape references, indexed. Bodies are in post-order (children first, in
/// child order); curves, surfaces, pcurves and locations in order of first use while the
/// bodies are listed. Pointer-keyed maps are only looked up, never iterated.
struct ModelTables {
  std::vector<const ShapeBody*> bodies;
  std::unordered_map<const ShapeBody*, std::size_t> body_index;
  std::vector<Location> locations;
  std::map<LocationKey, std::size_t> location_index;
  std::vector<const Curve*> curves;
  std::unordered_map<const Curve*, std::size_t> curve_index;
  std::vector<const Surface*> surfaces;
  std::unordered_map<const Surface*, std::size_t> surface_index;
  std::vector<const Curve2d*> pcurves;
  std::unordered_map<const Curve2d*, std::size_t> pcurve_index;
  /// Stored direction (unit_preimage) of each line, extrusion and revolution.
  std::unordered_map<const void*, Vec3> stored_direction;

  void add_location(const Location& location) {
    if (location.is_identity()) return;  // exact: a Location stores no identity, no -0.0
    if (location_index.try_emplace(location_key(location), locations.size()).second) {
      locations.push_back(location);
    }
  }

  void add_curve(const Curve* curve) {
    if (!curve_index.try_emplace(curve, curves.size()).second) return;
    curves.push_back(curve);
    if (curve->kind() == CurveKind::Line) {
      stored_direction[curve] =
          detail::stored_unit_direction(static_cast<const LineCurve*>(curve)->direction());
    }
  }

  void add_surface(const Surface* surface) {
    if (surface_index.contains(surface)) return;
    if (surface->kind() == SurfaceKind::Extrusion) {
      const auto* extrusion = static_cast<const ExtrusionSurface*>(surface);
      add_curve(extrusion->basis().get());
      stored_direction[surface] = detail::stored_unit_direction(extrusion->direction());
    } else if (surface->kind() == SurfaceKind::Revolution) {
      const auto* revolution = static_cast<const RevolutionSurface*>(surface);
      add_curve(revolution->meridian().get());
      stored_direction[surface] = detail::stored_unit_direction(revolution->axis_direction());
    }
    surface_index.emplace(surface, surfaces.size());
    surfaces.push_back(surface);
  }

  void add_pcurve(const Curve2d* pcurve) {
    if (pcurve_index.try_emplace(pcurve, pcurves.size()).second) pcurves.push_back(pcurve);
  }

  /// Called once per body, after all its children.
  void add_body(const ShapeBody* body) {
    body_index.emplace(body, bodies.size());
    bodies.push_back(body);
    for (const Shape& child : body->children()) add_location(child.location());
    if (const EdgeData* edge = body->edge(); edge != nullptr && edge->curve) {
      add_curve(edge->curve.get());
    }
    if (const FaceData* face = body->face()) {
      add_surface(face->surface.get());
      for (const auto& wire : face->pcurves) {
        for (const Curve2dPtr& pcurve : wire) add_pcurve(pcurve.get());
      }
    }
  }

  explicit ModelTables(const Shape& root) {
    if (root.is_null()) return;
    // Iterative post-order walk: nesting depth is unbounded in memory.
    struct Pending {
      const ShapeBody* body;
      std::size_t next_child;
    };
    std::vector<Pending> stack{{&root.body(), 0}};
    while (!stack.empty()) {
      Pending& top = stack.back();
      const auto& children = top.body->children();
      if (top.next_child < children.size()) {
        const ShapeBody* child = &children[top.next_child++].body();
        // Bodies form a DAG (a body is built before its parents), so a body met again is
        // already finished.
        if (!body_index.contains(child)) stack.push_back({child, 0});
        continue;
      }
      add_body(top.body);
      stack.pop_back();
    }
    add_location(root.location());
  }
};

// ---- numbers ----------------------------------------------------------------------------

/// Counts uses of number bit patterns, then gives the most used the smallest indices (ties:
/// first use).
class NumberPool {
 public:
  void count(std::uint64_t bits) {
    auto [it, inserted] = uses_.try_emplace(bits, Use{0, uses_.size(), 0});
    ++it->second.count;
  }

  // The indices are kept in the counting map itself (one map for both passes).
  void assign_indices() {
    order_.clear();
    order_.reserve(uses_.size());
    for (const auto& [bits, use] : uses_) order_.emplace_back(bits, use);
    std::sort(order_.begin(), order_.end(), [](const auto& a, const auto& b) {
      if (a.second.count != b.second.count) return a.second.count > b.second.count;
      return a.second.first_use < b.second.first_use;
    });
    for (std::size_t i = 0; i < order_.size(); ++i) uses_.at(order_[i].first).index = i;
  }

  std::size_t size() const { return order_.size(); }
  std::uint64_t bits(std::size_t i) const { return order_[i].first; }
  std::size_t index_of(std::uint64_t bits) const { return uses_.at(bits).index; }

 private:
  struct Use {
    std::size_t count;
    std::size_t first_use;
    std::size_t index;  // set by assign_indices
  };
  std::unordered_map<std::uint64_t, Use> uses_;
  std::vector<std::pair<std::uint64_t, Use>> order_;
};

/// Writes one section payload. In the counting pass numbers are only counted (the bytes
/// are thrown away); in the emitting pass they become indices into the sorted pool.
class PayloadEncoder {
 public:
  PayloadEncoder(NumberPool& pool, bool counting) : pool_(pool), counting_(counting) {}

  // The counting pass's bytes are thrown away: it does not write them.
  void byte(std::uint8_t v) {
    if (!counting_) out_.byte(v);
  }
  void varint(std::uint64_t v) {
    if (!counting_) out_.varint(v);
  }
  /// A reference to |v| (a recent-window position or a pool index, see native_layout.h),
  /// shifted left once, with the sign in bit 0: v and −v share one entry.
  void number(double v) {
    const std::uint64_t bits = double_bits(v);
    const std::uint64_t magnitude = bits & ~detail::kSignBit;
    if (counting_) {
      pool_.count(magnitude);
      return;
    }
    const std::size_t index = pool_.index_of(magnitude);
    const std::size_t position = recent_.find(index);
    const std::uint64_t code =
        position < recent_.size() ? position : detail::RecentNumbers::kCapacity + index;
    out_.varint((code << 1) | (bits >> 63));
    recent_.use(index);
  }
  void vec2(const Vec2& v) {
    number(v.x());
    number(v.y());
  }
  void vec3(const Vec3& v) {
    number(v.x());
    number(v.y());
    number(v.z());
  }
  void frame(const Frame& f) {
    vec3(f.origin);
    vec3(f.x);
    vec3(f.y);
    vec3(f.z);
  }
  std::string take() { return out_.take(); }

 private:
  NumberPool& pool_;
  bool counting_;
  ByteWriter out_;
  detail::RecentNumbers recent_;  // one encoder per section payload: starts empty
};

void encode_locations(const ModelTables& t, PayloadEncoder& e) {
  e.varint(t.locations.size());
  for (const Location& location : t.locations) {
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) e.number(location.rotation()(i, j));
    }
    e.number(location.scale());
    e.vec3(location.translation());
  }
}

void encode_curves(const ModelTables& t, PayloadEncoder& e) {
  e.varint(t.curves.size());
  for (const Curve* curve : t.curves) {
    e.byte(static_cast<std::uint8_t>(curve->kind()));
    switch (curve->kind()) {
      case CurveKind::Line: {
        const auto* line = static_cast<const LineCurve*>(curve);
        e.vec3(line->origin());
        e.vec3(t.stored_direction.at(curve));
        break;
      }
      case CurveKind::Circle: {
        const auto* circle = static_cast<const CircleCurve*>(curve);
        e.frame(circle->frame());
        e.number(circle->radius());
        break;
      }
      case CurveKind::Ellipse: {
        const auto* ellipse = static_cast<const EllipseCurve*>(curve);
        e.frame(ellipse->frame());
        e.number(ellipse->major_radius());
        e.number(ellipse->minor_radius());
        break;
      }
      case CurveKind::Polyline: {
        const auto* polyline = static_cast<const PolylineCurve*>(curve);
        e.varint(polyline->points().size());
        for (const Vec3& p : polyline->points()) e.vec3(p);
        e.number(polyline->tolerance());
        break;
      }
      case CurveKind::Trig: {
        const auto* trig = static_cast<const TrigCurve*>(curve);
        e.vec3(trig->center());
        e.vec3(trig->a());
        e.vec3(trig->b());
        break;
      }
    }
  }
}

void encode_surfaces(const ModelTables& t, PayloadEncoder& e) {
  e.varint(t.surfaces.size());
  for (const Surface* surface : t.surfaces) {
    e.byte(static_cast<std::uint8_t>(surface->kind()));
    switch (surface->kind()) {
      case SurfaceKind::Plane:
        e.frame(static_cast<const PlaneSurface*>(surface)->frame());
        break;
      case SurfaceKind::Cylinder: {
        const auto* cylinder = static_cast<const CylinderSurface*>(surface);
        e.frame(cylinder->frame());
        e.number(cylinder->radius());
        break;
      }
      case SurfaceKind::Cone: {
        const auto* cone = static_cast<const ConeSurface*>(surface);
        e.frame(cone->frame());
        e.number(cone->reference_radius());
        e.number(cone->semi_angle());
        break;
      }
      case SurfaceKind::Sphere: {
        const auto* sphere = static_cast<const SphereSurface*>(surface);
        e.frame(sphere->frame());
        e.number(sphere->radius());
        break;
      }
      case SurfaceKind::Torus: {
        const auto* torus = static_cast<const TorusSurface*>(surface);
        e.frame(torus->frame());
        e.number(torus->major_radius());
        e.number(torus->minor_radius());
        break;
      }
      case SurfaceKind::Extrusion: {
        const auto* extrusion = static_cast<const ExtrusionSurface*>(surface);
        e.varint(t.curve_index.at(extrusion->basis().get()));
        e.vec3(t.stored_direction.at(surface));
        break;
      }
      case SurfaceKind::Revolution: {
        const auto* revolution = static_cast<const RevolutionSurface*>(surface);
        e.varint(t.curve_index.at(revolution->meridian().get()));
        e.vec3(revolution->axis_origin());
        e.vec3(t.stored_direction.at(surface));
        break;
      }
    }
  }
}

void encode_pcurves(const ModelTables& t, PayloadEncoder& e) {
  e.varint(t.pcurves.size());
  for (const Curve2d* pcurve : t.pcurves) {
    switch (pcurve->kind()) {
      case Curve2dKind::Line: {
        const auto* line = static_cast<const Line2d*>(pcurve);
        e.byte(detail::kPcurveLine);
        e.vec2(line->origin());
        e.vec2(line->direction());
        break;
      }
      case Curve2dKind::Circle: {
        const auto* circle = static_cast<const Circle2d*>(pcurve);
        e.byte(circle->sense() > 0 ? detail::kPcurveCircle : detail::kPcurveClockwiseCircle);
        e.vec2(circle->center());
        e.number(circle->radius());
        break;
      }
      case Curve2dKind::Polyline: {
        const auto* polyline = static_cast<const Polyline2d*>(pcurve);
        e.byte(detail::kPcurvePolyline);
        e.varint(polyline->points().size());
        for (const Vec2& p : polyline->points()) e.vec2(p);
        break;
      }
      case Curve2dKind::Trig: {
        const auto* trig = static_cast<const Trig2d*>(pcurve);
        e.byte(detail::kPcurveTrig);
        e.vec2(trig->c());
        e.vec2(trig->a());
        e.vec2(trig->b());
        e.vec2(trig->d());
        break;
      }
    }
  }
}

/// A reference from the body at `from` (or from the root, `from` = body count).
void encode_ref(const ModelTables& t, std::size_t from, const Shape& ref, PayloadEncoder& e) {
  const std::size_t delta = from - t.body_index.at(&ref.body());
  const bool has_location = !ref.location().is_identity();
  e.varint((static_cast<std::uint64_t>(delta) << detail::kRefShift) |
           (has_location ? detail::kRefHasLocation : 0) |
           static_cast<std::uint64_t>(ref.orientation()));
  if (has_location) e.varint(t.location_index.at(location_key(ref.location())));
}

/// A face's pcurves: k + 1 when they are the table entries k, k + 1, … in order (the usual
/// case: unshared pcurves are listed in first-use order), else 0 and one index per edge use.
void encode_face_pcurves(const ModelTables& t, const FaceData& face, PayloadEncoder& e) {
  std::vector<std::size_t> indices;
  for (const auto& wire : face.pcurves) {
    for (const Curve2dPtr& pcurve : wire) indices.push_back(t.pcurve_index.at(pcurve.get()));
  }
  bool consecutive = !indices.empty();
  for (std::size_t k = 1; k < indices.size() && consecutive; ++k) {
    consecutive = indices[k] == indices[0] + k;
  }
  if (consecutive) {
    e.varint(indices[0] + 1);
    return;
  }
  e.varint(0);
  for (const std::size_t index : indices) e.varint(index);
}

void encode_bodies(const ModelTables& t, const Shape& root, PayloadEncoder& e) {
  e.varint(t.bodies.size());
  for (std::size_t i = 0; i < t.bodies.size(); ++i) {
    const ShapeBody& body = *t.bodies[i];
    const auto& children = body.children();
    e.varint((static_cast<std::uint64_t>(children.size()) << detail::kBodyHeadShift) |
             static_cast<std::uint64_t>(body.kind()));
    if (const VertexData* vertex = body.vertex()) {
      e.vec3(vertex->point);
      e.number(vertex->tolerance);
    } else if (const EdgeData* edge = body.edge()) {
      e.varint(edge->curve ? t.curve_index.at(edge->curve.get()) + 1 : 0);
      e.number(edge->first);
      e.number(edge->last);
      e.number(edge->tolerance);
    } else if (const FaceData* face = body.face()) {
      e.varint(t.surface_index.at(face->surface.get()));
      e.number(face->tolerance);
    }
    for (const Shape& child : children) encode_ref(t, i, child, e);
    if (const FaceData* face = body.face()) encode_face_pcurves(t, *face, e);
  }
  if (root.is_null()) {
    e.varint(0);
  } else {
    encode_ref(t, t.bodies.size(), root, e);
  }
}

struct Payloads {
  std::string locations, curves, surfaces, pcurves, bodies;
};

Payloads encode_payloads(const ModelTables& t, const Shape& root, NumberPool& pool, bool counting) {
  auto run = [&](auto encode) {
    PayloadEncoder e(pool, counting);
    encode(e);
    return e.take();
  };
  Payloads p;
  p.locations = run([&](PayloadEncoder& e) { encode_locations(t, e); });
  p.curves = run([&](PayloadEncoder& e) { encode_curves(t, e); });
  p.surfaces = run([&](PayloadEncoder& e) { encode_surfaces(t, e); });
  p.pcurves = run([&](PayloadEncoder& e) { encode_pcurves(t, e); });
  p.bodies = run([&](PayloadEncoder& e) { encode_bodies(t, root, e); });
  return p;
}

void write_section(ByteWriter& out, SectionTag tag, std::string_view payload) {
  out.varint(static_cast<std::uint64_t>(tag));
  out.varint(payload.size());
  out.bytes(payload);
}

}  // namespace

std::string detail::write_native_with(const Shape& shape, SectionTag extra_tag,
                                      std::string_view extra) {
  const ModelTables tables(shape);
  NumberPool pool;
  (void)encode_payloads(tables, shape, pool, /*counting=*/true);
  pool.assign_indices();
  const Payloads p = encode_payloads(tables, shape, pool, /*counting=*/false);

  ByteWriter numbers;
  numbers.varint(pool.size());
  std::vector<int> lengths(pool.size());
  for (std::size_t i = 0; i < pool.size(); ++i)
    lengths[i] = detail::significant_bytes(pool.bits(i));
  for (std::size_t i = 0; i < pool.size(); i += 2) {
    const int high = i + 1 < pool.size() ? lengths[i + 1] : 0;
    numbers.byte(static_cast<std::uint8_t>(lengths[i] | (high << 4)));
  }
  for (std::size_t i = 0; i < pool.size(); ++i) {
    for (int b = 8 - lengths[i]; b < 8; ++b) {
      numbers.byte(static_cast<std::uint8_t>(pool.bits(i) >> (8 * b)));
    }
  }

  ByteWriter out;
  out.bytes(std::string_view(detail::kNativeMagic, sizeof detail::kNativeMagic));
  out.varint(kNativeFormatVersion);
  out.varint(0);  // flags: none defined in version 1
  // Empty tables are left out (a reader treats an absent table as empty); the body
  // section always is there: it holds the root.
  if (pool.size() > 0) write_section(out, SectionTag::Numbers, numbers.str());
  if (!tables.locations.empty()) write_section(out, SectionTag::Locations, p.locations);
  if (!tables.curves.empty()) write_section(out, SectionTag::Curves, p.curves);
  if (!tables.surfaces.empty()) write_section(out, SectionTag::Surfaces, p.surfaces);
  if (!tables.pcurves.empty()) write_section(out, SectionTag::Pcurves, p.pcurves);
  write_section(out, SectionTag::Bodies, p.bodies);
  if (!extra.empty()) write_section(out, extra_tag, extra);
  out.u32le(crc32c(out.str()));
  return out.take();
}

std::string write_native(const Shape& shape) {
  return detail::write_native_with(shape, SectionTag::Csg, {});
}

}  // namespace csgtile::kernel
