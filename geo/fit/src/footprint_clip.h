#pragma once
// A building's footprint in the roof partition's frame (issue #18 item 2): which grid cells
// meet it, and the parts' polygons clipped to it (Boost.Geometry), so that a building fitted
// in its footprint stands exactly on it.

#include <map>
#include <optional>
#include <utility>
#include <vector>

#include "csgtile/geo/footprints.h"
#include "plane2d.h"

namespace csgtile::fit::detail {

/// A polygon in the frame (a, b) = (p·u, p·v): outer ring counter-clockwise, holes clockwise,
/// rings open.
struct FramePolygon {
  std::vector<Vec2> outer;
  std::vector<std::vector<Vec2>> holes;
};

class FootprintClip {
 public:
  /// The footprint's polygons (world x, y of the points' frame) seen in the frame (u, v).
  FootprintClip(const std::vector<geo::FootprintPolygon>& polygons, const Vec2& u, const Vec2& v);
  ~FootprintClip();
  FootprintClip(const FootprintClip&) = delete;
  FootprintClip& operator=(const FootprintClip&) = delete;

  /// Its extent in the frame: [a0, a1] × [b0, b1]; false when it has no area.
  bool extent(double& a0, double& a1, double& b0, double& b1) const;
  /// The area of the rectangle [a0, a1] × [b0, b1] inside the footprint.
  double area_in(double a0, double b0, double a1, double b1) const;
  /// The pieces of `polygon` inside the footprint (in the frame), largest first; pieces under
  /// `min_area` are left out.
  std::vector<FramePolygon> clip(const FramePolygon& polygon, double min_area) const;

 private:
  struct Impl;
  Impl* impl_;
};

/// The polygon with its outer ring counter-clockwise and its holes clockwise (as extrusion
/// profiles are).
FramePolygon oriented(const FramePolygon& polygon);

/// Vertices of a building's polygons made one where they lie closer than a distance: each
/// vertex becomes the first vertex seen within it (in the order polygons are given), so that
/// polygons sharing a boundary keep sharing it; then repeated vertices and spikes go. Clipping
/// a partition to a footprint leaves edges of millimetres where the footprint passes near a
/// cell's corner, walls the Booleans cannot section against their neighbours reliably.
class VertexSnap {
 public:
  explicit VertexSnap(double distance) : distance_(distance) {}
  /// The polygon snapped; nullopt when its outer ring keeps no area (holes that keep none
  /// are dropped).
  std::optional<FramePolygon> snap(const FramePolygon& polygon);

 private:
  std::vector<Vec2> ring(const std::vector<Vec2>& ring);
  double distance_;
  std::map<std::pair<long long, long long>, std::vector<Vec2>> seen_;
};

/// Vertices of the polygons lying within `distance` of an edge of another ring (or of their
/// own ring's other edges), between its ends, inserted into that edge in order along it.
/// VertexSnap moves a vertex by up to its distance, onto a vertex seen before; a neighbouring
/// polygon whose straight edge ran through the vertex's old place then no longer shares the
/// boundary (a roof part's wall 7 mm off the corner of the two flat pieces beside it: their
/// fuse failed, its faces' boundary loops crossing). A vertex already in a ring is not
/// inserted into it again. Deterministic.
void share_vertices(std::vector<std::vector<FramePolygon>>& polygons, double distance);

/// The frame of a footprint: u along its main walls (the direction, modulo 90°, along which
/// most of its outer rings' length runs), v = u turned left, and its extent in it; nullopt
/// when it has no edge.
std::optional<PrincipalFrame> footprint_frame(const std::vector<geo::FootprintPolygon>& polygons);

}  // namespace csgtile::fit::detail
