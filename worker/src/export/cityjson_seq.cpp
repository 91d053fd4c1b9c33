// CityJSONSeq from objects (cityjson_seq.h): surfaces from the faces, quantisation, closure
// and semantics per feature, then the text.

#include "export/cityjson_seq.h"
#include "snap_json.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <unordered_map>
#include <unordered_set>

#include "csgtile/kernel/check.h"
#include "csgtile/kernel/curve.h"
#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/face_rings.h"
#include "csgtile/kernel/mass_properties.h"
#include "csgtile/kernel/tessellation.h"
#include "csgtile/worker/publish.h"

namespace csgtile::worker {

namespace {

using Json = nlohmann::ordered_json;
using kernel::Shape;
using kernel::ShapeKind;
using kernel::Vec3;

/// A vertex in units of the scale (x, y, z), as the file stores it relative to translate.
using Point = std::array<std::int64_t, 3>;
using Ring = std::vector<Point>;

// In the order of a geometry's semantics.surfaces (those used).
enum class Semantic { Roof, Wall, Ground };
constexpr std::array<const char*, 3> kSemanticNames = {"RoofSurface", "WallSurface",
                                                       "GroundSurface"};

struct Surface {
  std::vector<Ring> rings;  ///< exterior first; open rings
  Semantic semantic = Semantic::Wall;
};
using ShellSurfaces = std::vector<Surface>;
using SolidShells = std::vector<ShellSurfaces>;  ///< exterior shell first

struct ObjectGeometry {
  std::vector<SolidShells> solids;
  bool closed = true;  ///< every shell closed and outward after quantisation
  std::size_t collapsed_triangles = 0, flat_surfaces = 0;
};

// Units beyond 2^53 lose integers in the doubles they come from.
constexpr double kMaxUnits = 9.0e15;

std::optional<Point> quantise(const Vec3& p, double scale) {
  Point q{};
  for (int i = 0; i < 3; ++i) {
    const double v = p[i] / scale;
    if (!std::isfinite(v) || std::abs(v) > kMaxUnits) return std::nullopt;
    q[i] = std::llround(v);
  }
  return q;
}

// Vertices of one object welded at the file's resolution: a quantised point within one unit
// (per axis) of an earlier one becomes that one. Validators snap vertices closer than their
// tolerance (val3dity: 1 mm, the default scale's unit), so two distinct vertices a unit
// apart read as one repeated point (CONSECUTIVE_POINTS_SAME) or a self-touching ring.
// First come, first kept: representatives are pairwise more than a unit apart;
// deterministic for the same mesh.
class Welder {
 public:
  Point operator()(const Point& p) {
    if (const auto it = seen_.find(p); it != seen_.end()) return it->second;
    Point rep = p;
    bool found = false;
    for (std::int64_t dx = -1; dx <= 1 && !found; ++dx) {
      for (std::int64_t dy = -1; dy <= 1 && !found; ++dy) {
        for (std::int64_t dz = -1; dz <= 1 && !found; ++dz) {
          const Point q{p[0] + dx, p[1] + dy, p[2] + dz};
          if (representatives_.count(q) != 0) {
            rep = q;
            found = true;
          }
        }
      }
    }
    if (!found) representatives_.insert(p);
    seen_.emplace(p, rep);
    return rep;
  }

