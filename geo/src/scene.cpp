#include "csgtile/geo/scene.h"

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>

namespace csgtile::geo {

using kernel::Error;
using kernel::ErrorCode;
using kernel::PrimitiveType;
using kernel::Result;
using kernel::Vec2;
using nlohmann::json;

const char* boolean_op_name(BooleanOp op) {
  switch (op) {
    case BooleanOp::None:
      return "";
    case BooleanOp::Fuse:
      return "fuse";
    case BooleanOp::Common:
      return "common";
    case BooleanOp::Cut:
      return "cut";
  }
  return "";
}

namespace {

// A primitive's "quality" object; keys absent or of another type stay at their defaults.
FitQuality quality_from(const json& q) {
  FitQuality fq;
  if (q.contains("inliers") && q["inliers"].is_number_integer())
    fq.inliers = q["inliers"].get<long long>();
  if (q.contains("rms") && q["rms"].is_number()) fq.rms = q["rms"].get<double>();
  if (q.contains("coverage") && q["coverage"].is_number())
    fq.coverage = q["coverage"].get<double>();
  if (q.contains("sigma") && q["sigma"].is_number()) fq.sigma = q["sigma"].get<double>();
  if (q.contains("within_2sigma") && q["within_2sigma"].is_number())
    fq.within_2sigma = q["within_2sigma"].get<double>();
  return fq;
}

// Reads the fields of one primitive; every failure names the primitive and the key.
class PrimitiveReader {
 public:
  PrimitiveReader(const json& j, std::size_t index) : j_(j) {
    where_ = "primitives[" + std::to_string(index) + "]";
    if (j.is_object() && j.contains("type") && j["type"].is_string()) {
      where_ += " (" + j["type"].get<std::string>();
      if (j.contains("id") && j["id"].is_string())
        where_ += " \"" + j["id"].get<std::string>() + "\"";
      where_ += ")";
    }
  }

  Error fail(const std::string& key, const std::string& what) const {
    return Error{ErrorCode::InvalidArgument, where_ + ": key \"" + key + "\" " + what};
  }

  Result<double> number(const std::string& key, bool allow_zero = false) const {
    if (!j_.contains(key)) return fail(key, "is missing");
    const json& v = j_[key];
    if (!v.is_number()) return fail(key, "must be a number");
    const double d = v.get<double>();
    if (!std::isfinite(d) || d < 0 || (d == 0 && !allow_zero)) {
      return fail(key, allow_zero ? "must be >= 0" : "must be > 0");
    }
    return d;
  }

  Result<std::vector<Vec2>> ring(const json& v, const std::string& key) const {
    if (!v.is_array()) return fail(key, "must be an array of [x, y] points");
    std::vector<Vec2> out;
    for (const json& p : v) {
      if (!p.is_array() || p.size() != 2 || !p[0].is_number() || !p[1].is_number()) {
        return fail(key, "must be an array of [x, y] points");
      }
      out.emplace_back(p[0].get<double>(), p[1].get<double>());
    }
    if (out.size() < 3) return fail(key, "needs at least 3 points");
    return out;
  }

  Result<kernel::Location> placement() const {
    if (!j_.contains("placement")) return kernel::Location();
    const json& m = j_["placement"];
    kernel::Matrix34 q;
    if (!m.is_array() || m.size() != 3)
      return fail("placement", "must be a 3x4 matrix [[...],[...],[...]]");
    for (int r = 0; r < 3; ++r) {
      const json& row = m[static_cast<std::size_t>(r)];
      if (!row.is_array() || row.size() != 4) return fail("placement", "must be a 3x4 matrix");
      for (int c = 0; c < 4; ++c) {
        const json& v = row[static_cast<std::size_t>(c)];
        if (!v.is_number()) return fail("placement", "must hold numbers only");
        q(r, c) = v.get<double>();
      }
    }
    auto loc = kernel::Location::from_matrix(q);
    if (!loc.ok()) return fail("placement", "is invalid: " + loc.error().message);
    return loc;
  }

  const std::string& where() const { return where_; }

