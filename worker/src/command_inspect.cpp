// `csgtile inspect FILE [--json]`: a summary of any file csgtile publishes, recognised by
// its content: native model (.csgt: topology counts, CSG tree, volume, validity), topology
// index (GeoPackage: tables and row counts, objects layer and SRS, index metadata),
// CityJSONSeq (header, features, object types, vertices), glTF binary (chunks, meshes,
// accessors, extensions, feature count), tileset.json, run manifest, scene JSON.

#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "commands.h"
#include "csgtile/geo/scene.h"
#include "csgtile/kernel/check.h"
#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/mass_properties.h"
#include "csgtile/kernel/native_format.h"
#include "csgtile/worker/errors.h"
#include "export/sqlite_util.h"

namespace csgtile::worker::detail {

namespace {

using Json = nlohmann::ordered_json;

Failure read_all(const std::string& path, std::string& bytes) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return {ErrorCode::Io, "cannot read " + path};
  std::ostringstream s;
  s << in.rdbuf();
  bytes = s.str();
  return {};
}

Failure inspect_native(const std::string& path, const std::string& bytes, Json& out) {
  auto model = kernel::read_native_model(bytes);
  if (!model.ok()) return failure_of(model.error(), path);
  const auto counts = kernel::count_shapes(model->shape);
  const auto mp = kernel::mass_properties(model->shape);
  const auto check = kernel::check_shape(model->shape);
  out["type"] = "native_model";
  Json topology;
  for (int k = 0; k < kernel::kShapeKindCount; ++k) {
    topology[kernel::shape_kind_name(static_cast<kernel::ShapeKind>(k))] =
        counts[static_cast<std::size_t>(k)];
  }
  out["topology"] = topology;
  out["volume"] = mp.volume;
  out["area"] = mp.area;
  out["valid"] = check.valid();
  if (!check.valid()) out["first_issue"] = check.issues.front().message;
  std::map<std::string, int> kinds, primitives;
  for (const auto& node : model->nodes) {
    ++kinds[kernel::csg_node_kind_name(node.kind)];
    if (node.kind == kernel::CsgNodeKind::Primitive)
      ++primitives[kernel::primitive_type_name(node.primitive.type)];
  }
  out["csg"] = {{"nodes", model->nodes.size()}, {"by_kind", kinds}, {"primitives", primitives}};
  return {};
}

Failure inspect_gpkg(const std::string& path, Json& out) {
  SqliteDb db;
  if (Failure f = db.open(path, SQLITE_OPEN_READONLY); !f.ok()) return f;
  out["type"] = "geopackage";
  Json tables = Json::object();
  std::vector<std::string> names;
  {
    SqliteStatement st(
        db,
        "SELECT name FROM sqlite_master WHERE type = 'table' AND name NOT LIKE 'sqlite_%' "
        "AND name NOT LIKE 'rtree_%' ORDER BY name");
    if (!st.ok()) return {ErrorCode::InputInvalid, path + ": not a readable SQLite file"};
    while (st.step() == SQLITE_ROW) names.push_back(st.text(0));
  }
  for (const std::string& name : names) {
    SqliteStatement st(db, "SELECT count(*) FROM \"" + name + "\"");
    if (st.ok() && st.step() == SQLITE_ROW) tables[name] = st.integer(0);
  }
  out["tables"] = tables;
  {
    SqliteStatement st(
        db, "SELECT table_name, data_type, srs_id FROM gpkg_contents ORDER BY table_name");
    if (!st.ok())
      return {ErrorCode::InputInvalid, path + ": SQLite but not a GeoPackage (no gpkg_contents)"};
    Json contents = Json::array();
    while (st.step() == SQLITE_ROW) {
      contents.push_back(
          {{"table", st.text(0)}, {"data_type", st.text(1)}, {"srs_id", st.integer(2)}});
    }
    out["contents"] = contents;
  }
  SqliteStatement meta(db, "SELECT key, value FROM index_metadata ORDER BY key");
  if (meta.ok()) {
    Json m;
    while (meta.step() == SQLITE_ROW) m[meta.text(0)] = meta.text(1);
    out["index_metadata"] = m;
  }
  return {};
}

Failure inspect_cityjson_seq(const std::string& path, const std::string& bytes, Json& out) {
  std::istringstream in(bytes);
  std::string line;
  long long features = 0, vertices = 0, line_no = 0;
  std::map<std::string, long long> types;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty()) continue;
    Json j = Json::parse(line, nullptr, false);
    if (j.is_discarded())
      return {ErrorCode::InputInvalid, path + ":" + std::to_string(line_no) + ": not JSON"};
    if (line_no == 1) {
      out["type"] = "cityjson_seq";
      out["version"] = j.value("version", "");
      if (j.contains("transform")) out["transform"] = j["transform"];
      if (j.contains("metadata")) out["metadata"] = j["metadata"];
      continue;
    }
    if (j.value("type", "") != "CityJSONFeature") {
      return {ErrorCode::InputInvalid,
              path + ":" + std::to_string(line_no) + ": not a CityJSONFeature"};
    }
    ++features;
    if (j.contains("vertices")) vertices += static_cast<long long>(j["vertices"].size());
    if (j.contains("CityObjects")) {
      for (const auto& [id, object] : j["CityObjects"].items()) ++types[object.value("type", "?")];
    }
  }
  out["features"] = features;
  out["city_objects"] = types;
  out["vertices"] = vertices;
  return {};
}

