// GLB bytes (gltf_writer.h): the binary buffer is assembled view by view, the JSON describes
// it, then both are framed as GLB chunks.

#include "export/gltf_writer.h"
#include "little_endian.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>

namespace csgtile::worker {

namespace {

using Json = nlohmann::ordered_json;

constexpr std::uint32_t kGlbMagic = 0x46546C67;  // "glTF"
constexpr std::uint32_t kGlbVersion = 2;
constexpr std::uint32_t kJsonChunkType = 0x4E4F534A;  // "JSON"
constexpr std::uint32_t kBinChunkType = 0x004E4942;   // "BIN\0"
constexpr int kComponentFloat = 5126;
constexpr int kComponentUnsignedInt = 5125;
constexpr int kTargetArrayBuffer = 34962;
constexpr int kTargetElementArrayBuffer = 34963;
constexpr int kModeTriangles = 4;
// Feature ids are stored as float32: integers are exact below 2^24.
constexpr std::size_t kMaxRows = std::size_t{1} << 24;
// Views start at multiples of 8: EXT_structural_metadata's alignment for its columns, and
// more than glTF's 4 for vertex attributes.
constexpr std::size_t kViewAlignment = 8;

void pad(std::string& out, std::size_t alignment, char fill) {
  while (out.size() % alignment != 0) out.push_back(fill);
}

// The BIN chunk under construction and its buffer views.
class Binary {
 public:
  /// Appends `data` as a new view (aligned); returns its index.
  std::size_t add_view(const std::string& data, std::optional<int> target) {
    pad(bytes_, kViewAlignment, '\0');
    Json view;
    view["buffer"] = 0;
    view["byteOffset"] = bytes_.size();
    view["byteLength"] = data.size();
    if (target) view["target"] = *target;
    bytes_ += data;
    views_.push_back(std::move(view));
    return views_.size() - 1;
  }
  std::string& bytes() { return bytes_; }
  Json& views() { return views_; }

