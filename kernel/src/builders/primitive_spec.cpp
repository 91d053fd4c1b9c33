#include "csgtile/kernel/primitives.h"

#include <cmath>
#include <cstring>
#include <list>
#include <mutex>
#include <optional>
#include <string>
#include <unordered_map>
#include <utility>

#include "csgtile/kernel/boolean.h"
#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/mass_properties.h"

namespace csgtile::kernel {

namespace {

// `solid` ∩ {n·p <= d} for each clip: a box standing for the half-space (its top face on the
// plane, the rest well outside the solid's bounding box), intersected exactly.
Result<Shape> apply_clips(Shape solid, const std::vector<Eigen::Vector4d>& clips,
                          double tolerance) {
  for (std::size_t k = 0; k < clips.size(); ++k) {
    const std::string which = "clip " + std::to_string(k);
    const Vec3 n = clips[k].head<3>();
    const double d = clips[k].w();
    if (!n.allFinite() || !std::isfinite(d) || std::abs(n.norm() - 1.0) > 1e-9) {
      return Error{ErrorCode::DegenerateGeometry,
                   which + ": not a unit normal and a finite offset"};
    }
    Vec3 e1 = std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
    e1 = (e1 - e1.dot(n) * n).normalized();
    const Vec3 e2 = n.cross(e1);
    const BoundingBox box = bounding_box(solid);
    if (box.empty() || !(box.max - box.min).allFinite() || (box.max - box.min).maxCoeff() > 1e9) {
      return Error{ErrorCode::DegenerateGeometry, which + ": the solid is too large to clip"};
    }
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int c = 0; c < 8; ++c) {
      const Vec3 p((c & 1) ? box.max.x() : box.min.x(), (c & 2) ? box.max.y() : box.min.y(),
                   (c & 4) ? box.max.z() : box.min.z());
      const double q[3] = {p.dot(e1), p.dot(e2), p.dot(n)};
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min(lo[a], q[a]);
        hi[a] = std::max(hi[a], q[a]);
      }
    }
    const double margin = 1.0 + 0.1 * (box.max - box.min).norm();
    if (d >= hi[2] + tolerance) continue;  // the plane is above the whole solid
    if (d <= lo[2] + tolerance) {
      return Error{ErrorCode::DegenerateGeometry, which + ": removes the whole primitive"};
    }
    Eigen::Matrix3d r;
    r.col(0) = e1;
    r.col(1) = e2;
    r.col(2) = n;
    const Vec3 corner = (lo[0] - margin) * e1 + (lo[1] - margin) * e2 + (lo[2] - margin) * n;
    auto half = make_box(hi[0] - lo[0] + 2 * margin, hi[1] - lo[1] + 2 * margin,
                         d - (lo[2] - margin), tolerance);
    if (!half.ok()) return half.error();
    auto at = Location::from_parts(r, 1.0, corner);
    if (!at.ok()) return at.error();
    BooleanOptions options;
    options.tolerance = tolerance;
    auto cut = boolean_operation(solid, half.value().moved(at.value()), BooleanOp::Common, options);
    if (!cut.ok()) return Error{cut.error().code, which + ": " + cut.error().message};
    const auto solids = map_child_shapes(cut.value(), ShapeKind::Solid);
    if (solids.size() != 1) {
      return Error{ErrorCode::DegenerateGeometry,
                   which + ": leaves " + std::to_string(solids.size()) + " solids, not one"};
    }
    solid = solids[0];
  }
  return solid;
}

// The clipped solids built last, by their local spec (everything but the placement) and
// tolerance. A city run builds each roof part several times — its fit's check, the box that
// puts it in cells, every cell's assembly and CSG check — and each build is an exact
// Boolean; the build is a pure function of the key, so a remembered solid (its bodies shared,
// as a shape's are) is the very one a new build would give. Bounded, least recently used
// first out; errors are remembered too.
class ClipMemo {
 public:
  static ClipMemo& instance() {
    static ClipMemo memo;
    return memo;
  }