 private:
  struct Hash {
    std::size_t operator()(const Point& p) const {
      std::uint64_t h = 1469598103934665603ULL;
      for (std::int64_t v : p) h = (h ^ static_cast<std::uint64_t>(v)) * 1099511628211ULL;
      return static_cast<std::size_t>(h);
    }
  };
  std::unordered_set<Point, Hash> representatives_;
  std::unordered_map<Point, Point, Hash> seen_;
};

// Consecutive repeats removed, the ring read cyclically.
Ring without_repeats(Ring ring) {
  ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
  while (ring.size() > 1 && ring.front() == ring.back()) ring.pop_back();
  return ring;
}

std::array<std::int64_t, 3> minus(const Point& a, const Point& b) {
  return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}

// Exact in 64-bit integers for differences below 2^31 units (2000 km at 1 mm).
bool collinear(const Ring& ring) {
  if (ring.size() < 3) return true;
  const Point& o = ring[0];
  std::size_t k = 1;
  while (k < ring.size() && ring[k] == o) ++k;
  if (k == ring.size()) return true;
  const auto d = minus(ring[k], o);
  for (std::size_t i = k + 1; i < ring.size(); ++i) {
    const auto e = minus(ring[i], o);
    if (d[1] * e[2] - d[2] * e[1] != 0 || d[2] * e[0] - d[0] * e[2] != 0 ||
        d[0] * e[1] - d[1] * e[0] != 0) {
      return false;
    }
  }
  return true;
}

// Newell's normal of a ring (twice its area vector), about its first point.
Vec3 ring_normal(const Ring& ring) {
  Vec3 n = Vec3::Zero();
  if (ring.empty()) return n;
  const Point& o = ring[0];
  for (std::size_t i = 0; i < ring.size(); ++i) {
    const auto a = minus(ring[i], o);
    const auto b = minus(ring[(i + 1) % ring.size()], o);
    const Vec3 va(static_cast<double>(a[0]), static_cast<double>(a[1]), static_cast<double>(a[2]));
    const Vec3 vb(static_cast<double>(b[0]), static_cast<double>(b[1]), static_cast<double>(b[2]));
    n += va.cross(vb);
  }
  return n;
}

// A quantised planar polygon is kept as one surface when its rings are still simple enough
// to be valid: at least three points each, no point used twice, an exterior with an area.
bool clean_polygon(const std::vector<Ring>& rings) {
  std::set<Point> seen;
  for (const Ring& ring : rings) {
    if (ring.size() < 3) return false;
    for (const Point& p : ring) {
      if (!seen.insert(p).second) return false;
    }
  }
  return !rings.empty() && !collinear(rings[0]);
}

// Features of a polygon this many units (quantisation steps) or smaller: a validator's
// triangulation of it has a triangle that thin, whose normal the rounding of its corners
// (up to half a unit each) turns by more than val3dity's 20° (its planarity test by the
// normals of its triangulation). Ten units keep them within about 5°.
constexpr double kFragileUnits = 10.0;

// Whether a quantised polygon has an edge shorter than kFragileUnits or a point that close
// to an edge it does not end (a neck, a spike, a hole touching its exterior): published as
// its tessellation's triangles instead (a triangle is planar whatever its rounding).
bool fragile_polygon(const std::vector<Ring>& rings) {
  auto at = [](const Point& p) {
    return Vec3(static_cast<double>(p[0]), static_cast<double>(p[1]), static_cast<double>(p[2]));
  };
  const double limit2 = kFragileUnits * kFragileUnits;
  for (std::size_t r = 0; r < rings.size(); ++r) {
    const Ring& ring = rings[r];
    for (std::size_t i = 0; i < ring.size(); ++i) {
      const Vec3 a = at(ring[i]), b = at(ring[(i + 1) % ring.size()]);
      const Vec3 e = b - a;
      const double ee = e.squaredNorm();
      if (ee < limit2) return true;
      for (std::size_t r2 = 0; r2 < rings.size(); ++r2) {
        for (std::size_t j = 0; j < rings[r2].size(); ++j) {
          if (r2 == r && (j == i || j == (i + 1) % ring.size())) continue;
          const Vec3 p = at(rings[r2][j]);
          const double t = std::clamp((p - a).dot(e) / ee, 0.0, 1.0);
          if ((a + t * e - p).squaredNorm() < limit2) return true;
        }
      }
    }
  }
  return false;
}

// Whether a planar face has a curved edge (a circle, an ellipse) drawn finer than the
// quantisation holds: three consecutive points of it whose middle lies closer to the chord of
// the other two than half kFragileUnits (the rounding of the three, up to a unit in space,
// then turns that ear's normal by up to 10°, and two ears' by up to 20°; the chordal
// tolerance alone draws ears of about ten units). Such a polygon's points are nearly cocircular, a
// validator's Delaunay triangulation of it keeps those thin ears, and the rounding turns their
// normals (a disc of 0.25 m radius drawn at 2.4° steps under millimetre units: ears under one
// unit high, normals 30° apart under val3dity). It is published as triangles instead.
bool finely_curved(const Shape& face, const kernel::EdgePoints& edge_points, double scale) {
  const double limit = 0.5 * kFragileUnits * scale;
  for (const Shape& edge : kernel::Explorer(face, ShapeKind::Edge)) {
    const auto& data = edge.body().edge();
    if (data == nullptr || data->degenerate() || data->curve->kind() == kernel::CurveKind::Line) {
      continue;
    }
    const std::vector<Vec3> pts = edge_points(edge);
    for (std::size_t i = 1; i + 1 < pts.size(); ++i) {
      const Vec3 chord = pts[i + 1] - pts[i - 1];
      const double len = chord.norm();
      if (!(len > 0.0)) continue;
      if ((pts[i] - pts[i - 1]).cross(chord).norm() / len < limit) return true;
    }
  }
  return false;
}

// Whether every point of a quantised polygon has the same x, the same y or the same z: it
// lies in one plane of the grid, and any triangulation of it does, whatever the rounding.
bool in_grid_plane(const std::vector<Ring>& rings) {
  for (int axis = 0; axis < 3; ++axis) {
    bool same = true;
    for (const Ring& ring : rings) {
      for (const Point& p : ring) same = same && p[axis] == rings[0][0][axis];
    }
    if (same) return true;
  }
  return false;
}

std::int64_t dot(const std::array<std::int64_t, 3>& a, const std::array<std::int64_t, 3>& b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

// Whether a triangle's point farthest from the others lies within one unit of the line
// through them: a sliver validators read as a line (val3dity snaps at its 1 mm tolerance, the
// default unit), whose neighbours then cross each other at its thin end (three roof planes
// meeting within a millimetre: SHELL_SELF_INTERSECTION). Collinear ones are thin.
bool thin_triangle(const Ring& t) {
  if (t.size() != 3) return false;
  const auto d = minus(t[1], t[0]);
  const auto e = minus(t[2], t[0]);
  const auto f = minus(t[2], t[1]);
  const auto len2 = [](const std::array<std::int64_t, 3>& v) {
    return static_cast<double>(v[0]) * static_cast<double>(v[0]) +
           static_cast<double>(v[1]) * static_cast<double>(v[1]) +
           static_cast<double>(v[2]) * static_cast<double>(v[2]);
  };
  const std::array<std::int64_t, 3> c{d[1] * e[2] - d[2] * e[1], d[2] * e[0] - d[0] * e[2],
                                      d[0] * e[1] - d[1] * e[0]};
  // Twice the area over the longest edge is the height on it.
  const double longest2 = std::max({len2(d), len2(e), len2(f)});
  return len2(c) <= longest2;
}

// A triangle whose three points lie on one line (a sliver that quantisation flattened), or
// within a unit of one (thin_triangle), bounds nothing, and validators reject it (a ring
// collapsed to a line). It is removed and
// its middle point inserted into the surface across its long edge: that surface's two new
// edges are the reverses of the ones the triangle shared with its other neighbours, so the
// shell stays closed (a triangle across it is cut in two instead, so that no ring holds three
// points on a line). A flat triangle and its twin (the same points reversed: a fin) both go.
// Returns how many collinear ones were removed (thin ones were never counted flat).
std::size_t absorb_flat_triangles(ShellSurfaces& shell) {
  std::size_t absorbed = 0;
  // The scans end (see the split below); each starts after the last change.
  std::size_t from = 0;
  for (;;) {
    bool changed = false;
    for (std::size_t si = from; si < shell.size(); ++si) {
      const Surface& s = shell[si];
      if (s.rings.size() != 1 || s.rings[0].size() != 3 || !thin_triangle(s.rings[0])) continue;
      const std::size_t flat = collinear(s.rings[0]) ? 1 : 0;
      from = si;  // where the next scan starts when this one changes the shell
      const Ring t = s.rings[0];
      int mid = -1;  // the point lying between the other two
      for (int k = 0; k < 3 && mid < 0; ++k) {
        const Point& m = t[k];
        const Point& a = t[(k + 1) % 3];
        const Point& b = t[(k + 2) % 3];
        if (dot(minus(m, a), minus(b, a)) >= 0 && dot(minus(m, b), minus(a, b)) >= 0) mid = k;
      }
      if (mid < 0) continue;
      const Point m = t[mid];
      const Point a = t[(mid + 1) % 3];
      const Point b = t[(mid + 2) % 3];  // the long edge is a → b; across it, b → a
      // Its twin (the same three points the other way round, a zero-volume fin): both go.
      std::size_t twin = shell.size();
      for (std::size_t sj = 0; sj < shell.size() && twin == shell.size(); ++sj) {
        const Surface& o = shell[sj];
        if (sj == si || o.rings.size() != 1 || o.rings[0].size() != 3) continue;
        const Ring& r = o.rings[0];
        for (int k = 0; k < 3; ++k) {
          if (r[k] == b && r[(k + 1) % 3] == a && r[(k + 2) % 3] == m) twin = sj;
        }
      }
      if (twin != shell.size()) {
        shell.erase(shell.begin() + static_cast<std::ptrdiff_t>(std::max(si, twin)));
        shell.erase(shell.begin() + static_cast<std::ptrdiff_t>(std::min(si, twin)));
        from = std::min(si, twin);
        absorbed += 2 * flat;
        changed = true;
        break;  // indices moved: scan again
      }
      bool inserted = false;
      std::optional<Surface> split;  // a triangle across the edge is cut in two at m
      for (std::size_t sj = 0; sj < shell.size() && !inserted; ++sj) {
        if (sj == si) continue;
        for (Ring& ring : shell[sj].rings) {
          const std::size_t n = ring.size();
          for (std::size_t i = 0; i < n && !inserted; ++i) {
            if (ring[i] != b || ring[(i + 1) % n] != a ||
                std::find(ring.begin(), ring.end(), m) != ring.end()) {
              continue;
            }
            if (n == 3 && shell[sj].rings.size() == 1) {
              // A thin triangle that is not flat splits its neighbour only into two triangles
              // that are not thin themselves. Every change then leaves fewer flat triangles, or
              // as many and fewer thin ones, and the scans end.
              const Point d = ring[(i + 2) % 3];
              if (flat == 0 && (thin_triangle({b, m, d}) || thin_triangle({m, a, d}))) continue;
              ring = {b, m, d};
              split = Surface{{{m, a, d}}, shell[sj].semantic};
            } else {
              ring.insert(ring.begin() + static_cast<std::ptrdiff_t>(i + 1), m);
            }
            inserted = true;
          }
          if (inserted) break;
        }
      }
      if (!inserted) continue;
      shell.erase(shell.begin() + static_cast<std::ptrdiff_t>(si));
      if (split) shell.push_back(std::move(*split));
      absorbed += flat;
      changed = true;
      break;  // indices moved: scan again
    }
    if (!changed) break;
  }
  return absorbed;
}

// Every directed edge of the shell's rings used once, and its reverse once: closed, and
// consistently oriented.
bool shell_closed(const ShellSurfaces& shell) {
  std::vector<std::pair<Point, Point>> edges;
  for (const Surface& s : shell) {
    for (const Ring& ring : s.rings) {
      for (std::size_t i = 0; i < ring.size(); ++i)
        edges.emplace_back(ring[i], ring[(i + 1) % ring.size()]);
    }
  }
  if (edges.empty()) return false;
  std::sort(edges.begin(), edges.end());
  if (std::adjacent_find(edges.begin(), edges.end()) != edges.end()) return false;
  return std::all_of(edges.begin(), edges.end(), [&](const auto& e) {
    return std::binary_search(edges.begin(), edges.end(), std::make_pair(e.second, e.first));
  });
}

// Signed volume enclosed by the shell in units³ (positive when its surfaces face outwards
// from what they enclose), as cones from the shell's first point over each ring's fan.
double shell_volume(const ShellSurfaces& shell) {
  const Point* origin = nullptr;
  double six_volume = 0.0;
  for (const Surface& s : shell) {
    for (const Ring& ring : s.rings) {
      if (origin == nullptr && !ring.empty()) origin = &ring[0];
      for (std::size_t i = 1; i + 1 < ring.size(); ++i) {
        auto to_vec = [&](const Point& p) {
          const auto d = minus(p, *origin);
          return Vec3(static_cast<double>(d[0]), static_cast<double>(d[1]),
                      static_cast<double>(d[2]));
        };
        six_volume += to_vec(ring[0]).dot(to_vec(ring[i]).cross(to_vec(ring[i + 1])));
      }
    }
  }
  return six_volume / 6.0;
}

// The semantic rule of the header: from the exterior ring's normal and the surface's top.
Semantic classify(const Surface& s, std::int64_t object_min_z, double ground_units) {
  const Vec3 n = ring_normal(s.rings[0]);
  const double length = n.norm();
  if (!(length > 0.0)) return Semantic::Wall;
  const double nz = n.z() / length;
  std::int64_t top = std::numeric_limits<std::int64_t>::min();
  for (const Point& p : s.rings[0]) top = std::max(top, p[2]);
  const bool at_ground = static_cast<double>(top - object_min_z) <= ground_units;
  if (nz < -0.9 && at_ground) return Semantic::Ground;
  if (nz > 0.2 && !at_ground) return Semantic::Roof;
  return Semantic::Wall;
}

// The surfaces of each solid of `root`, shell by shell, quantised. Planar faces are polygons
// from their wires, curved faces (and planar ones whose polygon does not survive
// quantisation or is too fragile for it) triangles of one tessellation, whose edge points the
// polygons share.
// `given`: root's tessellation at the chordal tolerance, when the object's job made it once
// for every exporter.
kernel::Result<ObjectGeometry> object_geometry(const Shape& root, const CityJsonOptions& options,
                                               bool weld_vertices,
                                               std::shared_ptr<const kernel::Mesh> given = {}) {
  auto meshed = kernel::shared_tessellation(root, options.chordal_tolerance, std::move(given));
  if (!meshed.ok()) return meshed.error();
  const kernel::Mesh& mesh = *meshed.value();
  const kernel::ShapeIndex faces = kernel::map_child_shapes(root, ShapeKind::Face);

  const std::vector<Vec3>& vertices = mesh.vertices;
  std::vector<Point> points;
  points.reserve(vertices.size());
  Welder welder;
  auto weld = [&](const Point& p) { return weld_vertices ? welder(p) : p; };
  for (const Vec3& v : vertices) {
    const auto q = quantise(v, options.scale);
    if (!q) {
      return kernel::Error{kernel::ErrorCode::InvalidArgument,
                           "a vertex is not finite or too far from the origin for the scale"};
    }
    points.push_back(weld(*q));
  }
  std::vector<std::vector<std::size_t>> triangles_of(faces.size());
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    if (mesh.triangle_face[i] < faces.size()) triangles_of[mesh.triangle_face[i]].push_back(i);
  }
  const kernel::EdgePoints edge_points = kernel::mesh_edge_points(root, mesh);

  ObjectGeometry geometry;
  auto add_face = [&](std::size_t f, ShellSurfaces& shell) {
    const Shape& face = faces[f];
    if (face.orientation() != kernel::Orientation::Forward &&
        face.orientation() != kernel::Orientation::Reversed) {
      return;  // Internal and External faces bound nothing
    }
    if (face.body().face()->surface->kind() == kernel::SurfaceKind::Plane) {
      if (auto rings = kernel::planar_face_rings(face, edge_points)) {
        Surface s;
        for (const auto& ring : *rings) {
          Ring q;
          for (const Vec3& p : ring) q.push_back(weld(*quantise(p, options.scale)));
          s.rings.push_back(without_repeats(std::move(q)));
        }
        if (clean_polygon(s.rings) && !fragile_polygon(s.rings) &&
            (in_grid_plane(s.rings) || !finely_curved(face, edge_points, options.scale))) {
          shell.push_back(std::move(s));
          return;
        }
      }
    }
    for (std::size_t i : triangles_of[f]) {
      const auto& tri = mesh.triangles[i];
      Ring q = {points[tri[0]], points[tri[1]], points[tri[2]]};
      if (q[0] == q[1] || q[1] == q[2] || q[2] == q[0]) {
        ++geometry.collapsed_triangles;  // its edges pair up among its neighbours
        continue;
      }
      if (collinear(q)) ++geometry.flat_surfaces;
      shell.push_back(Surface{{std::move(q)}, Semantic::Wall});
    }
  };

  const kernel::ShapeIndex solids = kernel::map_child_shapes(root, ShapeKind::Solid);
  for (const Shape& solid : solids.shapes()) {
    std::vector<ShellSurfaces> shells;
    std::vector<double> volumes;
    const kernel::ShapeIndex solid_shells = kernel::map_child_shapes(solid, ShapeKind::Shell);
    for (const Shape& shell : solid_shells.shapes()) {
      ShellSurfaces surfaces;
      const kernel::ShapeIndex shell_faces = kernel::map_child_shapes(shell, ShapeKind::Face);
      for (const Shape& face : shell_faces.shapes()) {
        if (const std::size_t f = faces.find(face); f != kernel::ShapeIndex::npos)
          add_face(f, surfaces);
      }
      if (surfaces.empty()) continue;
      geometry.flat_surfaces -= std::min(geometry.flat_surfaces, absorb_flat_triangles(surfaces));
      geometry.closed &= shell_closed(surfaces);
      volumes.push_back(shell_volume(surfaces));
      shells.push_back(std::move(surfaces));
    }
    if (shells.empty()) continue;
    // The exterior shell encloses the most; cavities face into the voids they bound.
    const std::size_t exterior = static_cast<std::size_t>(
        std::max_element(volumes.begin(), volumes.end()) - volumes.begin());
    for (std::size_t i = 0; i < volumes.size(); ++i) {
      geometry.closed &= i == exterior ? volumes[i] > 0.0 : volumes[i] < 0.0;
    }
    std::rotate(shells.begin(), shells.begin() + static_cast<std::ptrdiff_t>(exterior),
                shells.begin() + static_cast<std::ptrdiff_t>(exterior) + 1);
    geometry.solids.push_back(std::move(shells));
  }

  if (geometry.solids.empty()) {
    return kernel::Error{kernel::ErrorCode::DegenerateGeometry, "no face bounds the object"};
  }
  std::int64_t min_z = std::numeric_limits<std::int64_t>::max();
  for (const SolidShells& solid : geometry.solids) {
    for (const ShellSurfaces& shell : solid) {
      for (const Surface& s : shell) {
        for (const Ring& ring : s.rings) {
          for (const Point& p : ring) min_z = std::min(min_z, p[2]);
        }
      }
    }
  }
  const double ground_units = options.ground_tolerance / options.scale;
  for (SolidShells& solid : geometry.solids) {
    for (ShellSurfaces& shell : solid) {
      for (Surface& s : shell) s.semantic = classify(s, min_z, ground_units);
    }
  }
  return geometry;
}

// Vertices of one feature: distinct points in first-use order.
class FeatureVertices {
 public:
  std::size_t id(const Point& p) {
    const auto [it, added] = ids_.emplace(p, points_.size());
    if (added) points_.push_back(p);
    return it->second;
  }
  const std::vector<Point>& points() const { return points_; }

