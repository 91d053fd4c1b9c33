// Blocks (LoD1.2, issue #18 item 5): the points of a region seen from the air that no
// primitive explains (no plane was found for them, or their planes made nothing) are not
// left out of the model. Grouped into pieces of one height (cells of the outline grid whose
// highest points differ by less than a step), each piece becomes the extrusion of its
// outline from the terrain up to the 70th percentile of its points' heights, as 3DBAG's
// LoD1.2 does for a whole building.

#include <algorithm>
#include <cmath>
#include <map>

#include "fit_internal.h"
#include "footprint_clip.h"
#include "plane2d.h"

namespace csgtile::fit::detail {

using kernel::Vec2;

std::vector<Proposal> propose_blocks(const ProposalInput& in,
                                     const std::function<bool(const Vec3&)>& explained,
                                     std::vector<Rejection>& rejected) {
  std::vector<Proposal> out;
  const PrimitiveOptions& o = *in.options;
  if (o.ground == nullptr || !o.blocks) return out;
  const double spacing = in.shapes->spacing;
  if (!(spacing > 0.0)) return out;
  const double cell = 1.5 * spacing;
  const double step = std::max(1.0, 0.25 * o.min_building_height);  // a height jump
  // The points left: unused, finite, not inside or just above a kept primitive.
  std::map<std::pair<long long, long long>, std::vector<std::uint32_t>> cells;
  for (std::uint32_t i = 0; i < in.points.size(); ++i) {
    const Vec3& p = in.points[i];
    if ((*in.used)[i] || !p.allFinite() || explained(p)) continue;
    cells[{cell_index(p.x(), cell), cell_index(p.y(), cell)}].push_back(i);
  }
  if (cells.empty()) return out;
  std::map<std::pair<long long, long long>, double> top;  // highest point of each cell
  for (const auto& [key, members] : cells) {
    double z = -INFINITY;
    for (auto i : members) z = std::max(z, in.points[i].z());
    top[key] = z;
  }
  // Pieces: cells joined to their 8 neighbours when their tops differ by less than a step.
  std::map<std::pair<long long, long long>, int> piece;
  int pieces = 0;
  for (const auto& [start, unused] : cells) {
    if (piece.count(start) != 0) continue;
    std::vector<std::pair<long long, long long>> queue{start};
    piece[start] = pieces;
    for (std::size_t h = 0; h < queue.size(); ++h) {
      const auto [cx, cy] = queue[h];
      for (long long dy = -1; dy <= 1; ++dy) {
        for (long long dx = -1; dx <= 1; ++dx) {
          const std::pair<long long, long long> q{cx + dx, cy + dy};
          if (piece.count(q) != 0 || cells.count(q) == 0) continue;
          if (std::abs(top[q] - top[queue[h]]) >= step) continue;
          piece[q] = pieces;
          queue.push_back(q);
        }
      }
    }
    ++pieces;
  }
  std::vector<std::vector<std::uint32_t>> members(static_cast<std::size_t>(pieces));
  for (const auto& [key, list] : cells) {
    auto& m = members[static_cast<std::size_t>(piece[key])];
    m.insert(m.end(), list.begin(), list.end());
  }
  for (int k = 0; k < pieces; ++k) {
    auto& pts = members[static_cast<std::size_t>(k)];
    if (static_cast<long long>(pts.size()) < in.ransac->min_points) continue;
    std::sort(pts.begin(), pts.end());
    const std::string what = "block " + std::to_string(k);
    std::vector<double> heights;
    std::vector<Vec2> flat;
    for (auto i : pts) {
      heights.push_back(in.points[i].z());
      flat.emplace_back(in.points[i].x(), in.points[i].y());
    }
    std::sort(heights.begin(), heights.end());
    const double roof =
        heights[static_cast<std::size_t>(0.7 * static_cast<double>(heights.size() - 1))];
    const double tight = 2.0 * in.ransac->epsilon;
    std::string why;
    const auto outline = roof_outline(
        in, flat, [&](const Vec3& p) { return p.z() > roof + step; }, why);
    if (!outline) {
      if (!why.empty()) rejected.push_back({what, why, static_cast<long long>(pts.size())});
      continue;
    }
    const OutlineGround under = outline_ground(*outline, *o.ground);
    const double g = under.ground;
    if (!std::isfinite(g) || roof - g < o.min_building_height) {
      rejected.push_back(
          {what, "not a building's height above the terrain", static_cast<long long>(pts.size())});
      continue;
    }
    auto spec = outline_extrusion(*outline, under, roof - g);
    if (!spec) continue;
    Proposal p;
    p.spec = std::move(*spec);
    for (auto i : pts) {
      if (in.points[i].z() <= roof + tight + step) p.members.push_back(i);
    }
    p.area = polygon_area(outline->profile, outline->holes) +
             polygon_perimeter(outline->profile, outline->holes) * p.spec.height;
    p.what = what + " (LoD1.2 of points no surface explains)";
    out.push_back(std::move(p));
  }
  return out;
}

std::vector<Proposal> propose_footprint_block(const ProposalInput& in,
                                              std::vector<Rejection>& rejected,
                                              std::optional<double> top) {
  std::vector<Proposal> out;
  const PrimitiveOptions& o = *in.options;
  if (o.ground == nullptr || o.footprint == nullptr || o.footprint->empty()) return out;
  std::vector<std::uint32_t> pts;
  std::vector<double> heights;
  for (std::uint32_t i = 0; i < in.points.size(); ++i) {
    if ((*in.used)[i] || !in.points[i].allFinite()) continue;
    pts.push_back(i);
    heights.push_back(in.points[i].z());
  }
  const std::string what = top ? "footprint under its dome" : "footprint block (LoD1.2)";
  if (heights.empty() && !top) return out;
  std::sort(heights.begin(), heights.end());
  const double roof =
      top ? *top : heights[static_cast<std::size_t>(0.7 * static_cast<double>(heights.size() - 1))];
  for (std::size_t k = 0; k < o.footprint->size(); ++k) {
    const geo::FootprintPolygon& fp = (*o.footprint)[k];
    RoofOutline outline;  // in the world frame: (a, b) = (x, y)
    outline.cell = 1.5 * in.shapes->spacing;
    const FramePolygon ring = oriented(FramePolygon{fp.outer, fp.holes});
    outline.profile = ring.outer;
    outline.holes = ring.holes;
    const OutlineGround under = outline_ground(outline, *o.ground);
    const double g = under.ground;
    if (!std::isfinite(g) || roof - g < 0.5 * o.min_building_height) {
      rejected.push_back(
          {what, "not a building's height above the terrain", static_cast<long long>(pts.size())});
      continue;
    }
    auto spec = outline_extrusion(outline, under, roof - g);
    if (!spec) continue;
    Proposal p;
    p.spec = std::move(*spec);
    if (k == 0) p.members = pts;
    p.area = polygon_area(outline.profile, outline.holes) +
             polygon_perimeter(outline.profile, outline.holes) * p.spec.height;
    p.what = what;
    out.push_back(std::move(p));
  }
  return out;
}

}  // namespace csgtile::fit::detail
