#include "boolean/classifier.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>

#include "boolean/line_surface.h"
#include "boolean/tolerance.h"
#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/polygon2d.h"
#include "predicates/predicates.h"

namespace csgtile::kernel::detail {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
// Initial chords of curved pcurves span at most this parameter step; queries refine further
// only where needed.
constexpr double kInitialStep = std::numbers::pi / 8;
// Refinement depth after which a parameter point still inside an arc's bulge is taken as on
// the boundary (the bulge shrinks fourfold per level, so this is never reached in practice).
constexpr int kMaxRefinement = 60;

BoundingBox moved_box(const BoundingBox& local, const Location& location) {
  BoundingBox out;
  if (local.empty()) return out;
  for (int corner = 0; corner < 8; ++corner) {
    const Vec3 p((corner & 1) ? local.max.x() : local.min.x(),
                 (corner & 2) ? local.max.y() : local.min.y(),
                 (corner & 4) ? local.max.z() : local.min.z());
    out.add(location.apply_point(p));
  }
  return out;
}

// Bound on |c''(t)| of a pcurve (0 when it is straight between its breakpoints).
double second_derivative_bound(const Curve2d& curve) {
  switch (curve.kind()) {
    case Curve2dKind::Line:
    case Curve2dKind::Polyline:
      return 0.0;
    case Curve2dKind::Circle:
      return static_cast<const Circle2d&>(curve).radius();
    case Curve2dKind::Trig: {
      const auto& trig = static_cast<const Trig2d&>(curve);
      return trig.a().norm() + trig.b().norm();
    }
  }
  return 0.0;
}

// Parameters at which a pcurve use is first cut into chords, from t_start to t_end.
void initial_parameters(const Curve2d& curve, double t_start, double t_end,
                        std::vector<double>& out) {
  out.clear();
  out.push_back(t_start);
  switch (curve.kind()) {
    case Curve2dKind::Line:
      break;
    case Curve2dKind::Polyline: {
      // Breakpoints strictly between the ends, in walking order.
      const double lo = std::min(t_start, t_end), hi = std::max(t_start, t_end);
      const std::size_t first = out.size();
      const auto from = static_cast<long long>(std::floor(lo)) + 1;
      for (long long k = from; static_cast<double>(k) < hi; ++k)
        out.push_back(static_cast<double>(k));
      if (t_end < t_start)
        std::reverse(out.begin() + static_cast<std::ptrdiff_t>(first), out.end());
      break;
    }
    case Curve2dKind::Circle:
    case Curve2dKind::Trig: {
      const int n =
          std::max(1, static_cast<int>(std::ceil(std::abs(t_end - t_start) / kInitialStep)));
      for (int k = 1; k < n; ++k) out.push_back(t_start + (t_end - t_start) * k / n);
      break;
    }
  }
  out.push_back(t_end);
}

std::uint64_t splitmix64(std::uint64_t& state) {
  std::uint64_t z = (state += 0x9e3779b97f4a7c15ull);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

// Unit directions uniformly spread over the sphere, a fixed sequence for a seed.
std::vector<Vec3> make_ray_directions(std::uint64_t seed, int count) {
  std::vector<Vec3> out;
  std::uint64_t state = seed;
  for (int i = 0; i < count; ++i) {
    const double a = static_cast<double>(splitmix64(state) >> 11) * 0x1.0p-53;
    const double b = static_cast<double>(splitmix64(state) >> 11) * 0x1.0p-53;
    const double z = 2.0 * a - 1.0;
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    const double phi = 2.0 * std::numbers::pi * b;
    out.emplace_back(r * std::cos(phi), r * std::sin(phi), z);
  }
  return out;
}

// Candidates x + k·period inside [lo − eps, hi + eps] (x itself when not periodic).
int periodic_candidates(double x, double lo, double hi, double period, double eps,
                        std::array<double, 4>& out) {
  if (!(period > 0.0)) {
    out[0] = x;
    return 1;
  }
  const double k0 = std::ceil((lo - eps - x) / period);
  const double k1 = std::floor((hi + eps - x) / period);
  int n = 0;
  if (!(k0 <= k1) || !(std::abs(k0) < 1e15)) return 0;  // none, or too far to mean anything
  const auto first = static_cast<long long>(k0);
  for (long long k = first; static_cast<double>(k) <= k1 && n < static_cast<int>(out.size()); ++k) {
    out[static_cast<std::size_t>(n++)] = x + static_cast<double>(k) * period;
  }
  return n;
}

}  // namespace

const char* containment_name(Containment c) {
  switch (c) {
    case Containment::Inside:
      return "inside";
    case Containment::Outside:
      return "outside";
    case Containment::OnBoundary:
      return "on_boundary";
  }
  return "?";
}

// ---- FaceQuery ----------------------------------------------------------------------------

Vec2 FaceQuery::EdgeUse::point(double t) const {
  const double lambda = t_end != t_start ? (t - t_start) / (t_end - t_start) : 0.0;
  return curve->point(t) + offset + (1.0 - lambda) * gap_start + lambda * gap_end;
}

Result<FaceQuery> FaceQuery::create(const Shape& face) {
  if (face.is_null() || face.kind() != ShapeKind::Face) {
    return Error{ErrorCode::InvalidArgument, "FaceQuery needs a face"};
  }
  const FaceData* data = face.body().face();
  if (data == nullptr || data->surface == nullptr) {
    return Error{ErrorCode::InvalidShape, "face without a surface"};
  }
  FaceQuery q;
  q.face_ = face;
  q.surface_ = data->surface;
  q.location_ = face.location();
  q.inverse_ = face.location().inverse();
  q.outward_sign_ = face.orientation() == Orientation::Reversed ? -1.0 : 1.0;

  const Shape body = face.oriented(Orientation::Forward);
  if (data->pcurves.size() != body.child_count()) {
    return Error{ErrorCode::InvalidShape, "face has a pcurve list per wire mismatch"};
  }
  const double period_u = q.surface_->u_period();
  const double period_v = q.surface_->v_period();
  auto period_steps = [](double gap, double period) {
    return period > 0.0 ? std::round(gap / period) : 0.0;
  };

  struct OpenLoop {
    std::size_t loop;
    Vec2 end, start;
    bool along_u;  // open by a period in u (else in v)
  };
  std::vector<OpenLoop> open_loops;
  std::vector<double> params;
  for (std::size_t w = 0; w < body.child_count(); ++w) {
    const Shape wire = body.child(w);
    if (data->pcurves[w].size() != wire.child_count()) {
      return Error{ErrorCode::InvalidShape, "face has a pcurve count per edge mismatch"};
    }
    // Pass 1: the uses of this wire with their raw ends, shifted into one period run.
    const std::size_t first_use = q.uses_.size();
    std::vector<Vec2> raw_start, raw_end;
    for (std::size_t e = 0; e < wire.child_count(); ++e) {
      const Shape edge = wire.child(e);
      const Orientation o = edge.orientation();
      if (o != Orientation::Forward && o != Orientation::Reversed) continue;
      const EdgeData* ed = edge.body().edge();
      const Curve2dPtr& pcurve = data->pcurves[w][e];
      if (ed == nullptr || pcurve == nullptr) {
        return Error{ErrorCode::InvalidShape, "face has an edge without geometry or pcurve"};
      }
      if (!(ed->first < ed->last)) continue;
      EdgeUse use;
      use.curve = pcurve;
      use.t_start = o == Orientation::Forward ? ed->first : ed->last;
      use.t_end = o == Orientation::Forward ? ed->last : ed->first;
      use.offset = Vec2::Zero();
      use.gap_start = Vec2::Zero();
      use.gap_end = Vec2::Zero();
      use.second = second_derivative_bound(*pcurve);
      Vec2 start = pcurve->point(use.t_start);
      if (!raw_end.empty()) {
        const Vec2 gap = start - raw_end.back();
        use.offset = Vec2(-period_steps(gap.x(), period_u) * period_u,
                          -period_steps(gap.y(), period_v) * period_v);
      }
      raw_start.emplace_back(start + use.offset);
      raw_end.emplace_back(pcurve->point(use.t_end) + use.offset);
      q.uses_.push_back(std::move(use));
    }
    const std::size_t count = q.uses_.size() - first_use;
    if (count == 0) continue;
    const Vec2 closing = raw_start.front() - raw_end.back();
    const double open_u = period_steps(closing.x(), period_u);
    const double open_v = period_steps(closing.y(), period_v);
    const bool open = open_u != 0.0 || open_v != 0.0;
    // Junction points: each use starts where the previous one ended; a closed loop's last
    // use ends where the first one starts. The gaps are blended into the uses.
    for (std::size_t i = 1; i < count; ++i) {
      q.uses_[first_use + i].gap_start = raw_end[i - 1] - raw_start[i];
    }
    if (!open) q.uses_[first_use + count - 1].gap_end = raw_start.front() - raw_end.back();

    // Pass 2: chords.
    std::vector<Piece> loop;
    for (std::size_t i = 0; i < count; ++i) {
      const auto index = static_cast<std::uint32_t>(first_use + i);
      const EdgeUse& use = q.uses_[index];
      initial_parameters(*use.curve, use.t_start, use.t_end, params);
      const Vec2 junction_start = i == 0 ? raw_start.front() : raw_end[i - 1];
      const Vec2 junction_end =
          i + 1 < count ? raw_end[i] : (open ? raw_end[i] : raw_start.front());
      Vec2 a = junction_start;
      for (std::size_t k = 1; k < params.size(); ++k) {
        const Vec2 b = k + 1 == params.size() ? junction_end : use.point(params[k]);
        loop.push_back({use.second > 0.0 ? index : kStraight, params[k - 1], params[k], a, b});
        a = b;
      }
    }
    if (open)
      open_loops.push_back({q.loops_.size(), raw_end.back(), raw_start.front(), open_u != 0.0});
    q.loops_.push_back(std::move(loop));
  }
  if (q.loops_.empty()) return Error{ErrorCode::InvalidShape, "face has no boundary loop"};

  // The domain's box: chords widened by their bulge (closures are not added yet).
  double u0 = kInfinity, u1 = -kInfinity, v0 = kInfinity, v1 = -kInfinity;
  for (const auto& loop : q.loops_) {
    for (const Piece& piece : loop) {
      const double second = piece.use == kStraight ? 0.0 : q.uses_[piece.use].second;
      const double bulge = second * (piece.t1 - piece.t0) * (piece.t1 - piece.t0) / 8.0;
      for (const Vec2& p : {piece.a, piece.b}) {
        u0 = std::min(u0, p.x() - bulge);
        u1 = std::max(u1, p.x() + bulge);
        v0 = std::min(v0, p.y() - bulge);
        v1 = std::max(v1, p.y() + bulge);
      }
    }
  }
  if (!(u0 <= u1 && v0 <= v1) || !std::isfinite(u1 - u0) || !std::isfinite(v1 - v0)) {
    return Error{ErrorCode::InvalidShape, "face boundary has non-finite parameters"};
  }
  q.parameter_box_ = {u0, u1, v0, v1};
  q.uv_epsilon_ =
      kFaceQueryUvRelative *
      (1.0 + std::max({u1 - u0, v1 - v0, std::abs(u0), std::abs(u1), std::abs(v0), std::abs(v1)}));
  // Loops open by a period close far outside the domain, all on the same side (low v for
  // loops around u, low u for loops around v): the even–odd rule then keeps the band between
  // two such loops.
  const double far_v = v0 - (v1 - v0) - 1.0;
  const double far_u = u0 - (u1 - u0) - 1.0;
  for (const OpenLoop& open : open_loops) {
    auto& loop = q.loops_[open.loop];
    const Vec2 p1 = open.along_u ? Vec2(open.end.x(), far_v) : Vec2(far_u, open.end.y());
    const Vec2 p2 = open.along_u ? Vec2(open.start.x(), far_v) : Vec2(far_u, open.start.y());
    loop.push_back({kStraight, 0.0, 1.0, open.end, p1});
    loop.push_back({kStraight, 0.0, 1.0, p1, p2});
    loop.push_back({kStraight, 0.0, 1.0, p2, open.start});
  }

  BoundingBox local = q.surface_->bounds(q.parameter_box_);
  local.enlarge(kBoundsPadRelative * (1.0 + local.size().norm() + local.max.cwiseAbs().maxCoeff() +
                                      local.min.cwiseAbs().maxCoeff()));
  q.local_bounds_ = local;
  q.world_bounds_ = moved_box(local, q.location_);
  return q;
}

std::pair<Vec2, double> FaceQuery::project(const Vec3& p) const {
  const Vec3 local = inverse_.apply_point(p);
  const Vec2 uv = surface_->closest_parameters(local);
  const double distance = (surface_->point(uv.x(), uv.y()) - local).norm() * location_.scale();
  return {uv, distance};
}

Vec3 FaceQuery::outward_normal(const Vec2& uv) const {
  return outward_sign_ * location_.apply_direction(surface_->normal(uv.x(), uv.y()));
}

Containment FaceQuery::locate_uv(const Vec2& uv) const {
  std::array<double, 4> us{}, vs{};
  const ParamBox& box = parameter_box_;
  const int nu = periodic_candidates(uv.x(), box.u0, box.u1, surface_->u_period(), uv_epsilon_, us);
  const int nv = periodic_candidates(uv.y(), box.v0, box.v1, surface_->v_period(), uv_epsilon_, vs);
  Containment result = Containment::Outside;
  for (int i = 0; i < nu; ++i) {
    for (int j = 0; j < nv; ++j) {
      const Containment c =
          locate_once(Vec2(us[static_cast<std::size_t>(i)], vs[static_cast<std::size_t>(j)]));
      if (c == Containment::Inside) return c;
      if (c == Containment::OnBoundary) result = c;
    }
  }
  return result;
}

Containment FaceQuery::locate_once(const Vec2& q) const {
  const ParamBox& box = parameter_box_;
  const double eps = uv_epsilon_;
  if (q.x() < box.u0 - eps || q.x() > box.u1 + eps || q.y() < box.v0 - eps ||
      q.y() > box.v1 + eps) {
    return Containment::Outside;
  }
  bool inside = false;
  for (const auto& loop : loops_) {
    for (const Piece& piece : loop) {
      if (!cross(piece, q, inside)) return Containment::OnBoundary;
    }
  }
  return inside ? Containment::Inside : Containment::Outside;
}

bool FaceQuery::cross(const Piece& piece, const Vec2& q, bool& inside) const {
  // Crossing parity of a chord and of its arc agree whenever q is outside the capsule of
  // radius `bulge` around the chord (the closed curve arc + chord lies in it); otherwise the
  // arc is halved and each half tested with its own, four times smaller, bulge.
  struct Span {
    double t0, t1;
    Vec2 a, b;
    int depth;
  };
  const double second = piece.use == kStraight ? 0.0 : uses_[piece.use].second;
  const double eps = uv_epsilon_;
  std::array<Span, kMaxRefinement + 4> stack{};
  std::size_t size = 0;
  stack[size++] = {piece.t0, piece.t1, piece.a, piece.b, 0};
  while (size > 0) {
    const Span s = stack[--size];
    const double bulge = second * (s.t1 - s.t0) * (s.t1 - s.t0) / 8.0;
    const double reach = bulge + eps;
    if (q.y() > std::max(s.a.y(), s.b.y()) + reach || q.y() < std::min(s.a.y(), s.b.y()) - reach ||
        q.x() > std::max(s.a.x(), s.b.x()) + reach) {
      continue;  // neither the chord nor the arc can meet the ray
    }
    const double distance = segment_distance(q, s.a, s.b);
    const bool settled = bulge <= eps || s.depth >= kMaxRefinement;
    if (settled && distance <= reach) return false;
    if (settled || distance > reach) {
      // q is off the chord (and off the arc): the crossing with the ray is decided exactly.
      if (predicates::crosses_ray(s.a, s.b, q)) inside = !inside;
      continue;
    }
    const double tm = 0.5 * (s.t0 + s.t1);
    const Vec2 m = uses_[piece.use].point(tm);
    stack[size++] = {tm, s.t1, m, s.b, s.depth + 1};
    stack[size++] = {s.t0, tm, s.a, m, s.depth + 1};
  }
  return true;
}

// ---- BoxTree -------------------------------------------------------------------------------

void BoxTree::build(const std::vector<BoundingBox>& boxes) {
  nodes_.clear();
  items_.clear();
  if (boxes.empty()) return;
  std::vector<std::uint32_t> order(boxes.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<std::uint32_t>(i);
  nodes_.reserve(2 * boxes.size());
  build_node(order, boxes, 0, static_cast<std::uint32_t>(order.size()));
  items_ = std::move(order);
}

std::uint32_t BoxTree::build_node(std::vector<std::uint32_t>& order,
                                  const std::vector<BoundingBox>& boxes, std::uint32_t first,
                                  std::uint32_t count) {
  const auto index = static_cast<std::uint32_t>(nodes_.size());
  nodes_.emplace_back();
  BoundingBox box, centres;
  for (std::uint32_t i = first; i < first + count; ++i) {
    box.add(boxes[order[i]]);
    centres.add(0.5 * (boxes[order[i]].min + boxes[order[i]].max));
  }
  nodes_[index].box = box;
  if (count <= 4) {
    nodes_[index].first = first;
    nodes_[index].count = count;
    return index;
  }
  int axis = 0;
  centres.size().maxCoeff(&axis);
  const auto begin = order.begin() + first;
  const auto middle = begin + count / 2;
  std::nth_element(begin, middle, begin + count, [&](std::uint32_t a, std::uint32_t b) {
    const double ca = boxes[a].min[axis] + boxes[a].max[axis];
    const double cb = boxes[b].min[axis] + boxes[b].max[axis];
    return ca < cb || (ca == cb && a < b);
  });
  const std::uint32_t half = count / 2;
  const std::uint32_t left = build_node(order, boxes, first, half);
  const std::uint32_t right = build_node(order, boxes, first + half, count - half);
  nodes_[index].left = left;
  nodes_[index].right = right;
  return index;
}

// ---- SolidClassifier ------------------------------------------------------------------------

Result<SolidClassifier> SolidClassifier::create(const Shape& shape, double tolerance,
                                                const ClassifierOptions& options) {
  if (shape.is_null()) return Error{ErrorCode::InvalidArgument, "classifier needs a shape"};
  if (!(tolerance > 0.0) || !std::isfinite(tolerance)) {
    return Error{ErrorCode::InvalidArgument, "classifier tolerance must be finite and > 0"};
  }
  if (options.max_rays < 1) {
    return Error{ErrorCode::InvalidArgument, "classifier needs max_rays >= 1"};
  }
  SolidClassifier c;
  c.tolerance_ = tolerance;
  c.options_ = options;
  c.directions_ = make_ray_directions(options.seed, options.max_rays);
  ShapeIndex edge_index;

  auto add_face = [&](const Shape& face, std::uint32_t group) -> Status {
    const Orientation o = face.orientation();
    if (o != Orientation::Forward && o != Orientation::Reversed) return {};
    auto query = FaceQuery::create(face);
    if (!query.ok()) return query.error();
    std::vector<std::uint32_t> edges;
    for (const Shape& edge : Explorer(face, ShapeKind::Edge)) {
      const std::size_t index = edge_index.add(edge);
      if (index == c.edges_.size()) {
        const EdgeData* data = edge.body().edge();
        EdgeRecord record;
        record.location = edge.location();
        record.inverse = edge.location().inverse();
        record.band = std::max(tolerance, kernel::tolerance(edge));
        if (data->degenerate()) {
          record.point = edge.child_count() > 0 ? vertex_point(edge.child(0)) : Vec3::Zero();
          record.bounds.add(record.point);
        } else {
          record.curve = data->curve;
          record.first = data->first;
          record.last = data->last;
          record.bounds = moved_box(data->curve->bounds(data->first, data->last), record.location);
        }
        record.bounds.enlarge(record.band);
        c.edges_.push_back(std::move(record));
      }
      auto& groups = c.edges_[index].groups;
      if (std::find(groups.begin(), groups.end(), group) == groups.end()) groups.push_back(group);
      const auto id = static_cast<std::uint32_t>(index);
      if (std::find(edges.begin(), edges.end(), id) == edges.end()) edges.push_back(id);
    }
    c.faces_.push_back(std::move(query).value());
    c.face_group_.push_back(group);
    c.face_edges_.push_back(std::move(edges));
    return {};
  };

  std::uint32_t group = 0;
  for (const Shape& solid : Explorer(shape, ShapeKind::Solid)) {
    for (const Shape& face : Explorer(solid, ShapeKind::Face)) {
      if (auto s = add_face(face, group); !s.ok()) return s.error();
    }
    ++group;
  }
  bool loose = false;
  for (const Shape& face : Explorer(shape, ShapeKind::Face, ShapeKind::Solid)) {
    if (auto s = add_face(face, group); !s.ok()) return s.error();
    loose = true;
  }
  if (loose) ++group;
  c.group_count_ = group;

  double widest_band = tolerance;
  for (const EdgeRecord& e : c.edges_) {
    widest_band = std::max(widest_band, e.band);
    c.bounds_.add(e.bounds);
  }
  c.group_bounds_.assign(c.group_count_, BoundingBox());
  std::vector<BoundingBox> boxes;
  for (std::size_t f = 0; f < c.faces_.size(); ++f) {
    const BoundingBox& box = c.faces_[f].world_bounds();
    c.bounds_.add(box);
    c.group_bounds_[c.face_group_[f]].add(box);
    boxes.push_back(box);
  }
  for (const EdgeRecord& e : c.edges_) {
    for (std::uint32_t g : e.groups) c.group_bounds_[g].add(e.bounds);
  }
  c.bounds_.enlarge(widest_band);
  for (BoundingBox& box : c.group_bounds_) box.enlarge(widest_band);
  c.group_tree_.build(c.group_bounds_);
  c.face_tree_.build(boxes);
  boxes.clear();
  for (const EdgeRecord& e : c.edges_) boxes.push_back(e.bounds);
  c.edge_tree_.build(boxes);
  return c;
}

double SolidClassifier::edge_distance(const EdgeRecord& edge, const Vec3& p, double margin) const {
  if (!((edge.bounds.min.array() - margin <= p.array()).all() &&
        (p.array() <= edge.bounds.max.array() + margin).all())) {
    return kInfinity;
  }
  if (edge.curve == nullptr) return (p - edge.point).norm();
  const Vec3 local = edge.inverse.apply_point(p);
  const double t = edge.curve->closest_parameter(local, edge.first, edge.last);
  return (edge.curve->point(t) - local).norm() * edge.location.scale();
}

int SolidClassifier::Candidates::find(std::uint32_t g) const {
  for (std::size_t i = 0; i < groups.size(); ++i) {
    if (groups[i] == g) return static_cast<int>(i);
  }
  return -1;
}

SolidClassifier::Candidates SolidClassifier::candidates(const Vec3& p) const {
  Candidates c;
  group_tree_.visit_point(p, 0.0, [&](std::uint32_t g) { c.groups.push_back(g); });
  std::sort(c.groups.begin(), c.groups.end());
  c.open.assign(c.groups.size(), 1);
  return c;
}

std::vector<std::uint8_t> SolidClassifier::on_boundary(const Vec3& p, const Candidates& c) const {
  std::vector<std::uint8_t> on(c.groups.size(), 0);
  face_tree_.visit_point(p, tolerance_, [&](std::uint32_t f) {
    const int k = c.find(face_group_[f]);
    if (k < 0 || on[static_cast<std::size_t>(k)] != 0) return;
    const FaceQuery& face = faces_[f];
    const auto [uv, distance] = face.project(p);
    if (distance <= tolerance_ && face.locate_uv(uv) != Containment::Outside) {
      on[static_cast<std::size_t>(k)] = 1;
    }
  });
  edge_tree_.visit_point(p, 0.0, [&](std::uint32_t e) {
    const EdgeRecord& edge = edges_[e];
    bool pending = false;
    for (std::uint32_t g : edge.groups) {
      const int k = c.find(g);
      pending = pending || (k >= 0 && on[static_cast<std::size_t>(k)] == 0);
    }
    if (!pending || edge_distance(edge, p, 0.0) > tolerance_) return;
    for (std::uint32_t g : edge.groups) {
      const int k = c.find(g);
      if (k >= 0) on[static_cast<std::size_t>(k)] = 1;
    }
  });
  return on;
}

SolidClassifier::RayOutcome SolidClassifier::cast(const Vec3& p, const Vec3& direction,
                                                  const Candidates& c) const {
  RayOutcome out;
  out.parity.assign(c.groups.size(), 0);
  // Hits that matter lie in the open candidates' boxes: the ray stops where it leaves them.
  double t_max = 0.0;
  const BoxRay ray(p, direction);
  for (std::size_t k = 0; k < c.groups.size(); ++k) {
    double lo = 0.0, hi = kInfinity;
    if (c.open[k] != 0 && ray.clip(group_bounds_[c.groups[k]], lo, hi)) {
      t_max = std::max(t_max, hi);
    }
  }
  LineSurfaceIntersection intersection;
  face_tree_.visit_ray(p, direction, t_max, [&](std::uint32_t f) {
    const int k = c.find(face_group_[f]);
    if (k < 0 || c.open[static_cast<std::size_t>(k)] == 0) return;
    const FaceQuery& face = faces_[f];
    const double scale = face.location().scale();
    const Vec3 origin = face.to_local(p);
    const Vec3 local_direction = face.location().rotation().transpose() * direction;
    double lo = 0.0, hi = kInfinity;  // the ray's part in the face's box, in its frame
    if (!BoxRay(origin, local_direction).clip(face.local_bounds(), lo, hi)) return;
    const ParamBox& box = face.parameter_box();
    const double pad = kUvRelative * (1.0 + (box.u1 - box.u0) + (box.v1 - box.v0));
    const ParamBox range{box.u0 - pad, box.u1 + pad, box.v0 - pad, box.v1 + pad};
    intersect_line_surface(face.surface(), origin, local_direction, lo, hi, range,
                           tolerance_ / scale, intersection);
    if (intersection.degenerate) out.ambiguous = true;
    // A touching pair of roots comes back as one root somewhere between them (they are up to
    // about sqrt(eps) of the face's size apart): it is only harmless well inside or well
    // outside the face.
    const double touching = kTouchingRelative * face.world_bounds().size().norm();
    for (const LineSurfaceHit& hit : intersection.hits) {
      const Containment where = face.locate_uv(hit.uv);
      if (where == Containment::OnBoundary || (hit.tangent && where == Containment::Inside)) {
        out.ambiguous = true;
      }
      const Vec3 x = p + (hit.t * scale) * direction;
      for (std::uint32_t e : face_edges_[f]) {
        const double band = hit.tangent ? std::max(edges_[e].band, touching) : edges_[e].band;
        if (edge_distance(edges_[e], x, band - edges_[e].band) <= band) {
          out.ambiguous = true;
          break;
        }
      }
      if (where == Containment::Inside) out.parity[static_cast<std::size_t>(k)] ^= 1;
    }
  });
  return out;
}

std::vector<std::uint8_t> SolidClassifier::inside(const Vec3& p, const Candidates& c,
                                                  ClassifyStats& stats) const {
  std::vector<int> votes(c.groups.size(), 0);
  for (const Vec3& direction : directions_) {
    const RayOutcome ray = cast(p, direction, c);
    ++stats.rays;
    if (!ray.ambiguous) return ray.parity;
    for (std::size_t k = 0; k < votes.size(); ++k) votes[k] += ray.parity[k];
  }
  // Every ray was ambiguous: the majority of their parities decides, per solid.
  stats.voted = true;
  std::vector<std::uint8_t> result(votes.size(), 0);
  for (std::size_t k = 0; k < votes.size(); ++k) {
    result[k] = 2 * votes[k] > static_cast<int>(directions_.size()) ? 1 : 0;
  }
  return result;
}

Containment SolidClassifier::classify(const Vec3& p, ClassifyStats* stats) const {
  ClassifyStats local_stats;
  ClassifyStats& counts = stats != nullptr ? *stats : local_stats;
  counts = ClassifyStats{};
  if (group_count_ == 0 || !bounds_.contains(p)) return Containment::Outside;
  Candidates c = candidates(p);
  if (c.groups.empty()) return Containment::Outside;
  const std::vector<std::uint8_t> on = on_boundary(p, c);
  bool any_on = false, any_open = false;
  for (std::size_t k = 0; k < on.size(); ++k) {
    any_on = any_on || on[k] != 0;
    c.open[k] = on[k] == 0 ? 1 : 0;
    any_open = any_open || c.open[k] != 0;
  }
  if (!any_open) return Containment::OnBoundary;
  const std::vector<std::uint8_t> in = inside(p, c, counts);
  for (std::size_t k = 0; k < in.size(); ++k) {
    if (c.open[k] != 0 && in[k] != 0) return Containment::Inside;
  }
  return any_on ? Containment::OnBoundary : Containment::Outside;
}

std::optional<Vec3> SolidClassifier::boundary_normal(const Vec3& p) const {
  // The first face in explorer order: the trees visit in their own order, so keep the least.
  std::size_t best = faces_.size();
  Vec2 best_uv = Vec2::Zero();
  face_tree_.visit_point(p, tolerance_, [&](std::uint32_t f) {
    if (f >= best) return;
    const auto [uv, distance] = faces_[f].project(p);
    if (distance <= tolerance_ && faces_[f].locate_uv(uv) != Containment::Outside) {
      best = f;
      best_uv = uv;
    }
  });
  if (best < faces_.size()) return faces_[best].outward_normal(best_uv);
  // Within tolerance of an edge only (its faces' projections fell just outside them): the
  // first face using the nearest such edge.
  std::size_t edge = edges_.size();
  double nearest = kInfinity;
  edge_tree_.visit_point(p, 0.0, [&](std::uint32_t e) {
    const double d = edge_distance(edges_[e], p, 0.0);
    if (d <= tolerance_ && (d < nearest || (d == nearest && e < edge))) {
      nearest = d;
      edge = e;
    }
  });
  if (edge == edges_.size()) return std::nullopt;
  for (std::size_t f = 0; f < faces_.size(); ++f) {
    const auto& edges = face_edges_[f];
    if (std::find(edges.begin(), edges.end(), static_cast<std::uint32_t>(edge)) != edges.end()) {
      return faces_[f].outward_normal(faces_[f].project(p).first);
    }
  }
  return std::nullopt;
}

}  // namespace csgtile::kernel::detail