std::uint32_t le32(const std::string& b, std::size_t at) {
  std::uint32_t v = 0;
  std::memcpy(&v, b.data() + at, 4);
  return v;  // little-endian hosts only (x86-64, aarch64)
}

Failure inspect_glb(const std::string& path, const std::string& bytes, Json& out) {
  if (bytes.size() < 20) return {ErrorCode::InputInvalid, path + ": truncated glTF binary"};
  const std::uint32_t version = le32(bytes, 4), length = le32(bytes, 8);
  const std::uint32_t json_length = le32(bytes, 12), json_type = le32(bytes, 16);
  if (length != bytes.size() || json_type != 0x4E4F534Au || 20 + json_length > bytes.size()) {
    return {ErrorCode::InputInvalid, path + ": malformed glTF binary (lengths or chunk type)"};
  }
  Json j = Json::parse(bytes.substr(20, json_length), nullptr, false);
  if (j.is_discarded()) return {ErrorCode::InputInvalid, path + ": glTF JSON chunk does not parse"};
  out["type"] = "gltf_binary";
  out["version"] = version;
  out["bytes"] = length;
  out["meshes"] = j.contains("meshes") ? j["meshes"].size() : 0;
  out["accessors"] = j.contains("accessors") ? j["accessors"].size() : 0;
  out["extensions_used"] = j.value("extensionsUsed", Json::array());
  std::size_t bin = 20 + json_length;
  out["bin_chunk_bytes"] = bin + 8 <= bytes.size() ? le32(bytes, bin) : 0;
  return {};
}

Failure inspect(const std::string& path, Json& out) {
  std::string bytes;
  if (Failure f = read_all(path, bytes); !f.ok()) return f;
  out["file"] = path;
  out["bytes"] = bytes.size();
  if (bytes.rfind("SQLite format 3", 0) == 0) return inspect_gpkg(path, out);
  if (bytes.rfind("glTF", 0) == 0) return inspect_glb(path, bytes, out);
  auto native = kernel::read_native_model(bytes);
  if (native.ok() || bytes.rfind("CSGT", 0) == 0) return inspect_native(path, bytes, out);
  const std::size_t eol = bytes.find('\n');
  if (eol != std::string::npos && eol + 1 < bytes.size() && bytes.find("\"CityJSON\"") < eol) {
    return inspect_cityjson_seq(path, bytes, out);
  }
  Json j = Json::parse(bytes, nullptr, false);
  if (j.is_discarded())
    return {ErrorCode::InputInvalid, path + ": not a file csgtile publishes or reads"};
  if (j.contains("asset") && j.contains("root")) {
    out["type"] = "tileset";
    out["asset"] = j["asset"];
    out["geometric_error"] = j.value("geometricError", 0.0);
    if (j["root"].contains("boundingVolume")) out["bounding_volume"] = j["root"]["boundingVolume"];
    return {};
  }
  if (j.contains("run") && j.contains("jobs")) {
    out["type"] = "run_manifest";
    out["run"] = j["run"];
    out["jobs"] = j["jobs"].size();
    out["dead"] = j.value("dead", Json::array()).size();
    for (const char* key : {"index", "cityjson", "tiles"}) {
      if (j.contains(key)) out[key] = j[key];
    }
    return {};
  }
  if (j.contains("primitives")) {
    auto scene = geo::parse_scene(bytes);
    if (!scene.ok()) return {ErrorCode::InputInvalid, path + ": " + scene.error().message};
    std::map<std::string, int> types;
    for (const auto& p : scene->primitives) ++types[kernel::primitive_type_name(p.spec.type)];
    out["type"] = "scene";
    out["name"] = scene->name;
    out["op"] = geo::boolean_op_name(scene->op);
    out["primitives"] = types;
    return {};
  }
  return {ErrorCode::InputInvalid, path + ": JSON, but not a file csgtile publishes or reads"};
}

void print_text(const Json& j, const std::string& indent = "") {
  for (const auto& [key, value] : j.items()) {
    if (value.is_object()) {
      std::printf("%s%s:\n", indent.c_str(), key.c_str());
      print_text(value, indent + "  ");
    } else {
      std::printf("%s%s: %s\n", indent.c_str(), key.c_str(),
                  value.is_string() ? value.get<std::string>().c_str() : value.dump().c_str());
    }
  }
}

}  // namespace

void register_inspect(CLI::App& app, Action& action) {
  auto* cmd =
      app.add_subcommand("inspect",
                         "Summarise a file csgtile publishes (native model, GeoPackage index, "
                         "CityJSONSeq, glTF binary, tileset, manifest, scene)");
  auto file = std::make_shared<std::string>();
  auto json = std::make_shared<bool>(false);
  cmd->add_option("FILE", *file, "File to inspect")->required();
  cmd->add_flag("--json", *json, "Print one JSON object");
  cmd->callback([&action, file, json] {
    action = [file, json] {
      Json out;
      const Failure f = inspect(*file, out);
      if (!f.ok()) {
        if (*json)
          std::cout << Json{{"file", *file},
                            {"error", std::string(error_info(f.code).name) + ": " + f.message}}
                           .dump()
                    << "\n";
        std::fprintf(stderr, "csgtile inspect: %s\n", f.message.c_str());
        return error_info(f.code).exit_code;
      }
      if (*json) {
        std::cout << out.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) << "\n";
      } else {
        print_text(out);
      }
      return 0;
    };
  });
}

}  // namespace csgtile::worker::detail