 private:
  const json& j_;
  std::string where_;
};

Result<ScenePrimitive> read_primitive(const json& j, std::size_t index) {
  PrimitiveReader r(j, index);
  if (!j.is_object()) return Error{ErrorCode::InvalidArgument, r.where() + ": must be an object"};
  if (!j.contains("type") || !j["type"].is_string())
    return r.fail("type", "is missing or not a string");
  ScenePrimitive out;
  kernel::PrimitiveSpec& s = out.spec;
  const std::string type = j["type"].get<std::string>();
  auto take = [&](const char* key, double& field, bool allow_zero = false) -> std::optional<Error> {
    auto v = r.number(key, allow_zero);
    if (!v.ok()) return v.error();
    field = v.value();
    return std::nullopt;
  };
  std::optional<Error> err;
  if (type == "box") {
    s.type = PrimitiveType::Box;
    if (!j.contains("size") || !j["size"].is_array() || j["size"].size() != 3) {
      return r.fail("size", "must be [dx, dy, dz]");
    }
    for (int i = 0; i < 3; ++i) {
      const json& v = j["size"][static_cast<std::size_t>(i)];
      if (!v.is_number() || !(v.get<double>() > 0) || !std::isfinite(v.get<double>())) {
        return r.fail("size", "must hold three numbers > 0");
      }
      s.size[i] = v.get<double>();
    }
  } else if (type == "cylinder") {
    s.type = PrimitiveType::Cylinder;
    if ((err = take("r", s.radius)) || (err = take("h", s.height))) return *err;
  } else if (type == "cone") {
    s.type = PrimitiveType::Cone;
    if ((err = take("r1", s.radius, true)) || (err = take("r2", s.radius2, true)) ||
        (err = take("h", s.height))) {
      return *err;
    }
    if (s.radius == 0 && s.radius2 == 0) return r.fail("r1", "and r2 cannot both be 0");
  } else if (type == "sphere") {
    s.type = PrimitiveType::Sphere;
    if ((err = take("r", s.radius))) return *err;
  } else if (type == "torus") {
    s.type = PrimitiveType::Torus;
    if ((err = take("R", s.radius)) || (err = take("r", s.radius2))) return *err;
    if (!(s.radius > s.radius2)) return r.fail("R", "must be greater than r");
  } else if (type == "extrusion") {
    s.type = PrimitiveType::Extrusion;
    if (!j.contains("profile")) return r.fail("profile", "is missing");
    auto outer = r.ring(j["profile"], "profile");
    if (!outer.ok()) return outer.error();
    s.profile = outer.value();
    if (j.contains("holes")) {
      if (!j["holes"].is_array()) return r.fail("holes", "must be an array of rings");
      for (const json& h : j["holes"]) {
        auto hole = r.ring(h, "holes");
        if (!hole.ok()) return hole.error();
        s.holes.push_back(hole.value());
      }
    }
    if ((err = take("h", s.height))) return *err;
  } else if (type == "revolution") {
    s.type = PrimitiveType::Revolution;
    if (!j.contains("profile")) return r.fail("profile", "is missing");
    auto profile = r.ring(j["profile"], "profile");
    if (!profile.ok()) return profile.error();
    s.profile = profile.value();
    if (j.contains("angle")) {
      if ((err = take("angle", s.angle))) return *err;
      if (s.angle > 2 * std::numbers::pi + 1e-12) return r.fail("angle", "must be <= 2*pi");
    }
  } else {
    return r.fail("type", "\"" + type +
                              "\" is not one of box, cylinder, cone, sphere, torus, extrusion, "
                              "revolution");
  }
  if (j.contains("clip")) {
    // Half-spaces in the local frame, [nx, ny, nz, d] each: the part n·p <= d is kept.
    if (!j["clip"].is_array()) return r.fail("clip", "must be an array of [nx, ny, nz, d]");
    for (const json& c : j["clip"]) {
      bool good = c.is_array() && c.size() == 4;
      Eigen::Vector4d v = Eigen::Vector4d::Zero();
      for (std::size_t k = 0; good && k < 4; ++k) {
        good = c[k].is_number() && std::isfinite(c[k].get<double>());
        if (good) v[static_cast<Eigen::Index>(k)] = c[k].get<double>();
      }
      const double n = v.head<3>().norm();
      if (!good || !(n > 0.0)) return r.fail("clip", "must hold [nx, ny, nz, d] with n != 0");
      s.clips.push_back(std::abs(n - 1.0) > 1e-12 ? Eigen::Vector4d(v / n) : v);
    }
  }
  auto placement = r.placement();
  if (!placement.ok()) return placement.error();
  s.placement = placement.value();
  if (j.contains("id")) {
    if (!j["id"].is_string()) return r.fail("id", "must be a string");
    out.id = j["id"].get<std::string>();
  }
  if (j.contains("quality") && j["quality"].is_object()) out.quality = quality_from(j["quality"]);
  if (j.contains("building")) {
    if (!j["building"].is_string()) return r.fail("building", "must be a string");
    out.building = j["building"].get<std::string>();
  }
  if (j.contains("house")) {
    if (!j["house"].is_string()) return r.fail("house", "must be a string");
    out.house = j["house"].get<std::string>();
  }
  return out;
}

}  // namespace

Result<Scene> parse_scene(std::string_view text) {
  json j = json::parse(text.begin(), text.end(), nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded()) return Error{ErrorCode::InvalidArgument, "scene is not valid JSON"};
  if (!j.is_object()) return Error{ErrorCode::InvalidArgument, "scene must be a JSON object"};
  Scene scene;
  if (j.contains("name") && j["name"].is_string()) scene.name = j["name"].get<std::string>();
  if (j.contains("op")) {
    if (!j["op"].is_string())
      return Error{ErrorCode::InvalidArgument, "key \"op\" must be a string"};
    const std::string op = j["op"].get<std::string>();
    if (op == "fuse")
      scene.op = BooleanOp::Fuse;
    else if (op == "common")
      scene.op = BooleanOp::Common;
    else if (op == "cut")
      scene.op = BooleanOp::Cut;
    else
      return Error{ErrorCode::InvalidArgument,
                   "key \"op\": \"" + op + "\" is not fuse, common or cut"};
  }
  if (j.contains("crs") || j.contains("origin")) {
    SceneFrame frame;
    if (j.contains("crs")) {
      if (!j["crs"].is_string())
        return Error{ErrorCode::InvalidArgument, "key \"crs\" must be a string"};
      frame.crs = j["crs"].get<std::string>();
    }
    if (j.contains("origin")) {
      const json& o = j["origin"];
      if (!o.is_array() || o.size() != 3) {
        return Error{ErrorCode::InvalidArgument, "key \"origin\" must be [x, y, z]"};
      }
      for (std::size_t i = 0; i < 3; ++i) {
        if (!o[i].is_number() || !std::isfinite(o[i].get<double>())) {
          return Error{ErrorCode::InvalidArgument, "key \"origin\" must hold three finite numbers"};
        }
        frame.origin[i] = o[i].get<double>();
      }
    }
    scene.frame = frame;
  }
  if (j.contains("seed")) {
    if (!j["seed"].is_number_unsigned()) {
      return Error{ErrorCode::InvalidArgument, "key \"seed\" must be an integer >= 0"};
    }
    scene.seed = j["seed"].get<std::uint64_t>();
  }
  if (!j.contains("primitives") || !j["primitives"].is_array()) {
    return Error{ErrorCode::InvalidArgument, "key \"primitives\" is missing or not an array"};
  }
  for (std::size_t i = 0; i < j["primitives"].size(); ++i) {
    auto p = read_primitive(j["primitives"][i], i);
    if (!p.ok()) return p.error();
    scene.primitives.push_back(std::move(p).value());
  }
  if (j.contains("expected") && j["expected"].is_object()) {
    const json& e = j["expected"];
    SceneExpectation ex;
    if (e.contains("volume") && e["volume"].is_number()) ex.volume = e["volume"].get<double>();
    if (e.contains("area") && e["area"].is_number()) ex.area = e["area"].get<double>();
    if (e.contains("topology") && e["topology"].is_object()) {
      const json& t = e["topology"];
      TopologyCounts c;
      auto get = [&](const char* k, long long& f) {
        if (t.contains(k) && t[k].is_number_integer()) f = t[k].get<long long>();
      };
      get("solids", c.solids);
      get("shells", c.shells);
      get("faces", c.faces);
      get("edges", c.edges);
      get("vertices", c.vertices);
      ex.topology = c;
    }
    scene.expected = ex;
  }
  return scene;
}

namespace {

using OrderedJson = nlohmann::ordered_json;

// A primitive's "quality" object, keys in a fixed order.
OrderedJson quality_json(const FitQuality& q) {
  OrderedJson j = {{"inliers", q.inliers}, {"rms", q.rms}, {"coverage", q.coverage}};
  if (q.sigma) j["sigma"] = *q.sigma;
  if (q.within_2sigma) j["within_2sigma"] = *q.within_2sigma;
  return j;
}

// + 0.0 turns -0 into 0: the same scene prints the same bytes whichever sign a zero got.
double clean(double v) { return v + 0.0; }

OrderedJson ring_json(const std::vector<Vec2>& ring) {
  OrderedJson out = OrderedJson::array();
  for (const Vec2& p : ring) out.push_back({clean(p.x()), clean(p.y())});
  return out;
}

OrderedJson primitive_json(const ScenePrimitive& p) {
  const kernel::PrimitiveSpec& s = p.spec;
  OrderedJson j;
  j["type"] = kernel::primitive_type_name(s.type);
  if (!p.id.empty()) j["id"] = p.id;
  switch (s.type) {
    case PrimitiveType::Box:
      j["size"] = {clean(s.size.x()), clean(s.size.y()), clean(s.size.z())};
      break;
    case PrimitiveType::Cylinder:
      j["r"] = s.radius;
      j["h"] = s.height;
      break;
    case PrimitiveType::Cone:
      j["r1"] = clean(s.radius);
      j["r2"] = clean(s.radius2);
      j["h"] = s.height;
      break;
    case PrimitiveType::Sphere:
      j["r"] = s.radius;
      break;
    case PrimitiveType::Torus:
      j["R"] = s.radius;
      j["r"] = s.radius2;
      break;
    case PrimitiveType::Extrusion:
      j["profile"] = ring_json(s.profile);
      if (!s.holes.empty()) {
        OrderedJson holes = OrderedJson::array();
        for (const auto& h : s.holes) holes.push_back(ring_json(h));
        j["holes"] = std::move(holes);
      }
      j["h"] = s.height;
      break;
    case PrimitiveType::Revolution:
      j["profile"] = ring_json(s.profile);
      // The default (a full turn) is left implicit, as hand-written scenes do.
      if (s.angle < 2 * std::numbers::pi) j["angle"] = s.angle;
      break;
  }
  if (!s.clips.empty()) {
    OrderedJson clips = OrderedJson::array();
    for (const auto& c : s.clips)
      clips.push_back({clean(c.x()), clean(c.y()), clean(c.z()), c.w()});
    j["clip"] = std::move(clips);
  }
  const kernel::Matrix34 m = s.placement.matrix();
  OrderedJson rows = OrderedJson::array();
  for (int r = 0; r < 3; ++r) {
    rows.push_back({clean(m(r, 0)), clean(m(r, 1)), clean(m(r, 2)), clean(m(r, 3))});
  }
  j["placement"] = std::move(rows);
  if (p.quality) j["quality"] = quality_json(*p.quality);
  if (!p.building.empty()) j["building"] = p.building;
  if (!p.house.empty()) j["house"] = p.house;
  return j;
}

}  // namespace

std::string assembly_group(const ScenePrimitive& p, std::string_view scope) {
  if (!p.building.empty()) return "footprint " + p.building;
  if (!p.house.empty()) return "house " + std::string(scope) + "/" + p.house;
  return {};
}

std::string scene_to_json(const Scene& scene) {
  // Top-level keys one per line and one primitive per line: diffable, still compact.
  std::string out = "{\"name\": " + OrderedJson(scene.name).dump();
  if (scene.op != BooleanOp::None) {
    out += ",\n \"op\": " + OrderedJson(boolean_op_name(scene.op)).dump();
  }
  if (scene.frame) {
    out += ",\n \"crs\": " + OrderedJson(scene.frame->crs).dump();
    const auto& o = scene.frame->origin;
    out += ",\n \"origin\": " + OrderedJson{clean(o[0]), clean(o[1]), clean(o[2])}.dump();
  }
  if (scene.seed) out += ",\n \"seed\": " + std::to_string(*scene.seed);
  out += ",\n \"primitives\": [";
  for (std::size_t i = 0; i < scene.primitives.size(); ++i) {
    out += (i == 0 ? "\n  " : ",\n  ") + primitive_json(scene.primitives[i]).dump();
  }
  out += scene.primitives.empty() ? "]" : "\n ]";
  if (scene.expected) {
    OrderedJson e = OrderedJson::object();
    if (scene.expected->volume) e["volume"] = *scene.expected->volume;
    if (scene.expected->area) e["area"] = *scene.expected->area;
    if (scene.expected->topology) {
      const TopologyCounts& t = *scene.expected->topology;
      OrderedJson counts = OrderedJson::object();
      auto put = [&](const char* key, long long v) {
        if (v >= 0) counts[key] = v;
      };
      put("solids", t.solids);
      put("shells", t.shells);
      put("faces", t.faces);
      put("edges", t.edges);
      put("vertices", t.vertices);
      e["topology"] = std::move(counts);
    }
    out += ",\n \"expected\": " + e.dump();
  }
  out += "}\n";
  return out;
}

Result<Scene> read_scene(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error{ErrorCode::IoError, "cannot read scene file " + path.string()};
  std::ostringstream buf;
  buf << in.rdbuf();
  auto scene = parse_scene(buf.str());
  if (!scene.ok()) return Error{scene.error().code, path.string() + ": " + scene.error().message};
  return scene;
}

std::string fit_quality_to_json(const FitQuality& quality) { return quality_json(quality).dump(); }

kernel::Result<FitQuality> parse_fit_quality(std::string_view text) {
  const json q = json::parse(text, nullptr, false);
  if (q.is_discarded() || !q.is_object()) {
    return kernel::Error{kernel::ErrorCode::InvalidArgument, "fit quality: not a JSON object"};
  }
  return quality_from(q);
}

}  // namespace csgtile::geo
