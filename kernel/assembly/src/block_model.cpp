// LoD1.2 block models and the heights of a building's solid (block_model.h).

#include "csgtile/assembly/block_model.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "csgtile/kernel/check.h"
#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/face_rings.h"
#include "csgtile/kernel/tessellation.h"
#include "footprint_union.h"

namespace csgtile::assembly {

namespace {

using kernel::ErrorCode;
using kernel::Vec2;
using kernel::Vec3;
using Triangle = std::array<Vec3, 3>;

// The exporters' rules (CityJSON semantics): a face turned up by more than this is roof, one
// turned down by more than this (in size) is seen from below.
constexpr double kRoofNz = 0.2;
constexpr double kDownNz = -0.9;
// A face is part of the footprint when it faces down at all (not vertical): the downward
// faces' projections together are the solid's.
constexpr double kSeenFromBelow = 1e-6;

// The area seen from above of the part of `t` at or below height z: the triangle clipped by
// the plane (at most four corners), its shoelace area.
double area_below(const Triangle& t, double z) {
  std::array<Vec3, 4> poly;
  int n = 0;
  for (int i = 0; i < 3; ++i) {
    const Vec3& a = t[static_cast<std::size_t>(i)];
    const Vec3& b = t[static_cast<std::size_t>((i + 1) % 3)];
    const bool a_in = a.z() <= z, b_in = b.z() <= z;
    if (a_in) poly[static_cast<std::size_t>(n++)] = a;
    if (a_in != b_in)
      poly[static_cast<std::size_t>(n++)] = a + (z - a.z()) / (b.z() - a.z()) * (b - a);
  }
  double twice = 0.0;
  for (int i = 0; i < n; ++i) {
    const Vec3& a = poly[static_cast<std::size_t>(i)];
    const Vec3& b = poly[static_cast<std::size_t>((i + 1) % n)];
    twice += a.x() * b.y() - a.y() * b.x();
  }
  return 0.5 * std::abs(twice);
}

// The height below which a share q of the roof's area lies: the area function is continuous
// and increasing from roof_min to roof_max; bisection to the resolution of doubles.
double roof_percentile(const std::vector<Triangle>& roof, double total, double low, double high,
                       double q) {
  const double target = q * total;
  for (int i = 0; i < 200 && high - low > 1e-12 * std::max(1.0, std::abs(high)); ++i) {
    const double mid = 0.5 * (low + high);
    double below = 0.0;
    for (const Triangle& t : roof) below += area_below(t, mid);
    (below < target ? low : high) = mid;
  }
  return high;
}

struct Measured {
  std::shared_ptr<const kernel::Mesh> mesh;  // never null
  BuildingHeights heights;
  std::vector<Triangle> roof;             // the roof's triangles (nz > kRoofNz)
  std::vector<std::uint32_t> roof_faces;  // the face (Mesh::triangle_face) of each
};

// `given`: the shape's tessellation at `chordal_tolerance`, when the caller has it.
kernel::Result<Measured> measure(const kernel::Shape& shape, double chordal_tolerance,
                                 std::shared_ptr<const kernel::Mesh> given) {
  auto meshed = kernel::shared_tessellation(shape, chordal_tolerance, std::move(given));
  if (!meshed.ok()) return meshed.error();
  Measured out;
  out.mesh = std::move(meshed).value();
  const kernel::Mesh& m = *out.mesh;
  BuildingHeights& h = out.heights;
  double ground = std::numeric_limits<double>::infinity();
  double lowest = ground;
  h.roof_min = ground;
  h.roof_max = -ground;
  std::vector<Triangle> roof;
  std::vector<bool> roof_face;
  for (std::size_t i = 0; i < m.triangles.size(); ++i) {
    const auto& k = m.triangles[i];
    const Triangle t = {m.vertices[k[0]], m.vertices[k[1]], m.vertices[k[2]]};
    const Vec3 n = (t[1] - t[0]).cross(t[2] - t[0]);
    const double length = n.norm();
    if (!(length > 0.0)) continue;
    const double low = std::min({t[0].z(), t[1].z(), t[2].z()});
    const double high = std::max({t[0].z(), t[1].z(), t[2].z()});
    lowest = std::min(lowest, low);
    const double nz = n.z() / length;
    if (nz < kDownNz) ground = std::min(ground, low);
    if (nz <= kRoofNz) continue;
    roof.push_back(t);
    out.roof_faces.push_back(m.triangle_face[i]);
    h.roof_area += 0.5 * n.z();
    h.roof_min = std::min(h.roof_min, low);
    h.roof_max = std::max(h.roof_max, high);
    const std::size_t f = m.triangle_face[i];
    if (f >= roof_face.size()) roof_face.resize(f + 1, false);
    roof_face[f] = true;
  }
  if (roof.empty() || !(h.roof_area > 0.0)) {
    return kernel::Error{ErrorCode::DegenerateGeometry, "the solid has no roof seen from above"};
  }
  h.ground = std::isfinite(ground) ? ground : lowest;
  h.roof_faces = static_cast<std::size_t>(std::count(roof_face.begin(), roof_face.end(), true));
  h.roof_50p = roof_percentile(roof, h.roof_area, h.roof_min, h.roof_max, 0.5);
  h.roof_70p = roof_percentile(roof, h.roof_area, h.roof_min, h.roof_max, 0.7);
  out.roof = std::move(roof);
  return out;
}

Vec3 ring_normal(const std::vector<Vec3>& ring) {
  Vec3 n = Vec3::Zero();
  for (std::size_t i = 0; i < ring.size(); ++i) n += ring[i].cross(ring[(i + 1) % ring.size()]);
  return n;
}

}  // namespace

kernel::Result<BuildingHeights> building_heights(const kernel::Shape& shape,
                                                 double chordal_tolerance,
                                                 std::shared_ptr<const kernel::Mesh> mesh) {
  auto measured = measure(shape, chordal_tolerance, std::move(mesh));
  if (!measured.ok()) return measured.error();
  return measured.value().heights;
}

namespace {

// Every CSG leaf of a building is an extrusion or a box. Errors: InvalidArgument naming the
// first that is not (a curved primitive: not a building).
kernel::Status check_building_leaves(const kernel::CsgModel& model) {
  if (model.shape.is_null() || model.nodes.empty()) {
    return kernel::Status(ErrorCode::InvalidArgument,
                          "the model has no CSG history: its leaves cannot tell a building");
  }
  for (std::size_t k = 0; k < model.nodes.size(); ++k) {
    const kernel::CsgNode& node = model.nodes[k];
    if (node.kind != kernel::CsgNodeKind::Primitive) continue;
    const kernel::PrimitiveSpec& s = node.primitive;
    if (s.type != kernel::PrimitiveType::Extrusion && s.type != kernel::PrimitiveType::Box) {
      return kernel::Status(ErrorCode::InvalidArgument, "leaf " + std::to_string(k) + " is a " +
                                                            kernel::primitive_type_name(s.type) +
                                                            ", not an extrusion or a box");
    }
  }
  return kernel::Status();
}

// Twice the area over the perimeter of a face's projection (outer ring, holes): its width
// where it is a strip.
double projected_width(const kernel::PrimitiveSpec& spec) {
  auto area = [](const std::vector<Vec2>& ring) {
    double a2 = 0.0;
    for (std::size_t i = 0; i < ring.size(); ++i) {
      const Vec2& p = ring[i];
      const Vec2& q = ring[(i + 1) % ring.size()];
      a2 += p.x() * q.y() - p.y() * q.x();
    }
    return 0.5 * std::abs(a2);
  };
  double a = area(spec.profile), perimeter = 0.0;
  for (const auto& hole : spec.holes) a -= area(hole);
  for (std::size_t i = 0; i < spec.profile.size(); ++i) {
    perimeter += (spec.profile[(i + 1) % spec.profile.size()] - spec.profile[i]).norm();
  }
  return perimeter > 0.0 ? 2.0 * a / perimeter : 0.0;
}

// A piece of a block not yet built: its name in the block's CSG tree and its extrusion.
struct PieceSpec {
  std::string name;
  kernel::PrimitiveSpec spec;
};

// The footprint of `shape` (meshed as `mesh`): every face seen from below, each as an
// extrusion from `ground` to `top` named `label` + "footprint face " + its number, appended
// to `specs`. A face whose projection is a strip
// narrower than `min_width` (a wall leaning out by a few millimetres) is left out: it adds
// nothing a block model shows, and slivers that thin do not survive the coordinates'
// quantisation in the published files (the shell then crosses itself). The mean width
// (projected_width) of a strip tapering to a point is half its widest: the gable wall of a
// pitched-roof extrusion 0.13° off level, 15 mm wide under its ridge and 11 mm on average,
// left an 8 mm chamfer on its LoD1.3 block that val3dity found crossing itself; a face is left
// out under twice `min_width` on average.
kernel::Status footprint_specs(const kernel::Shape& shape, const kernel::Mesh& mesh, double ground,
                               double top, double min_width, const std::string& label,
                               std::vector<PieceSpec>& specs) {
  const kernel::EdgePoints edge_points = kernel::mesh_edge_points(shape, mesh);
  const kernel::ShapeIndex faces = kernel::map_child_shapes(shape, kernel::ShapeKind::Face);
  const std::size_t before = specs.size();
  for (std::size_t f = 0; f < faces.size(); ++f) {
    const kernel::Shape& face = faces[f];
    if (face.orientation() != kernel::Orientation::Forward &&
        face.orientation() != kernel::Orientation::Reversed) {
      continue;  // Internal and External faces bound nothing
    }
    const bool planar = face.body().face()->surface->kind() == kernel::SurfaceKind::Plane;
    auto rings = planar ? kernel::planar_face_rings(face, edge_points) : std::nullopt;
    if (!rings) continue;  // curved faces do not occur on extrusions and boxes cut by planes
    const Vec3 n = ring_normal(rings->front());
    if (!(n.norm() > 0.0) || n.z() / n.norm() >= -kSeenFromBelow) continue;
    kernel::PrimitiveSpec spec;
    spec.type = kernel::PrimitiveType::Extrusion;
    spec.height = top - ground;
    spec.placement = kernel::Location::translation(Vec3(0.0, 0.0, ground));
    for (std::size_t r = 0; r < rings->size(); ++r) {
      std::vector<Vec2> ring;
      for (const Vec3& p : (*rings)[r]) ring.emplace_back(p.x(), p.y());
      if (r == 0) {
        spec.profile = std::move(ring);
      } else {
        spec.holes.push_back(std::move(ring));
      }
    }
    if (projected_width(spec) < 2.0 * min_width) continue;
    specs.push_back({label + "footprint face " + std::to_string(f), std::move(spec)});
  }
  if (specs.size() == before) {
    return kernel::Status(
        ErrorCode::DegenerateGeometry,
        label + (label.empty() ? "the solid" : "") + " has no face seen from below");
  }
  return kernel::Status();
}

// Each spec built as a piece of the block.
kernel::Status add_pieces(const std::vector<PieceSpec>& specs, double tolerance,
                          std::vector<kernel::CsgModel>& pieces) {
  for (const auto& [name, spec] : specs) {
    auto piece = kernel::csg_primitive(spec, name, tolerance);
    if (!piece.ok()) {
      return kernel::Status(piece.error().code, name + ": " + piece.error().message);
    }
    pieces.push_back(std::move(piece).value());
  }
  return kernel::Status();
}

// footprint_specs, built.
kernel::Status add_footprint_pieces(const kernel::Shape& shape, const kernel::Mesh& mesh,
                                    double ground, double top, double tolerance, double min_width,
                                    const std::string& label,
                                    std::vector<kernel::CsgModel>& pieces) {
  std::vector<PieceSpec> specs;
  if (kernel::Status st = footprint_specs(shape, mesh, ground, top, min_width, label, specs);
      !st.ok()) {
    return st;
  }
  return add_pieces(specs, tolerance, pieces);
}

// The pieces fused into one valid solid.
kernel::Result<kernel::CsgModel> fuse_block(std::vector<kernel::CsgModel> pieces,
                                            double tolerance) {
  kernel::CsgModel out;
  const bool single = pieces.size() == 1;
  if (single) {
    out = std::move(pieces.front());
  } else {
    kernel::BooleanOptions b;
    b.tolerance = tolerance;
    auto fused = kernel::csg_combine(pieces, kernel::BooleanOp::Fuse, b);
    if (!fused.ok()) return fused.error();
    out = std::move(fused).value();
  }
  const std::size_t solids = kernel::map_child_shapes(out.shape, kernel::ShapeKind::Solid).size();
  if (solids != 1) {
    return kernel::Error{ErrorCode::DegenerateGeometry,
                         "the footprint is in " + std::to_string(solids) + " pieces"};
  }
  // One solid out of several pieces is one Boolean's result, which the fuse checked
  // (BooleanOptions::check_result); a single piece is checked here.
  if (single && !kernel::check_shape(out.shape).valid()) {
    return kernel::Error{ErrorCode::InvalidShape, "the block fails the validity checker"};
  }
  return out;
}

// LoD1.2 of a building measured as `measured`.
kernel::Result<kernel::CsgModel> lod12_of(const kernel::CsgModel& model, const Measured& measured,
                                          const BlockModelOptions& options) {
  const double ground = measured.heights.ground, top = measured.heights.roof_70p;
  if (!(top - ground > 100.0 * options.tolerance)) {
    return kernel::Error{ErrorCode::DegenerateGeometry,
                         "the roof's 70th percentile is not above the ground"};
  }
  std::vector<kernel::CsgModel> pieces;
  if (kernel::Status st =
          add_footprint_pieces(model.shape, *measured.mesh, ground, top, options.tolerance,
                               options.chordal_tolerance, "", pieces);
      !st.ok()) {
    return st.error();
  }
  return fuse_block(std::move(pieces), options.tolerance);
}

// LoD1.3 of a building measured as `measured`.
kernel::Result<kernel::CsgModel> lod13_of(const kernel::CsgModel& model, const Measured& measured,
                                          const BlockModelOptions& options) {
  const BuildingHeights& heights = measured.heights;
  const double ground = heights.ground;
  // The roof parts: the leaves. Each roof triangle of the model belongs to the leaf its face
  // came from (the CSG history), so a part's roof is what is left of it in the model.
  struct Part {
    std::size_t node = 0;
    std::vector<Triangle> roof;
    double area = 0.0, low = std::numeric_limits<double>::infinity(), high = -low;
    double top = 0.0, level = 0.0;
  };
  std::vector<Part> parts;
  std::vector<int> part_of(model.nodes.size(), -1);
  for (std::size_t k = 0; k < model.nodes.size(); ++k) {
    if (model.nodes[k].kind != kernel::CsgNodeKind::Primitive) continue;
    part_of[k] = static_cast<int>(parts.size());
    parts.push_back(Part{k, {}, 0.0});
  }
  for (std::size_t i = 0; i < measured.roof.size(); ++i) {
    const std::size_t f = measured.roof_faces[i];
    if (f >= model.face_sources.size() || model.face_sources[f].empty()) continue;
    const int node = model.face_sources[f].front().node;
    if (node < 0 || static_cast<std::size_t>(node) >= part_of.size() || part_of[node] < 0) continue;
    Part& p = parts[static_cast<std::size_t>(part_of[node])];
    const Triangle& t = measured.roof[i];
    p.roof.push_back(t);
    p.area += 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).z();
    p.low = std::min({p.low, t[0].z(), t[1].z(), t[2].z()});
    p.high = std::max({p.high, t[0].z(), t[1].z(), t[2].z()});
  }
  // Levels: the parts with a roof sorted by their own 70th percentile, a new level where the
  // next is a step or more higher; a level's height is its roofs' 70th percentile together.
  // A part whose roof is all hidden under others' takes the building's.
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    Part& p = parts[i];
    p.level = heights.roof_70p;
    if (!(p.area > 0.0)) continue;
    p.top = roof_percentile(p.roof, p.area, p.low, p.high, 0.7);
    order.push_back(i);
  }
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return parts[a].top < parts[b].top; });
  for (std::size_t first = 0; first < order.size();) {
    std::size_t last = first + 1;
    while (last < order.size() &&
           parts[order[last]].top - parts[order[last - 1]].top < options.level_step) {
      ++last;
    }
    std::vector<Triangle> roof;
    double area = 0.0, low = std::numeric_limits<double>::infinity(), high = -low;
    for (std::size_t i = first; i < last; ++i) {
      const Part& p = parts[order[i]];
      roof.insert(roof.end(), p.roof.begin(), p.roof.end());
      area += p.area;
      low = std::min(low, p.low);
      high = std::max(high, p.high);
    }
    const double level = roof_percentile(roof, area, low, high, 0.7);
    for (std::size_t i = first; i < last; ++i) parts[order[i]].level = level;
    first = last;
  }
  // Each part's footprint (its leaf without the roof planes that cut its top: those do not
  // reach its bottom) from the building's ground to its level.
  // The pieces of one level tile its footprint edge to edge (the parts share their walls):
  // their union is found in the plane (footprint_union.h), and the fuse takes one prism per
  // level and connected piece rather than one per part. Where they do not tile so, the level's
  // pieces go to the fuse as they are.
  std::map<double, std::vector<PieceSpec>> levels;
  kernel::TessellationOptions tessellation;
  tessellation.chordal_tolerance = options.chordal_tolerance;
  for (const Part& p : parts) {
    const std::string label = "roof part " + std::to_string(p.node) + " ";
    if (!(p.level - ground > 100.0 * options.tolerance)) {
      return kernel::Error{ErrorCode::DegenerateGeometry,
                           label + "has its level's roof not above the ground"};
    }
    kernel::PrimitiveSpec plain = model.nodes[p.node].primitive;
    plain.clips.clear();
    auto solid = kernel::csg_primitive(plain, label, options.tolerance);
    if (!solid.ok()) return kernel::Error{solid.error().code, label + solid.error().message};
    auto mesh = kernel::tessellate(solid.value().shape, tessellation);
    if (!mesh.ok()) return kernel::Error{mesh.error().code, label + mesh.error().message};
    if (kernel::Status st = footprint_specs(solid.value().shape, mesh.value(), ground, p.level,
                                            options.chordal_tolerance, label, levels[p.level]);
        !st.ok()) {
      return st.error();
    }
  }
  std::vector<kernel::CsgModel> pieces;
  std::size_t level_number = 0;
  for (const auto& [level, specs] : levels) {
    std::vector<detail::FootprintPolygon> tiles;
    for (const auto& [name, spec] : specs) tiles.push_back({spec.profile, spec.holes});
    auto merged =
        specs.size() > 1 ? detail::union_of_tiles(tiles, options.tolerance) : std::nullopt;
    std::vector<PieceSpec> joined;
    if (merged) {
      for (detail::FootprintPolygon& polygon : *merged) {
        kernel::PrimitiveSpec spec = specs.front().spec;  // the level's height and placement
        spec.profile = std::move(polygon.outer);
        spec.holes = std::move(polygon.holes);
        joined.push_back({"level " + std::to_string(level_number) + " footprint piece " +
                              std::to_string(joined.size()),
                          std::move(spec)});
      }
    }
    if (kernel::Status st = add_pieces(merged ? joined : specs, options.tolerance, pieces);
        !st.ok()) {
      return st.error();
    }
    ++level_number;
  }
  return fuse_block(std::move(pieces), options.tolerance);
}

