// RayCaster: a bounding volume hierarchy over the primitives' world bounds (median splits
// along the longest axis of the centroids, two primitives per leaf) and an infinite ground
// plane. Traversal visits the nearer child first and skips boxes beyond the best hit so far.

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>

#include "synth/ray_internal.h"

namespace csgtile::geo {

using kernel::Vec3;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr int kLeafSize = 2;

struct Node {
  kernel::BoundingBox box;
  int left = -1;  // children of an inner node
  int right = -1;
  int first = 0;  // leaf: primitives order_[first, first + count)
  int count = 0;
};

// Entry distance of the ray into `box` if it meets it within [0, t_max], else +inf.
double enter(const kernel::BoxRay& ray, const kernel::BoundingBox& box, double t_max) {
  double t0 = 0.0, t1 = t_max;
  return ray.clip(box, t0, t1) ? t0 : kInf;
}

}  // namespace

struct RayCaster::Impl {
  std::vector<detail::PreparedPrimitive> primitives;
  std::optional<double> ground_z;
  std::vector<Node> nodes;
  std::vector<int> order;

  int build(int first, int count) {
    Node node;
    kernel::BoundingBox centroids;
    for (int i = first; i < first + count; ++i) {
      const auto& b =
          primitives[static_cast<std::size_t>(order[static_cast<std::size_t>(i)])].world_bounds;
      node.box.add(b);
      centroids.add(0.5 * (b.min + b.max));
    }
    const int index = static_cast<int>(nodes.size());
    nodes.push_back(node);
    if (count <= kLeafSize) {
      nodes[static_cast<std::size_t>(index)].first = first;
      nodes[static_cast<std::size_t>(index)].count = count;
      return index;
    }
    int axis = 0;
    const Vec3 extent = centroids.size();
    if (extent.y() > extent[axis]) axis = 1;
    if (extent.z() > extent[axis]) axis = 2;
    auto centre = [&](int i) {
      const auto& b = primitives[static_cast<std::size_t>(i)].world_bounds;
      return b.min[axis] + b.max[axis];
    };
    // Ties broken by index: the tree does not depend on the sort's algorithm.
    const auto begin = order.begin() + first;
    std::nth_element(begin, begin + count / 2, begin + count, [&](int a, int b) {
      const double ca = centre(a), cb = centre(b);
      return ca < cb || (ca == cb && a < b);
    });
    const int left = build(first, count / 2);
    const int right = build(first + count / 2, count - count / 2);
    nodes[static_cast<std::size_t>(index)].left = left;
    nodes[static_cast<std::size_t>(index)].right = right;
    return index;
  }
};

RayCaster::RayCaster(const std::vector<kernel::PrimitiveSpec>& primitives,
                     std::optional<double> ground_z)
    : impl_(std::make_unique<Impl>()) {
  impl_->ground_z = ground_z;
  impl_->primitives.reserve(primitives.size());
  for (const auto& spec : primitives) impl_->primitives.push_back(detail::prepare_primitive(spec));
  impl_->order.resize(primitives.size());
  std::iota(impl_->order.begin(), impl_->order.end(), 0);
  if (!primitives.empty()) impl_->build(0, static_cast<int>(primitives.size()));
}

RayCaster::~RayCaster() = default;
RayCaster::RayCaster(RayCaster&&) noexcept = default;
RayCaster& RayCaster::operator=(RayCaster&&) noexcept = default;

std::size_t RayCaster::size() const { return impl_->primitives.size(); }

std::optional<RayHit> RayCaster::first_hit(const Vec3& origin, const Vec3& direction,
                                           double t_max) const {
  std::optional<RayHit> best;
  double limit = t_max;
  if (impl_->ground_z && direction.z() < 0.0 && origin.z() > *impl_->ground_z) {
    const double t = (*impl_->ground_z - origin.z()) / direction.z();
    if (t <= limit) {
      best = RayHit{t, -1, Vec3::UnitZ()};
      limit = t;
    }
  }
  if (impl_->nodes.empty()) return best;
  const kernel::BoxRay ray(origin, direction);
  std::array<int, 128> stack{};
  int top = 0;
  if (enter(ray, impl_->nodes[0].box, limit) < kInf) stack[static_cast<std::size_t>(top++)] = 0;
  while (top > 0) {
    const Node& node =
        impl_->nodes[static_cast<std::size_t>(stack[static_cast<std::size_t>(--top)])];
    if (enter(ray, node.box, limit) == kInf) continue;  // the best hit moved closer
    if (node.count > 0) {
      for (int i = node.first; i < node.first + node.count; ++i) {
        const int index = impl_->order[static_cast<std::size_t>(i)];
        auto hit = detail::hit_primitive(impl_->primitives[static_cast<std::size_t>(index)], origin,
                                         direction, 0.0, limit);
        if (hit && (!best || hit->t < best->t ||
                    (hit->t == best->t && best->primitive >= 0 && index < best->primitive))) {
          hit->primitive = index;
          best = hit;
          limit = hit->t;
        }
      }
      continue;
    }
    const double t_left = enter(ray, impl_->nodes[static_cast<std::size_t>(node.left)].box, limit);
    const double t_right =
        enter(ray, impl_->nodes[static_cast<std::size_t>(node.right)].box, limit);
    // Push the farther child first so that the nearer one is visited first.
    const bool left_first = t_left <= t_right;
    const int near_child = left_first ? node.left : node.right;
    const int far_child = left_first ? node.right : node.left;
    const double t_near = std::min(t_left, t_right);
    const double t_far = std::max(t_left, t_right);
    if (t_far < kInf) stack[static_cast<std::size_t>(top++)] = far_child;
    if (t_near < kInf) stack[static_cast<std::size_t>(top++)] = near_child;
  }
  return best;
}

bool RayCaster::inside(const Vec3& point) const {
  for (const auto& p : impl_->primitives) {
    if (p.world_bounds.contains(point) && detail::primitive_contains(p, point)) return true;
  }
  return false;
}

std::optional<RayHit> intersect_primitive(const kernel::PrimitiveSpec& spec, const Vec3& origin,
                                          const Vec3& direction, double t_min, double t_max) {
  return detail::hit_primitive(detail::prepare_primitive(spec), origin, direction, t_min, t_max);
}

bool primitive_contains(const kernel::PrimitiveSpec& spec, const Vec3& point) {
  return detail::primitive_contains(detail::prepare_primitive(spec), point);
}

}  // namespace csgtile::geo