 private:
  std::string bytes_;
  Json views_ = Json::array();
};

bool valid_identifier(const std::string& name) {
  if (name.empty()) return false;
  const auto word = [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
  };
  return !(name[0] >= '0' && name[0] <= '9') && std::all_of(name.begin(), name.end(), word);
}

std::size_t column_size(const PropertyColumn& column) {
  return std::visit([](const auto& v) { return v.size(); }, column.values);
}

Failure check_input(const GltfMesh& mesh, const PropertyTable& table) {
  auto bad = [](const std::string& message) {
    return Failure{ErrorCode::InputInvalid, "glTF: " + message};
  };
  const std::size_t n = mesh.positions.size();
  if (n == 0 || mesh.indices.empty()) return bad("the mesh has no triangles");
  if (mesh.normals.size() != n || mesh.feature_ids.size() != n) {
    return bad("positions, normals and feature ids differ in number");
  }
  if (mesh.indices.size() % 3 != 0) return bad("the index count is not a multiple of 3");
  if (n > std::numeric_limits<std::uint32_t>::max()) return bad("too many vertices");
  for (std::uint32_t i : mesh.indices) {
    if (i >= n) return bad("index " + std::to_string(i) + " out of range");
  }
  for (std::size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      if (!std::isfinite(mesh.positions[i][k]) || !std::isfinite(mesh.normals[i][k])) {
        return bad("vertex " + std::to_string(i) + " is not finite");
      }
    }
  }
  if (table.count == 0 || table.count >= kMaxRows) {
    return bad("the property table needs 1 to 2^24 - 1 rows");
  }
  for (std::uint32_t id : mesh.feature_ids) {
    if (id >= table.count) return bad("feature id " + std::to_string(id) + " out of range");
  }
  if (!valid_identifier(table.schema_id) || !valid_identifier(table.class_name)) {
    return bad("schema and class ids must be identifiers");
  }
  std::set<std::string> names;
  for (const PropertyColumn& c : table.columns) {
    if (!valid_identifier(c.name)) return bad("property \"" + c.name + "\" is not an identifier");
    if (!names.insert(c.name).second) return bad("duplicate property \"" + c.name + "\"");
    if (column_size(c) != table.count) {
      return bad("property \"" + c.name + "\" has " + std::to_string(column_size(c)) +
                 " values for " + std::to_string(table.count) + " rows");
    }
  }
  return {};
}

// Accessor of `count` elements over one view.
Json accessor(std::size_t view, int component_type, std::size_t count, const char* type) {
  Json a;
  a["bufferView"] = view;
  a["componentType"] = component_type;
  a["count"] = count;
  a["type"] = type;
  return a;
}

// A column's class property and its table entry; its data goes into `binary`.
std::pair<Json, Json> add_column(const PropertyColumn& column, Binary& binary) {
  Json definition, entry;
  if (!column.description.empty()) definition["description"] = column.description;
  if (const auto* strings = std::get_if<std::vector<std::string>>(&column.values)) {
    definition["type"] = "STRING";
    std::string values, offsets;
    put_u32(offsets, 0);
    for (const std::string& s : *strings) {
      values += s;
      put_u32(offsets, static_cast<std::uint32_t>(values.size()));
    }
    // glTF forbids empty buffer views; the byte past the last offset belongs to no string.
    if (values.empty()) values.push_back('\0');
    entry["values"] = binary.add_view(values, std::nullopt);
    entry["stringOffsets"] = binary.add_view(offsets, std::nullopt);
    entry["stringOffsetType"] = "UINT32";
  } else if (const auto* numbers = std::get_if<std::vector<double>>(&column.values)) {
    definition["type"] = "SCALAR";
    definition["componentType"] = "FLOAT64";
    std::string values;
    for (double v : *numbers) put_f64(values, v);
    entry["values"] = binary.add_view(values, std::nullopt);
  } else if (const auto* counts = std::get_if<std::vector<std::uint32_t>>(&column.values)) {
    definition["type"] = "SCALAR";
    definition["componentType"] = "UINT32";
    std::string values;
    for (std::uint32_t v : *counts) put_u32(values, v);
    entry["values"] = binary.add_view(values, std::nullopt);
  } else {
    const auto& flags = std::get<std::vector<bool>>(column.values);
    definition["type"] = "BOOLEAN";
    // A bitstream: row i is bit (i % 8) of byte i / 8, least significant bit first.
    std::string values((flags.size() + 7) / 8, '\0');
    for (std::size_t i = 0; i < flags.size(); ++i) {
      if (flags[i]) values[i / 8] = static_cast<char>(values[i / 8] | (1 << (i % 8)));
    }
    entry["values"] = binary.add_view(values, std::nullopt);
  }
  definition["required"] = true;
  return {std::move(definition), std::move(entry)};
}

void put_chunk(std::string& out, std::uint32_t type, const std::string& data) {
  put_u32(out, static_cast<std::uint32_t>(data.size()));
  put_u32(out, type);
  out += data;
}

}  // namespace

