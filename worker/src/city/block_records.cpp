// Blocks of a cell's buildings kept in its object records (block_records.h).

#include "city/block_records.h"

#include <string>

#include "csgtile/kernel/native_format.h"
#include "csgtile/worker/publish.h"

namespace csgtile::worker::city::detail {

namespace {

Failure read_model(const std::filesystem::path& run_dir, const ordered_json& key,
                   const kernel::Location& by, std::optional<kernel::CsgModel>& out) {
  out.reset();
  if (key.is_null()) return {};
  if (!key.is_string() || !is_safe_key(key.get<std::string>())) {
    return {ErrorCode::Internal, "a block's key in an object record is not a safe key"};
  }
  const std::filesystem::path path = run_dir / key.get<std::string>();
  auto model = kernel::read_native_model_file(path);
  if (!model.ok()) {
    return failure_of(model.error(), path.string());
  }
  out = std::move(model).value();
  if (!by.is_identity()) move_model(*out, by);
  return {};
}

}  // namespace

Failure publish_blocks(const IndexObject& object, ObjectBatch& batch, ordered_json& record) {
  record = ordered_json::object();
  if (const auto& h = object.heights) {
    record["heights"] = {{"ground", h->ground},        {"roof_min", h->roof_min},
                         {"roof_50p", h->roof_50p},    {"roof_70p", h->roof_70p},
                         {"roof_max", h->roof_max},    {"roof_area", h->roof_area},
                         {"roof_faces", h->roof_faces}};
  } else {
    record["heights"] = nullptr;
  }
  // Each block published as the objects are (content-addressed), named by its key.
  auto block = [&](const std::optional<kernel::CsgModel>& model, ordered_json& key) -> Failure {
    key = nullptr;
    if (!model) return {};
    PublishedModel published;
    if (Failure f = publish_model(*model, batch, published); !f.ok()) return f;
    key = published.key;
    return {};
  };
  if (Failure f = block(object.lod12, record["lod12"]); !f.ok()) return f;
  record["lod12_error"] = object.lod12_error;
  if (Failure f = block(object.lod13, record["lod13"]); !f.ok()) return f;
  record["lod13_error"] = object.lod13_error;
  return {};
}

std::vector<std::string> block_keys(const ordered_json& entry) {
  std::vector<std::string> keys;
  if (!entry.contains("blocks")) return keys;
  for (const char* lod : {"lod12", "lod13"}) {
    const ordered_json& key = entry.at("blocks").at(lod);
    if (key.is_string()) keys.push_back(key.get<std::string>());
  }
  return keys;
}

Failure read_blocks(const std::filesystem::path& run_dir, const ordered_json& entry,
                    const kernel::Location& by, IndexObject& object, bool& found) {
  found = false;
  if (!entry.contains("blocks")) return {};
  const ordered_json& b = entry.at("blocks");
  try {
    std::optional<assembly::BuildingHeights> heights;
    if (const ordered_json& h = b.at("heights"); !h.is_null()) {
      assembly::BuildingHeights v;
      v.ground = h.at("ground").get<double>();
      v.roof_min = h.at("roof_min").get<double>();
      v.roof_50p = h.at("roof_50p").get<double>();
      v.roof_70p = h.at("roof_70p").get<double>();
      v.roof_max = h.at("roof_max").get<double>();
      v.roof_area = h.at("roof_area").get<double>();
      v.roof_faces = h.at("roof_faces").get<std::size_t>();
      heights = v;
    }
    std::optional<kernel::CsgModel> lod12, lod13;
    if (Failure f = read_model(run_dir, b.at("lod12"), by, lod12); !f.ok()) return f;
    if (Failure f = read_model(run_dir, b.at("lod13"), by, lod13); !f.ok()) return f;
    object.heights = heights;
    object.lod12 = std::move(lod12);
    object.lod12_error = b.at("lod12_error").get<std::string>();
    object.lod13 = std::move(lod13);
    object.lod13_error = b.at("lod13_error").get<std::string>();
  } catch (const nlohmann::json::exception& e) {
    return {ErrorCode::Internal, std::string("an object record's blocks: ") + e.what()};
  }
  found = true;
  return {};
}

}  // namespace csgtile::worker::city::detail