 private:
  std::map<Point, std::size_t> ids_;
  std::vector<Point> points_;
};

Json surface_json(const Surface& s, FeatureVertices& vertices) {
  Json rings = Json::array();
  for (const Ring& ring : s.rings) {
    Json ids = Json::array();
    for (const Point& p : ring) ids.push_back(vertices.id(p));
    rings.push_back(std::move(ids));
  }
  return rings;
}

// Solid (one solid), MultiSolid (several) or, when a shell is open, MultiSurface; semantic
// surfaces listed in Semantic order, those used only.
Json geometry_json(const ObjectGeometry& g, const char* lod, FeatureVertices& vertices) {
  std::array<bool, kSemanticNames.size()> used{};
  for (const SolidShells& solid : g.solids) {
    for (const ShellSurfaces& shell : solid) {
      for (const Surface& s : shell) used[static_cast<std::size_t>(s.semantic)] = true;
    }
  }
  std::array<int, kSemanticNames.size()> position{};
  Json surfaces = Json::array();
  for (std::size_t k = 0; k < used.size(); ++k) {
    if (!used[k]) continue;
    position[k] = static_cast<int>(surfaces.size());
    surfaces.push_back(Json{{"type", kSemanticNames[k]}});
  }
  auto shell_json = [&](const ShellSurfaces& shell, Json& boundaries, Json& values) {
    for (const Surface& s : shell) {
      boundaries.push_back(surface_json(s, vertices));
      values.push_back(position[static_cast<std::size_t>(s.semantic)]);
    }
  };
  Json boundaries = Json::array(), values = Json::array();
  std::string type;
  if (!g.closed) {
    type = "MultiSurface";
    for (const SolidShells& solid : g.solids) {
      for (const ShellSurfaces& shell : solid) shell_json(shell, boundaries, values);
    }
  } else {
    for (const SolidShells& solid : g.solids) {
      Json solid_boundaries = Json::array(), solid_values = Json::array();
      for (const ShellSurfaces& shell : solid) {
        Json b = Json::array(), v = Json::array();
        shell_json(shell, b, v);
        solid_boundaries.push_back(std::move(b));
        solid_values.push_back(std::move(v));
      }
      boundaries.push_back(std::move(solid_boundaries));
      values.push_back(std::move(solid_values));
    }
    type = g.solids.size() == 1 ? "Solid" : "MultiSolid";
    if (g.solids.size() == 1) {
      boundaries = std::move(boundaries[0]);
      values = std::move(values[0]);
    }
  }
  Json out;
  out["type"] = type;
  out["lod"] = lod;
  out["boundaries"] = std::move(boundaries);
  out["semantics"] = {{"surfaces", std::move(surfaces)}, {"values", std::move(values)}};
  return out;
}

Json attributes_json(const IndexObject& object, const std::optional<ObjectGeometry>& geometry,
                     const CityJsonOptions& options) {
  std::set<std::string> types;
  for (const PrimitiveInfo& p : object.primitives) types.insert(p.type);
  const kernel::MassProperties mp = kernel::mass_properties(object.model.shape);
  Json a;
  a["primitive_types"] = Json(std::vector<std::string>(types.begin(), types.end()));
  a["primitive_count"] = object.primitives.size();
  a["csg_nodes"] = object.model.nodes.size();
  a["volume"] = mp.volume;
  a["area"] = mp.area;
  a["valid"] = model_valid(object);
  const FitSummary fit = fit_summary(object.primitives);
  if (fit.rms) a["fit_rms"] = *fit.rms;
  if (fit.coverage) a["fit_coverage"] = *fit.coverage;
  if (fit.within_2sigma) a["fit_within_2sigma"] = *fit.within_2sigma;
  // All of its points against its model, as 3DBAG's b3_rmse_lod22.
  if (const auto& m = object.model_fit) {
    a["model_rmse"] = m->rmse;
    a["model_points"] = m->points;
    if (m->within_2sigma) a["model_within_2sigma"] = *m->within_2sigma;
  }
  if (geometry) {
    a["closed"] = geometry->closed;
    if (geometry->collapsed_triangles > 0) a["collapsed_triangles"] = geometry->collapsed_triangles;
  }
  if (object.escalation) a["fuse_escalation"] = escalation_json(object.escalation);
  // Heights (issue #18 item 6), in the file's CRS heights.
  if (const auto& h = object.heights) {
    const double z0 = options.origin.z();
    a["h_ground"] = h->ground + z0;
    a["h_roof_min"] = h->roof_min + z0;
    a["h_roof_50p"] = h->roof_50p + z0;
    a["h_roof_70p"] = h->roof_70p + z0;
    a["h_roof_max"] = h->roof_max + z0;
    a["roof_surfaces"] = h->roof_faces;
  }
  return a;
}

Failure check_input(const std::vector<IndexObject>& objects, const CityJsonOptions& options) {
  if (!(options.scale > 0.0) || !std::isfinite(options.scale) ||
      !(options.chordal_tolerance > 0.0) || !(options.ground_tolerance >= 0.0) ||
      !options.origin.allFinite()) {
    return {ErrorCode::InputInvalid,
            "CityJSON: scale and chordal tolerance must be > 0, the ground tolerance >= 0 and "
            "the origin finite"};
  }
  std::set<std::string> seen;
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const IndexObject& o = objects[i];
    const std::string where = "CityJSON: object " + std::to_string(i);
    if (o.id.empty()) return {ErrorCode::InputInvalid, where + " has an empty id"};
    if (!seen.insert(o.id).second) {
      return {ErrorCode::InputInvalid, where + ": duplicate id \"" + o.id + "\""};
    }
    const Shape& s = o.model.shape;
    if (s.is_null() || kernel::map_child_shapes(s, ShapeKind::Solid).size() == 0) {
      return {ErrorCode::InputInvalid,
              where + " (\"" + o.id + "\") is not a solid or a compound of solids"};
    }
  }
  return {};
}

// Coordinates in the metadata are rounded to 1e-6 so that they print as short decimals
// (the vertices themselves are exact integers).
double rounded(double v) { return std::round(v * 1e6) / 1e6; }

std::string dump_line(const Json& j) {
  return j.dump(-1, ' ', false, Json::error_handler_t::replace) + "\n";
}

}  // namespace