Result<std::string> glb_bytes(const GltfMesh& mesh, const PropertyTable& table,
                              const GltfOptions& options) {
  if (Failure s = check_input(mesh, table); !s.ok()) return s;
  const std::size_t n = mesh.positions.size();

  Binary binary;
  std::string data;
  std::array<float, 3> low = mesh.positions[0], high = mesh.positions[0];
  for (const auto& p : mesh.positions) {
    for (int k = 0; k < 3; ++k) {
      put_f32(data, p[k]);
      low[k] = std::min(low[k], p[k]);
      high[k] = std::max(high[k], p[k]);
    }
  }
  const std::size_t position_view = binary.add_view(data, kTargetArrayBuffer);
  data.clear();
  for (const auto& v : mesh.normals) {
    for (float c : v) put_f32(data, c);
  }
  const std::size_t normal_view = binary.add_view(data, kTargetArrayBuffer);
  data.clear();
  for (std::uint32_t id : mesh.feature_ids) put_f32(data, static_cast<float>(id));
  const std::size_t feature_view = binary.add_view(data, kTargetArrayBuffer);
  data.clear();
  for (std::uint32_t i : mesh.indices) put_u32(data, i);
  const std::size_t index_view = binary.add_view(data, kTargetElementArrayBuffer);

  Json accessors = Json::array();
  Json position = accessor(position_view, kComponentFloat, n, "VEC3");
  // Doubles made from the stored floats: the validator compares them exactly.
  position["min"] = {static_cast<double>(low[0]), static_cast<double>(low[1]),
                     static_cast<double>(low[2])};
  position["max"] = {static_cast<double>(high[0]), static_cast<double>(high[1]),
                     static_cast<double>(high[2])};
  accessors.push_back(std::move(position));
  accessors.push_back(accessor(normal_view, kComponentFloat, n, "VEC3"));
  accessors.push_back(accessor(feature_view, kComponentFloat, n, "SCALAR"));
  accessors.push_back(accessor(index_view, kComponentUnsignedInt, mesh.indices.size(), "SCALAR"));

  Json class_properties = Json::object(), table_properties = Json::object();
  for (const PropertyColumn& column : table.columns) {
    auto [definition, entry] = add_column(column, binary);
    class_properties[column.name] = std::move(definition);
    table_properties[column.name] = std::move(entry);
  }
  pad(binary.bytes(), 4, '\0');

  Json object_class;
  if (!table.class_description.empty()) object_class["description"] = table.class_description;
  object_class["properties"] = std::move(class_properties);
  Json property_table;
  property_table["class"] = table.class_name;
  property_table["count"] = table.count;
  property_table["properties"] = std::move(table_properties);
  Json metadata;
  metadata["schema"] = {{"id", table.schema_id},
                        {"classes", {{table.class_name, std::move(object_class)}}}};
  metadata["propertyTables"] = Json::array({std::move(property_table)});

  Json primitive;
  primitive["attributes"] = {{"POSITION", 0}, {"NORMAL", 1}, {"_FEATURE_ID_0", 2}};
  primitive["indices"] = 3;
  primitive["material"] = 0;
  primitive["mode"] = kModeTriangles;
  primitive["extensions"]["EXT_mesh_features"]["featureIds"] =
      Json::array({{{"featureCount", table.count}, {"attribute", 0}, {"propertyTable", 0}}});

  Json gltf;
  gltf["asset"] = {{"version", "2.0"}, {"generator", options.generator}};
  gltf["extensionsUsed"] = {"EXT_mesh_features", "EXT_structural_metadata"};
  gltf["extensions"]["EXT_structural_metadata"] = std::move(metadata);
  gltf["scene"] = 0;
  gltf["scenes"] = Json::array({{{"nodes", {0}}}});
  gltf["nodes"] = Json::array({{{"mesh", 0}}});
  gltf["meshes"] = Json::array({{{"primitives", Json::array({std::move(primitive)})}}});
  Json pbr;
  pbr["baseColorFactor"] = options.base_color;
  pbr["metallicFactor"] = 0.0;
  pbr["roughnessFactor"] = 1.0;
  gltf["materials"] = Json::array({{{"pbrMetallicRoughness", std::move(pbr)}}});
  gltf["accessors"] = std::move(accessors);
  gltf["bufferViews"] = std::move(binary.views());
  gltf["buffers"] = Json::array({{{"byteLength", binary.bytes().size()}}});

  std::string json = gltf.dump(-1, ' ', false, Json::error_handler_t::replace);
  pad(json, 4, ' ');
  const std::size_t total = 12 + 8 + json.size() + 8 + binary.bytes().size();
  if (total > std::numeric_limits<std::uint32_t>::max()) {
    return Failure{ErrorCode::InputInvalid, "glTF: more than 4 GiB of data"};
  }
  std::string out;
  out.reserve(total);
  put_u32(out, kGlbMagic);
  put_u32(out, kGlbVersion);
  put_u32(out, static_cast<std::uint32_t>(total));
  put_chunk(out, kJsonChunkType, json);
  put_chunk(out, kBinChunkType, binary.bytes());
  return out;
}

}  // namespace csgtile::worker