// A building's leaves checked and its model measured once.
kernel::Result<Measured> measure_building(const kernel::CsgModel& model,
                                          const BlockModelOptions& options,
                                          std::shared_ptr<const kernel::Mesh> mesh = {}) {
  if (kernel::Status st = check_building_leaves(model); !st.ok()) return st.error();
  return measure(model.shape, options.chordal_tolerance, std::move(mesh));
}

// One block of a building: its heights and `make`'s model.
template <typename Make>
kernel::Result<BlockModel> one_block(const kernel::CsgModel& model,
                                     const BlockModelOptions& options, Make make) {
  auto measured = measure_building(model, options);
  if (!measured.ok()) return measured.error();
  auto block = make(model, measured.value(), options);
  if (!block.ok()) return block.error();
  return BlockModel{measured.value().heights, std::move(block).value()};
}

}  // namespace

kernel::Result<BlockModel> block_model(const kernel::CsgModel& model,
                                       const BlockModelOptions& options) {
  return one_block(model, options, lod12_of);
}

kernel::Result<BlockModel> multi_height_block_model(const kernel::CsgModel& model,
                                                    const BlockModelOptions& options) {
  return one_block(model, options, lod13_of);
}

kernel::Result<BuildingBlocks> building_blocks(const kernel::CsgModel& model,
                                               const BlockModelOptions& options,
                                               std::shared_ptr<const kernel::Mesh> mesh) {
  auto measured = measure_building(model, options, std::move(mesh));
  if (!measured.ok()) return measured.error();
  auto lod12 = lod12_of(model, measured.value(), options);
  if (!lod12.ok()) return lod12.error();
  BuildingBlocks out;
  out.heights = measured.value().heights;
  out.lod12 = std::move(lod12).value();
  auto lod13 = lod13_of(model, measured.value(), options);
  if (lod13.ok()) {
    out.lod13 = std::move(lod13).value();
  } else {
    out.lod13_error = lod13.error();
  }
  return out;
}

}  // namespace csgtile::assembly