  static std::string key(const PrimitiveSpec& spec, double tolerance) {
    std::string k;
    auto put = [&k](const void* data, std::size_t bytes) {
      k.append(static_cast<const char*>(data), bytes);
    };
    auto put_ring = [&](const std::vector<Vec2>& ring) {
      const std::size_t n = ring.size();
      put(&n, sizeof n);
      for (const Vec2& q : ring) put(q.data(), 2 * sizeof(double));
    };
    put(&spec.type, sizeof spec.type);
    put(spec.size.data(), 3 * sizeof(double));
    put(&spec.radius, sizeof(double));
    put(&spec.radius2, sizeof(double));
    put(&spec.height, sizeof(double));
    put(&spec.angle, sizeof(double));
    put(&tolerance, sizeof(double));
    put_ring(spec.profile);
    const std::size_t holes = spec.holes.size();
    put(&holes, sizeof holes);
    for (const auto& hole : spec.holes) put_ring(hole);
    for (const Eigen::Vector4d& c : spec.clips) put(c.data(), 4 * sizeof(double));
    return k;
  }

  std::optional<Result<Shape>> find(const std::string& k) {
    const std::lock_guard<std::mutex> lock(mutex_);
    auto it = entries_.find(k);
    if (it == entries_.end()) return std::nullopt;
    order_.splice(order_.begin(), order_, it->second.second);
    return it->second.first;
  }

  void insert(const std::string& k, const Result<Shape>& built) {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (entries_.count(k) != 0) return;
    order_.push_front(k);
    entries_.emplace(k, std::make_pair(built, order_.begin()));
    if (entries_.size() > kCapacity) {
      entries_.erase(order_.back());
      order_.pop_back();
    }
  }

 private:
  static constexpr std::size_t kCapacity = 2048;  // a few MB of roof parts
  std::mutex mutex_;
  std::list<std::string> order_;  // most recently used first
  std::unordered_map<std::string, std::pair<Result<Shape>, std::list<std::string>::iterator>>
      entries_;
};

}  // namespace

const char* primitive_type_name(PrimitiveType type) {
  switch (type) {
    case PrimitiveType::Box:
      return "box";
    case PrimitiveType::Cylinder:
      return "cylinder";
    case PrimitiveType::Cone:
      return "cone";
    case PrimitiveType::Sphere:
      return "sphere";
    case PrimitiveType::Torus:
      return "torus";
    case PrimitiveType::Extrusion:
      return "extrusion";
    case PrimitiveType::Revolution:
      return "revolution";
  }
  return "unknown";
}

Result<Shape> build_primitive(const PrimitiveSpec& spec, double tolerance) {
  std::string memo_key;
  std::optional<Result<Shape>> remembered;
  if (!spec.clips.empty()) {
    memo_key = ClipMemo::key(spec, tolerance);
    remembered = ClipMemo::instance().find(memo_key);
  }
  Result<Shape> local = remembered ? *remembered : [&]() -> Result<Shape> {
    switch (spec.type) {
      case PrimitiveType::Box:
        return make_box(spec.size.x(), spec.size.y(), spec.size.z(), tolerance);
      case PrimitiveType::Cylinder:
        return make_cylinder(spec.radius, spec.height, tolerance);
      case PrimitiveType::Cone:
        return make_cone(spec.radius, spec.radius2, spec.height, tolerance);
      case PrimitiveType::Sphere:
        return make_sphere(spec.radius, tolerance);
      case PrimitiveType::Torus:
        return make_torus(spec.radius, spec.radius2, tolerance);
      case PrimitiveType::Extrusion:
        return make_extrusion(spec.profile, spec.holes, spec.height, tolerance);
      case PrimitiveType::Revolution:
        return make_revolution(spec.profile, spec.angle, tolerance);
    }
    return Error{ErrorCode::InvalidArgument, "unknown primitive type"};
  }();
  if (!remembered && local.ok() && !spec.clips.empty()) {
    local = apply_clips(local.value(), spec.clips, tolerance);
  }
  if (!remembered && !spec.clips.empty()) ClipMemo::instance().insert(memo_key, local);
  if (!local.ok()) return local;
  if (spec.placement.is_identity()) return local;
  return local.value().moved(spec.placement);
}

}  // namespace csgtile::kernel
