// Tile content (tile_content.h): objects tessellated, mapped to ENU, split per face, rotated
// to glTF's y up, with one property table row per object.

#include "export/tile_content.h"

#include <cmath>
#include <cstdint>
#include <set>
#include <unordered_map>

#include "csgtile/kernel/check.h"
#include "csgtile/kernel/mass_properties.h"
#include "csgtile/kernel/tessellation.h"
#include "export/gltf_writer.h"

namespace csgtile::worker {

namespace {

using kernel::Vec3;

// One object's triangles in ENU (double), vertices split per face.
struct ObjectMesh {
  std::vector<Vec3> positions;
  std::vector<Vec3> normals;  // unit
  std::vector<std::uint32_t> indices;
};

kernel::Result<ObjectMesh> object_mesh(const IndexObject& object,
                                       const TileContentOptions& options) {
  auto meshed = model_mesh(object, options.chordal_tolerance);
  if (!meshed.ok()) return meshed.error();
  const kernel::Mesh& mesh = *meshed.value();
  if (mesh.triangles.empty()) {
    return kernel::Error{kernel::ErrorCode::DegenerateGeometry, "no triangles"};
  }
  std::vector<Vec3> enu;
  enu.reserve(mesh.vertices.size());
  for (const Vec3& v : mesh.vertices) {
    const Vec3 p = options.to_enu ? options.to_enu(v) : v;
    if (!p.allFinite()) {
      return kernel::Error{kernel::ErrorCode::InvalidArgument,
                           "a vertex is outside the CRS's domain"};
    }
    enu.push_back(p);
  }

  // A vertex of the tessellation gets one copy per face using it: (face, vertex) → copy,
  // numbered in first use, so the order does not depend on the map.
  ObjectMesh out;
  std::unordered_map<std::uint64_t, std::uint32_t> copies;
  std::vector<Vec3> sums;  // area-weighted normals per copy
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    const auto& tri = mesh.triangles[i];
    const Vec3 n = (enu[tri[1]] - enu[tri[0]]).cross(enu[tri[2]] - enu[tri[0]]);
    for (std::uint32_t v : tri) {
      const std::uint64_t key = (std::uint64_t{mesh.triangle_face[i]} << 32) | v;
      const auto [it, added] =
          copies.emplace(key, static_cast<std::uint32_t>(out.positions.size()));
      if (added) {
        out.positions.push_back(enu[v]);
        sums.emplace_back(Vec3::Zero());
      }
      sums[it->second] += n;
      out.indices.push_back(it->second);
    }
  }
  out.normals.reserve(sums.size());
  for (const Vec3& s : sums) {
    const double length = s.norm();
    // Only a vertex whose every triangle collapsed in ENU has no direction; up is harmless.
    out.normals.push_back(length > 0.0 ? Vec3(s / length) : Vec3::UnitZ());
  }
  return out;
}

// glTF is y up: ENU (x, y, z) is stored as (x, z, −y).
std::array<float, 3> to_y_up(const Vec3& p) {
  return {static_cast<float>(p.x()), static_cast<float>(p.z()), static_cast<float>(-p.y())};
}

Failure check_input(const std::vector<IndexObject>& objects, const TileContentOptions& options) {
  if (!(options.chordal_tolerance > 0.0) || !std::isfinite(options.chordal_tolerance)) {
    return {ErrorCode::InputInvalid, "3D Tiles: the chordal tolerance must be > 0"};
  }
  std::set<std::string> seen;
  for (std::size_t i = 0; i < objects.size(); ++i) {
    if (objects[i].id.empty() || !seen.insert(objects[i].id).second) {
      return {ErrorCode::InputInvalid,
              "3D Tiles: object " + std::to_string(i) + " has an empty or duplicate id"};
    }
  }
  return {};
}

}  // namespace

Result<TileContent> tile_content(const std::vector<IndexObject>& objects,
                                 const TileContentOptions& options) {
  if (Failure s = check_input(objects, options); !s.ok()) return s;
  TileContent content;
  GltfMesh mesh;
  std::vector<std::string> ids, cells, types;
  std::vector<std::uint32_t> primitive_counts;
  std::vector<double> volumes, areas;
  std::vector<bool> valid;
  for (const IndexObject& object : objects) {
    auto m = object_mesh(object, options);
    if (!m.ok()) {
      content.warnings.push_back("3D Tiles: object " + object.id +
                                 " left out: " + kernel::error_code_name(m.error().code) + ": " +
                                 m.error().message);
      continue;
    }
    const auto feature = static_cast<std::uint32_t>(ids.size());
    const auto base = static_cast<std::uint32_t>(mesh.positions.size());
    for (std::size_t v = 0; v < m->positions.size(); ++v) {
      mesh.positions.push_back(to_y_up(m->positions[v]));
      mesh.normals.push_back(to_y_up(m->normals[v]));
      mesh.feature_ids.push_back(feature);
    }
    for (std::uint32_t i : m->indices) mesh.indices.push_back(base + i);

    std::set<std::string> kinds;
    for (const PrimitiveInfo& p : object.primitives) kinds.insert(p.type);
    std::string joined;
    for (const std::string& k : kinds) joined += (joined.empty() ? "" : ",") + k;
    const kernel::MassProperties mp = kernel::mass_properties(object.model.shape);
    ids.push_back(object.id);
    cells.push_back(object.cell);
    types.push_back(std::move(joined));
    primitive_counts.push_back(static_cast<std::uint32_t>(object.primitives.size()));
    volumes.push_back(mp.volume);
    areas.push_back(mp.area);
    valid.push_back(model_valid(object));
  }
  if (ids.empty()) {
    std::string why = "3D Tiles: no object has triangles";
    // The first few reasons; the others are usually the same.
    for (std::size_t i = 0; i < content.warnings.size() && i < 3; ++i)
      why += "; " + content.warnings[i];
    return Failure{ErrorCode::GeometryInvalid, why};
  }

  PropertyTable table;
  table.class_description = "A csgtile object: a solid (or compound of solids) of the run";
  table.count = ids.size();
  table.columns = {
      {"id", "Object id, as in the topology index and the CityJSON", ids},
      {"cell", "Output cell of the object", cells},
      {"primitive_types", "Distinct primitive types, comma-separated", types},
      {"primitive_count", "Primitives in the object's CSG tree", primitive_counts},
      {"volume", "Volume in model units cubed", volumes},
      {"area", "Boundary area in model units squared", areas},
      {"valid", "The kernel's checker accepts the object", valid},
  };
  GltfOptions gltf;
  gltf.generator = options.generator;
  auto glb = glb_bytes(mesh, table, gltf);
  if (!glb.ok()) return glb.error();

  content.glb = std::move(glb).value();
  content.object_ids = std::move(ids);
  content.vertices = mesh.positions.size();
  content.triangles = mesh.indices.size() / 3;
  // Bounds of what is stored, back in z up: (x, y, z) = (x_gl, −z_gl, y_gl).
  for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
    const auto& p = mesh.positions[i];
    const Vec3 q(p[0], -static_cast<double>(p[2]), p[1]);
    content.low = i == 0 ? q : Vec3(content.low.cwiseMin(q));
    content.high = i == 0 ? q : Vec3(content.high.cwiseMax(q));
  }
  return content;
}

}  // namespace csgtile::worker