std::string cityjson_reference_system(const geo::Crs& crs, std::vector<std::string>* warnings) {
  // Compound CRSs EPSG defines for a horizontal + vertical pair this build knows.
  struct Compound {
    int horizontal, vertical, code;
  };
  constexpr Compound kCompounds[] = {{28992, 5709, 7415}, {27700, 5701, 7405}};
  if (crs.epsg <= 0) return {};
  int code = crs.epsg;
  if (crs.vertical && crs.vertical->epsg > 0) {
    const auto it = std::find_if(std::begin(kCompounds), std::end(kCompounds), [&](const auto& c) {
      return c.horizontal == crs.epsg && c.vertical == crs.vertical->epsg;
    });
    if (it != std::end(kCompounds)) {
      code = it->code;
    } else if (warnings != nullptr) {
      warnings->push_back("CityJSON: EPSG:" + std::to_string(crs.epsg) + "+" +
                          std::to_string(crs.vertical->epsg) +
                          " has no compound EPSG code here; referenceSystem names the "
                          "horizontal CRS only");
    }
  }
  return "https://www.opengis.net/def/crs/EPSG/0/" + std::to_string(code);
}

Result<std::string> cityjson_seq(const std::vector<IndexObject>& objects,
                                 const CityJsonOptions& options, CityJsonStats* stats) {
  CityJsonStats local;
  CityJsonStats& st = stats != nullptr ? *stats : local;
  st = CityJsonStats{};
  if (Failure s = check_input(objects, options); !s.ok()) return s;

  std::string features;
  Point low{}, high{};
  bool any_vertex = false;
  for (const IndexObject& object : objects) {
    // Vertices welded at the file's unit (what validators do); where welding would open a
    // shell that is closed without it (a collapse that pinches the surface), not welded.
    const auto mesh = shared_mesh(object, options.chordal_tolerance);
    auto geometry = object_geometry(object.model.shape, options, true, mesh);
    if (geometry.ok() && !geometry.value().closed) {
      auto plain = object_geometry(object.model.shape, options, false, mesh);
      if (plain.ok() && plain.value().closed) geometry = std::move(plain);
    }
    std::optional<ObjectGeometry> g;
    if (geometry.ok()) {
      g = std::move(geometry).value();
    } else {
      st.warnings.push_back("CityJSON: object " + object.id +
                            ": no geometry: " + kernel::error_code_name(geometry.error().code) +
                            ": " + geometry.error().message);
    }
    // A building's LoD1.2 block and LoD1.3 levels beside its LoD2.2 model, as 3DBAG
    // publishes them: each one closed solid after quantisation, or the reason it is missing.
    auto block_geometry = [&](const std::optional<kernel::CsgModel>& model, std::string& problem,
                              const char* lod) -> std::optional<ObjectGeometry> {
      std::optional<ObjectGeometry> out;
      if (model) {
        auto b = object_geometry(model->shape, options, true);
        if (b.ok() && b.value().closed && b.value().solids.size() == 1) {
          out = std::move(b).value();
        } else {
          problem = b.ok() ? "its shell is not closed after quantisation"
                           : kernel::error_code_name(b.error().code) + std::string(": ") +
                                 b.error().message;
        }
      }
      if (!problem.empty()) {
        st.warnings.push_back("CityJSON: object " + object.id + ": no " + lod + ": " + problem);
      }
      return out;
    };
    std::string block_problem = object.lod12_error;
    const std::optional<ObjectGeometry> block =
        block_geometry(object.lod12, block_problem, "LoD1.2");
    std::string levels_problem = block ? object.lod13_error : std::string();
    const std::optional<ObjectGeometry> levels =
        block ? block_geometry(object.lod13, levels_problem, "LoD1.3") : std::nullopt;
    const bool building = is_building(object);
    const bool one_solid = g && g->solids.size() == 1;
    FeatureVertices vertices;
    Json city_object;
    // CityJSON's Building admits no MultiSolid: an object of several solids (a group whose
    // fuse failed, or a result in pieces) is a GenericCityObject, unless it is a building
    // with its LoD1.2 block: then a Building of that block alone, the reason recorded.
    city_object["type"] = g && !one_solid && !block ? "GenericCityObject" : "Building";
    Json attributes = attributes_json(object, g, options);
    if (building) {
      // Its outline: the footprint it was fitted in (its id), or derived from the points.
      if (!object.footprint_id.empty()) attributes["footprint_id"] = object.footprint_id;
      attributes["outline"] = object.footprint_id.empty() ? "derived" : "footprint";
      attributes["lod_reached"] = one_solid ? Json("2.2")
                                  : levels  ? Json("1.3")
                                  : block   ? Json("1.2")
                                            : Json();
      if (g && !one_solid) {
        attributes["lod22_failure"] = lod22_failure(object);
      }
      if (!block_problem.empty()) attributes["lod12_failure"] = block_problem;
      if (!levels_problem.empty()) attributes["lod13_failure"] = levels_problem;
    }
    city_object["attributes"] = std::move(attributes);
    Json geometries = Json::array();
    if (g && (one_solid || !block)) {
      geometries.push_back(geometry_json(*g, building ? "2.2" : "2", vertices));
    }
    if (levels) geometries.push_back(geometry_json(*levels, "1.3", vertices));
    if (block) geometries.push_back(geometry_json(*block, "1.2", vertices));
    if (!geometries.empty()) city_object["geometry"] = std::move(geometries);
    if (g) {
      st.collapsed_triangles += g->collapsed_triangles;
      st.flat_surfaces += g->flat_surfaces;
      for (const SolidShells& solid : g->solids) {
        for (const ShellSurfaces& shell : solid) st.surfaces += shell.size();
      }
      if (!g->closed) {
        ++st.open_objects;
        st.warnings.push_back("CityJSON: object " + object.id +
                              ": a shell is not closed and outward after quantisation; "
                              "written as MultiSurface");
      }
    }
    Json vertex_list = Json::array();
    for (const Point& p : vertices.points()) {
      vertex_list.push_back(Json::array({p[0], p[1], p[2]}));
      if (!any_vertex) low = high = p;
      any_vertex = true;
      for (int i = 0; i < 3; ++i) {
        low[i] = std::min(low[i], p[i]);
        high[i] = std::max(high[i], p[i]);
      }
    }
    Json feature;
    feature["type"] = "CityJSONFeature";
    feature["id"] = object.id;
    feature["CityObjects"] = {{object.id, std::move(city_object)}};
    feature["vertices"] = std::move(vertex_list);
    features += dump_line(feature);
    ++st.features;
  }

  Json header;
  header["type"] = "CityJSON";
  header["version"] = "2.0";
  header["transform"] = {
      {"scale", {options.scale, options.scale, options.scale}},
      {"translate", {options.origin.x(), options.origin.y(), options.origin.z()}}};
  header["CityObjects"] = Json::object();
  header["vertices"] = Json::array();
  Json metadata = Json::object();
  if (options.crs) {
    const std::string url = cityjson_reference_system(*options.crs, &st.warnings);
    if (!url.empty()) metadata["referenceSystem"] = url;
  }
  if (any_vertex) {
    Json extent = Json::array();
    for (const Point* p : {&low, &high}) {
      for (int i = 0; i < 3; ++i)
        extent.push_back(rounded(options.origin[i] + static_cast<double>((*p)[i]) * options.scale));
    }
    metadata["geographicalExtent"] = std::move(extent);
  }
  header["metadata"] = std::move(metadata);
  return dump_line(header) + features;
}

Failure write_run_cityjson(const RunExportOptions& settings, const RunObjects& run,
                           const std::filesystem::path& run_dir, CityJsonReport& report) {
  CityJsonOptions options;
  options.crs = run.crs;
  options.origin = run.origin;
  options.chordal_tolerance = settings.chordal_tolerance;
  auto text = cityjson_seq(run.objects, options, &report.stats);
  if (!text.ok()) return {ErrorCode::Internal, text.error().message};
  if (Failure f = write_file_atomic(run_dir / report.key, text.value()); !f.ok()) return f;
  report.sha256 = sha256_hex(text.value());
  report.bytes = text.value().size();
  return {};
}

}  // namespace csgtile::worker
