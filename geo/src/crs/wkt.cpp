// OGC WKT 1 and WKT 2 → Crs (a small tolerant parser), and Crs → WKT 1.
//
// The parser builds a tree of nodes KEYWORD[item, ...] where an item is a quoted string, a
// number, a bare word (EAST, ellipsoidal) or a nested node; '(' and ')' are accepted for
// brackets, keywords in any case. Interpretation then walks the tree by keyword, accepting the
// WKT 1 (OGC 01-009, GDAL, ESRI) and WKT 2 (ISO 19162:2015/2019) spellings of the same things.
// Limits (length, depth, node count) keep hostile text from exhausting memory or the stack.

#include <cmath>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "crs/crs_internal.h"

namespace csgtile::geo {
namespace {

using kernel::Error;
using kernel::ErrorCode;
using kernel::Result;

constexpr std::size_t kMaxWktLength = 1 << 20;
constexpr int kMaxDepth = 32;
constexpr std::size_t kMaxNodes = 20000;

struct WktNode;

struct WktItem {
  enum class Kind { Text, Number, Word, Node };
  Kind kind = Kind::Text;
  std::string text;
  double number = 0.0;
  std::unique_ptr<WktNode> node;
};

struct WktNode {
  std::string keyword;  // upper case
  std::vector<WktItem> items;

  const WktNode* child(std::initializer_list<const char*> keywords) const {
    for (const WktItem& item : items) {
      if (item.kind != WktItem::Kind::Node) continue;
      for (const char* k : keywords) {
        if (item.node->keyword == k) return item.node.get();
      }
    }
    return nullptr;
  }
  std::vector<const WktNode*> children(std::initializer_list<const char*> keywords) const {
    std::vector<const WktNode*> out;
    for (const WktItem& item : items) {
      if (item.kind != WktItem::Kind::Node) continue;
      for (const char* k : keywords) {
        if (item.node->keyword == k) out.push_back(item.node.get());
      }
    }
    return out;
  }
  std::string name() const {
    for (const WktItem& item : items) {
      if (item.kind == WktItem::Kind::Text) return item.text;
    }
    return {};
  }
  std::vector<double> numbers() const {
    std::vector<double> out;
    for (const WktItem& item : items) {
      if (item.kind == WktItem::Kind::Number) out.push_back(item.number);
    }
    return out;
  }
  std::optional<double> number(std::size_t index) const {
    auto n = numbers();
    return index < n.size() ? std::optional<double>(n[index]) : std::nullopt;
  }
  const WktItem* item(std::size_t index) const {
    return index < items.size() ? &items[index] : nullptr;
  }
};

class Parser {
 public:
  explicit Parser(std::string_view text) : s_(text) {}

  Result<std::unique_ptr<WktNode>> parse() {
    skip_space();
    auto node = parse_node(0);
    if (!node.ok()) return node;
    skip_space();
    while (pos_ < s_.size() && (s_[pos_] == '\0' || s_[pos_] == ';')) ++pos_;
    skip_space();
    if (pos_ < s_.size()) trailing_ = true;
    return node;
  }
  bool trailing() const { return trailing_; }

 private:
  Error error(const std::string& what) const {
    return Error{ErrorCode::InvalidArgument,
                 "WKT syntax error at offset " + std::to_string(pos_) + ": " + what};
  }

  void skip_space() {
    while (pos_ < s_.size() &&
           (s_[pos_] == ' ' || s_[pos_] == '\t' || s_[pos_] == '\n' || s_[pos_] == '\r'))
      ++pos_;
  }

  static bool is_word_char(char c) {
    return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
  }

  std::string read_word() {
    const std::size_t start = pos_;
    while (pos_ < s_.size() && is_word_char(s_[pos_])) ++pos_;
    return std::string(s_.substr(start, pos_ - start));
  }

  Result<std::unique_ptr<WktNode>> parse_node(int depth) {
    if (depth > kMaxDepth) return error("nesting deeper than " + std::to_string(kMaxDepth));
    if (++nodes_ > kMaxNodes) return error("more than " + std::to_string(kMaxNodes) + " nodes");
    std::string keyword = read_word();
    if (keyword.empty()) return error("expected a keyword");
    for (char& c : keyword) {
      if (c >= 'a' && c <= 'z') c = static_cast<char>(c - 'a' + 'A');
    }
    skip_space();
    if (pos_ >= s_.size() || (s_[pos_] != '[' && s_[pos_] != '('))
      return error("expected '[' after " + keyword);
    const char close = s_[pos_] == '[' ? ']' : ')';
    ++pos_;
    auto node = std::make_unique<WktNode>();
    node->keyword = std::move(keyword);
    skip_space();
    if (pos_ < s_.size() && s_[pos_] == close) {
      ++pos_;
      return node;
    }
    while (true) {
      skip_space();
      if (pos_ >= s_.size()) return error("unexpected end inside " + node->keyword);
      WktItem item;
      const char c = s_[pos_];
      if (c == '"') {
        item.kind = WktItem::Kind::Text;
        ++pos_;
        while (true) {
          if (pos_ >= s_.size()) return error("unterminated string");
          if (s_[pos_] == '"') {
            if (pos_ + 1 < s_.size() && s_[pos_ + 1] == '"') {  // WKT 2 doubled quote
              item.text.push_back('"');
              pos_ += 2;
              continue;
            }
            ++pos_;
            break;
          }
          item.text.push_back(s_[pos_++]);
        }
      } else if (c == '-' || c == '+' || c == '.' || (c >= '0' && c <= '9')) {
        const std::size_t start = pos_;
        while (pos_ < s_.size() &&
               (s_[pos_] == '-' || s_[pos_] == '+' || s_[pos_] == '.' || s_[pos_] == 'e' ||
                s_[pos_] == 'E' || (s_[pos_] >= '0' && s_[pos_] <= '9'))) {
          ++pos_;
        }
        const std::string spelled(s_.substr(start, pos_ - start));
        char* end = nullptr;
        item.kind = WktItem::Kind::Number;
        item.text = spelled;
        item.number = std::strtod(spelled.c_str(), &end);
        if (end != spelled.c_str() + spelled.size() || !std::isfinite(item.number)) {
          return error("bad number '" + spelled + "'");
        }
      } else if (is_word_char(c)) {
        const std::size_t start = pos_;
        std::string word = read_word();
        const std::size_t after = pos_;
        skip_space();
        if (pos_ < s_.size() && (s_[pos_] == '[' || s_[pos_] == '(')) {
          pos_ = start;
          auto child = parse_node(depth + 1);
          if (!child.ok()) return child.error();
          item.kind = WktItem::Kind::Node;
          item.node = std::move(child).value();
        } else {
          pos_ = after;
          item.kind = WktItem::Kind::Word;
          item.text = std::move(word);
        }
      } else {
        return error(std::string("unexpected character '") + c + "' in " + node->keyword);
      }
      node->items.push_back(std::move(item));
      skip_space();
      if (pos_ >= s_.size()) return error("unexpected end inside " + node->keyword);
      if (s_[pos_] == ',') {
        ++pos_;
        continue;
      }
      if (s_[pos_] == close) {
        ++pos_;
        return node;
      }
      return error(std::string("expected ',' or '") + close + "' in " + node->keyword);
    }
  }

  std::string_view s_;
  std::size_t pos_ = 0;
  std::size_t nodes_ = 0;
  bool trailing_ = false;
};

// ---- interpretation ----------------------------------------------------------------------

Error unsupported(std::string message) { return Error{ErrorCode::Unsupported, std::move(message)}; }
Error invalid(std::string message) { return Error{ErrorCode::InvalidArgument, std::move(message)}; }

/// EPSG code of AUTHORITY["EPSG","4326"] or ID["EPSG",4326] (0 when absent or another authority).
int epsg_code(const WktNode& node) {
  const WktNode* id = node.child({"AUTHORITY", "ID"});
  if (!id || id->items.size() < 2) return 0;
  if (detail::normalise_name(id->name()) != "epsg") return 0;
  const WktItem& code = id->items[1];
  if (code.kind == WktItem::Kind::Number) {
    return code.number >= 0 && code.number < 1e9 ? static_cast<int>(code.number) : 0;
  }
  if (code.kind == WktItem::Kind::Text) return std::atoi(code.text.c_str());
  return 0;
}

struct Context {
  std::vector<std::string> warnings;
};

/// A UNIT / LENGTHUNIT node as a linear unit. A known non-metre name with factor 1 (a bug of
/// some writers: UNIT["US survey foot",1.0]) is read by its name, with a warning.
LinearUnit linear_unit_of(const WktNode& unit, Context& ctx) {
  const std::string name = unit.name();
  const double factor = unit.number(0).value_or(1.0);
  const auto by_name = detail::linear_unit_from_name(name);
  if (by_name && factor == 1.0 && by_name->metres != 1.0) {
    ctx.warnings.push_back("WKT unit '" + name + "' has conversion factor 1: read as " +
                           by_name->name + " (" + detail::format_number(by_name->metres) + " m)");
    return *by_name;
  }
  if (int code = epsg_code(unit)) {
    if (auto known = detail::linear_unit_from_epsg(code);
        known && std::fabs(known->metres - factor) <= 1e-12 * factor) {
      return *known;
    }
  }
  return detail::linear_unit_from_size(name, factor);
}

AngularUnit angular_unit_of(const WktNode& unit) {
  return detail::angular_unit_from_size(unit.name(), unit.number(0).value_or(detail::kDegree));
}

/// The unit node of a CRS: a direct UNIT/…UNIT child, or one inside its CS axes (WKT 2).
const WktNode* crs_unit_node(const WktNode& crs, std::initializer_list<const char*> keywords) {
  if (const WktNode* u = crs.child(keywords)) return u;
  for (const WktNode* axis : crs.children({"AXIS"})) {
    if (const WktNode* u = axis->child(keywords)) return u;
  }
  return nullptr;
}

Result<Ellipsoid> ellipsoid_of(const WktNode& node, Context& ctx) {
  const auto n = node.numbers();
  if (n.size() < 2)
    return invalid("WKT " + node.keyword + "[\"" + node.name() +
                   "\"] needs a semi-major axis and an inverse flattening");
  Ellipsoid e;
  e.name = node.name();
  e.epsg = epsg_code(node);
  double unit = 1.0;
  if (const WktNode* u = node.child({"LENGTHUNIT", "UNIT"})) unit = linear_unit_of(*u, ctx).metres;
  e.semi_major_m = n[0] * unit;
  e.inverse_flattening = n[1];
  return e;
}

/// The datum of a geographic CRS node (GEOGCS, GEOGCRS, BASEGEOGCRS, ...), with its prime
/// meridian and relation to WGS 84.
Result<GeodeticDatum> datum_of(const WktNode& geog, const AngularUnit& angle, Context& ctx) {
  const WktNode* datum = geog.child({"DATUM", "GEODETICDATUM", "TRF", "ENSEMBLE"});
  if (!datum) return invalid("WKT " + geog.keyword + "[\"" + geog.name() + "\"] has no DATUM");
  const WktNode* ell = datum->child({"SPHEROID", "ELLIPSOID"});
  if (!ell) ell = geog.child({"SPHEROID", "ELLIPSOID"});
  if (!ell) return invalid("WKT DATUM[\"" + datum->name() + "\"] has no SPHEROID/ELLIPSOID");
  auto ellipsoid = ellipsoid_of(*ell, ctx);
  if (!ellipsoid.ok()) return ellipsoid.error();

  GeodeticDatum d;
  const int code = epsg_code(*datum);
  std::optional<GeodeticDatum> known = code ? detail::datum_from_epsg(code) : std::nullopt;
  if (!known) known = detail::datum_from_name(datum->name());
  if (known && std::fabs(known->ellipsoid.semi_major_m - ellipsoid.value().semi_major_m) > 1e-3) {
    ctx.warnings.push_back(
        "WKT datum '" + datum->name() + "' is named like " + known->name +
        " but its ellipsoid differs: its relation to WGS 84 is not taken from the table");
    known.reset();
  }
  if (known) {
    d = *known;
    d.name = datum->name().empty() ? known->name : datum->name();
  } else {
    d.name = datum->name();
    d.epsg = code;
    const Ellipsoid& e = ellipsoid.value();
    if (e.semi_major_m == 6378137.0 && std::fabs(e.inverse_flattening - 298.2572) < 1e-3) {
      d.to_wgs84 = Helmert7{};
      d.to_wgs84_source = "assumed null (datum on a WGS 84/GRS 80 ellipsoid)";
      if (!datum->child({"TOWGS84"})) {
        ctx.warnings.push_back("WKT datum '" + d.name + "' is not known: assumed equal to WGS 84");
      }
    } else {
      d.to_wgs84 = std::nullopt;
      d.to_wgs84_source = "unknown";
      if (!datum->child({"TOWGS84"})) {
        ctx.warnings.push_back(
            "WKT datum '" + d.name +
            "' is not known and has no TOWGS84: it cannot be placed on the globe");
      }
    }
  }
  d.ellipsoid = ellipsoid.value();
  if (const WktNode* t = datum->child({"TOWGS84"})) {
    const auto v = t->numbers();
    if (v.size() != 3 && v.size() != 7) {
      return invalid("WKT TOWGS84 needs 3 or 7 numbers, has " + std::to_string(v.size()));
    }
    auto at = [&](std::size_t i) { return i < v.size() ? v[i] : 0.0; };
    d.to_wgs84 =
        detail::helmert_from_position_vector(at(0), at(1), at(2), at(3), at(4), at(5), at(6));
    d.to_wgs84_source = "WKT TOWGS84";
  }
  if (const WktNode* pm = geog.child({"PRIMEM", "PRIMEMERIDIAN"})) {
    double radians = angle.radians;
    if (const WktNode* u = pm->child({"ANGLEUNIT", "UNIT"})) radians = angular_unit_of(*u).radians;
    d.prime_meridian_deg = pm->number(0).value_or(0.0) * radians / detail::kDegree;
  }
  return d;
}

Result<Crs> geographic_of(const WktNode& geog, Context& ctx) {
  if (const WktNode* cs = geog.child({"CS"})) {
    const WktItem* type = cs->item(0);
    if (type && detail::normalise_name(type->text) == "cartesian") {
      return unsupported("WKT " + geog.keyword + "[\"" + geog.name() +
                         "\"] is geocentric (Cartesian CS): not supported");
    }
  }
  Crs crs;
  crs.kind = CrsKind::Geographic;
  crs.name = geog.name();
  crs.epsg = epsg_code(geog);
  crs.source = "WKT";
  crs.angular_unit = degree_unit();
  if (const WktNode* u = crs_unit_node(geog, {"ANGLEUNIT", "UNIT"}))
    crs.angular_unit = angular_unit_of(*u);
  auto datum = datum_of(geog, crs.angular_unit, ctx);
  if (!datum.ok()) return datum.error();
  crs.datum = datum.value();
  return crs;
}

enum class Role {
  Latitude,
  Longitude,
  StandardParallel1,
  StandardParallel2,
  Scale,
  Easting,
  Northing,
  Unknown
};

Role role_of_parameter(const WktNode& parameter) {
  switch (epsg_code(parameter)) {
    case 8801:
    case 8821:
      return Role::Latitude;
    case 8802:
    case 8822:
    case 8833:
      return Role::Longitude;
    case 8805:
      return Role::Scale;
    case 8806:
    case 8826:
      return Role::Easting;
    case 8807:
    case 8827:
      return Role::Northing;
    case 8823:
    case 8832:
      return Role::StandardParallel1;
    case 8824:
      return Role::StandardParallel2;
    default:
      break;
  }
  const std::string n = detail::normalise_name(parameter.name());
  if (n == "latitudeoforigin" || n == "latitudeofnaturalorigin" || n == "latitudeoffalseorigin" ||
      n == "latitudeofcenter" || n == "latitudeofcentre" || n == "latitudeofprojectioncentre") {
    return Role::Latitude;
  }
  if (n == "centralmeridian" || n == "longitudeofnaturalorigin" || n == "longitudeoffalseorigin" ||
      n == "longitudeoforigin" || n == "longitudeofcenter" || n == "longitudeofcentre" ||
      n == "straightverticallongitudefrompole") {
    return Role::Longitude;
  }
  if (n == "scalefactor" || n == "scalefactoratnaturalorigin" || n == "scalefactoratorigin")
    return Role::Scale;
  if (n == "falseeasting" || n == "eastingatfalseorigin") return Role::Easting;
  if (n == "falsenorthing" || n == "northingatfalseorigin") return Role::Northing;
  if (n == "standardparallel1" || n == "latitudeof1ststandardparallel" ||
      n == "latitudeofstandardparallel" || n == "standardparallel" || n == "latitudeoftruescale") {
    return Role::StandardParallel1;
  }
  if (n == "standardparallel2" || n == "latitudeof2ndstandardparallel")
    return Role::StandardParallel2;
  return Role::Unknown;
}

enum class MethodGuess {
  TM,
  LCC1,
  LCC2,
  LCCAmbiguous,
  PolarGdal,
  PolarA,
  PolarB,
  PolarNorthEsri,
  PolarSouthEsri,
  Oblique,
  Unknown
};

MethodGuess method_of(const WktNode& method_node) {
  switch (epsg_code(method_node)) {
    case 9807:
      return MethodGuess::TM;
    case 9801:
      return MethodGuess::LCC1;
    case 9802:
      return MethodGuess::LCC2;
    case 9810:
      return MethodGuess::PolarA;
    case 9829:
      return MethodGuess::PolarB;
    case 9809:
      return MethodGuess::Oblique;
    default:
      break;
  }
  const std::string n = detail::normalise_name(method_node.name());
  if (n.find("southorient") != std::string::npos || n.find("belgium") != std::string::npos ||
      n.find("variantc") != std::string::npos || n.find("michigan") != std::string::npos) {
    return MethodGuess::Unknown;
  }
  if (n == "transversemercator" || n == "gausskruger" || n == "transversemercatorgausskruger")
    return MethodGuess::TM;
  if (n == "lambertconformalconic1sp" || n == "lambertconicconformal1sp") return MethodGuess::LCC1;
  if (n == "lambertconformalconic2sp" || n == "lambertconicconformal2sp") return MethodGuess::LCC2;
  if (n == "lambertconformalconic" || n == "lambertconicconformal")
    return MethodGuess::LCCAmbiguous;
  if (n == "polarstereographic") return MethodGuess::PolarGdal;
  if (n == "polarstereographicvarianta") return MethodGuess::PolarA;
  if (n == "polarstereographicvariantb") return MethodGuess::PolarB;
  if (n == "stereographicnorthpole") return MethodGuess::PolarNorthEsri;
  if (n == "stereographicsouthpole") return MethodGuess::PolarSouthEsri;
  if (n == "obliquestereographic" || n == "doublestereographic") return MethodGuess::Oblique;
  return MethodGuess::Unknown;
}

/// The projection of a PROJCS (WKT 1) or PROJCRS (WKT 2) node.
Result<Projection> projection_of(const WktNode& projcs, const WktNode* conversion,
                                 const AngularUnit& angle, const LinearUnit& length, Context& ctx) {
  const WktNode* method_node = conversion ? conversion->child({"METHOD", "PROJECTION"})
                                          : projcs.child({"PROJECTION", "METHOD"});
  if (!method_node)
    return invalid("WKT " + projcs.keyword + "[\"" + projcs.name() +
                   "\"] has no PROJECTION/METHOD");
  const WktNode& holder = conversion ? *conversion : projcs;

  struct Value {
    bool present = false;
    double value = 0.0;
  };
  Value lat, lon, sp1, sp2, scale, easting, northing;
  for (const WktNode* parameter : holder.children({"PARAMETER"})) {
    auto raw = parameter->number(0);
    if (!raw) return invalid("WKT PARAMETER[\"" + parameter->name() + "\"] has no value");
    const Role role = role_of_parameter(*parameter);
    double value = *raw;
    switch (role) {
      case Role::Latitude:
      case Role::Longitude:
      case Role::StandardParallel1:
      case Role::StandardParallel2: {
        double radians = angle.radians;
        if (const WktNode* u = parameter->child({"ANGLEUNIT", "UNIT"}))
          radians = angular_unit_of(*u).radians;
        value = value * radians / detail::kDegree;
        break;
      }
      case Role::Easting:
      case Role::Northing: {
        double metres = length.metres;
        if (const WktNode* u = parameter->child({"LENGTHUNIT", "UNIT"}))
          metres = linear_unit_of(*u, ctx).metres;
        value *= metres;
        break;
      }
      case Role::Scale:
        if (const WktNode* u = parameter->child({"SCALEUNIT"})) value *= u->number(0).value_or(1.0);
        break;
      case Role::Unknown:
        ctx.warnings.push_back("WKT parameter '" + parameter->name() + "' (" +
                               detail::format_number(value) + ") is not used by " +
                               method_node->name() + ": ignored");
        continue;
    }
    Value* slot = role == Role::Latitude            ? &lat
                  : role == Role::Longitude         ? &lon
                  : role == Role::StandardParallel1 ? &sp1
                  : role == Role::StandardParallel2 ? &sp2
                  : role == Role::Scale             ? &scale
                  : role == Role::Easting           ? &easting
                                                    : &northing;
    slot->present = true;
    slot->value = value;
  }

  Projection p;
  p.latitude_of_origin_deg = lat.value;
  p.longitude_of_origin_deg = lon.value;
  p.scale_factor = scale.present ? scale.value : 1.0;
  p.false_easting_m = easting.value;
  p.false_northing_m = northing.value;
  p.standard_parallel_1_deg = sp1.value;
  p.standard_parallel_2_deg = sp2.value;
  const std::string method_name = method_node->name();
  auto require = [&](const Value& v, const char* what) -> std::optional<Error> {
    if (v.present) return std::nullopt;
    return invalid("WKT projection " + method_name + " needs the parameter " + what);
  };
  switch (method_of(*method_node)) {
    case MethodGuess::TM:
      p.method = ProjectionMethod::TransverseMercator;
      break;
    case MethodGuess::Oblique:
      p.method = ProjectionMethod::ObliqueStereographic;
      if (auto e = require(lat, "latitude of origin")) return *e;
      break;
    case MethodGuess::LCC1:
      p.method = ProjectionMethod::LambertConicConformal1SP;
      if (!lat.present && sp1.present)
        p.latitude_of_origin_deg = sp1.value;
      else if (auto e = require(lat, "latitude of origin"))
        return *e;
      break;
    case MethodGuess::LCC2:
      p.method = ProjectionMethod::LambertConicConformal2SP;
      if (auto e = require(sp1, "standard parallel 1")) return *e;
      if (auto e = require(sp2, "standard parallel 2")) return *e;
      break;
    case MethodGuess::LCCAmbiguous:  // ESRI: one name for both; the parameters decide
      if (sp2.present) {
        p.method = ProjectionMethod::LambertConicConformal2SP;
        if (auto e = require(sp1, "standard parallel 1")) return *e;
        if (scale.present && scale.value != 1.0) {
          return unsupported("WKT " + method_name +
                             " with two standard parallels and scale factor " +
                             detail::format_number(scale.value) + " is not supported");
        }
      } else {
        p.method = ProjectionMethod::LambertConicConformal1SP;
        p.latitude_of_origin_deg = sp1.present ? sp1.value : lat.value;
        if (!sp1.present && !lat.present)
          return *require(lat, "latitude of origin or standard parallel 1");
      }
      break;
    case MethodGuess::PolarGdal:  // GDAL WKT 1: latitude_of_origin ±90 → A, otherwise the standard
                                  // parallel
      if (std::fabs(lat.value) == 90.0) {
        p.method = ProjectionMethod::PolarStereographicA;
      } else {
        p.method = ProjectionMethod::PolarStereographicB;
        p.standard_parallel_1_deg = lat.present ? lat.value : sp1.value;
        p.latitude_of_origin_deg = p.standard_parallel_1_deg < 0 ? -90.0 : 90.0;
        if (scale.present && scale.value != 1.0) {
          ctx.warnings.push_back("WKT Polar_Stereographic with latitude_of_origin " +
                                 detail::format_number(lat.value) +
                                 " read as variant B: scale factor " +
                                 detail::format_number(scale.value) + " ignored");
        }
      }
      break;
    case MethodGuess::PolarA:
      p.method = ProjectionMethod::PolarStereographicA;
      break;
    case MethodGuess::PolarB:
      p.method = ProjectionMethod::PolarStereographicB;
      if (auto e = require(sp1, "latitude of standard parallel")) return *e;
      p.latitude_of_origin_deg = sp1.value < 0 ? -90.0 : 90.0;
      break;
    case MethodGuess::PolarNorthEsri:
    case MethodGuess::PolarSouthEsri: {
      const bool south = method_of(*method_node) == MethodGuess::PolarSouthEsri;
      p.method = ProjectionMethod::PolarStereographicB;
      if (auto e = require(sp1, "standard_parallel_1")) return *e;
      p.standard_parallel_1_deg = south ? -std::fabs(sp1.value) : std::fabs(sp1.value);
      p.latitude_of_origin_deg = south ? -90.0 : 90.0;
      break;
    }
    case MethodGuess::Unknown:
      return unsupported(
          "WKT projection method '" + method_name +
          "' is not supported (supported: Transverse Mercator, Lambert Conic Conformal 1SP/2SP, "
          "Polar Stereographic A/B, Oblique Stereographic)");
  }
  return p;
}

Result<Crs> projected_of(const WktNode& node, Context& ctx) {
  const bool wkt2 = node.keyword == "PROJCRS" || node.keyword == "PROJECTEDCRS";
  const WktNode* geog =
      wkt2 ? node.child({"BASEGEOGCRS", "BASEGEODCRS", "BASEGEOGRAPHICCRS", "GEOGCRS", "GEODCRS"})
           : node.child({"GEOGCS"});
  if (!geog)
    return invalid("WKT " + node.keyword + "[\"" + node.name() + "\"] has no base geographic CRS");
  auto base = geographic_of(*geog, ctx);
  if (!base.ok()) return base.error();
  Crs crs = base.value();
  crs.kind = CrsKind::Projected;
  crs.name = node.name();
  crs.epsg = epsg_code(node);
  crs.linear_unit = metre_unit();
  if (const WktNode* u = crs_unit_node(node, {"LENGTHUNIT", "UNIT"})) {
    crs.linear_unit = linear_unit_of(*u, ctx);
  } else {
    ctx.warnings.push_back("WKT " + node.keyword + "[\"" + node.name() +
                           "\"] has no UNIT: metre assumed");
  }
  const WktNode* conversion = wkt2 ? node.child({"CONVERSION"}) : nullptr;
  if (wkt2 && !conversion)
    return invalid("WKT " + node.keyword + "[\"" + node.name() + "\"] has no CONVERSION");
  auto projection = projection_of(node, conversion, crs.angular_unit, crs.linear_unit, ctx);
  if (!projection.ok()) return projection.error();
  crs.projection = projection.value();
  return crs;
}

VerticalCrs vertical_of(const WktNode& node, Context& ctx) {
  VerticalCrs v;
  v.name = node.name();
  v.epsg = epsg_code(node);
  if (const WktNode* u = crs_unit_node(node, {"LENGTHUNIT", "UNIT"})) {
    v.unit = linear_unit_of(*u, ctx);
  } else if (auto known = detail::vertical_from_epsg(v.epsg)) {
    v.unit = known->unit;
  }
  return v;
}

Result<Crs> interpret(const WktNode& node, Context& ctx, int depth = 0) {
  if (depth > 4) return invalid("WKT CRS nodes nested too deeply");
  const std::string& k = node.keyword;
  if (k == "COMPD_CS" || k == "COMPOUNDCRS") {
    const WktNode* horizontal = nullptr;
    const WktNode* vertical = nullptr;
    for (const WktItem& item : node.items) {
      if (item.kind != WktItem::Kind::Node) continue;
      const std::string& ck = item.node->keyword;
      if (ck == "VERT_CS" || ck == "VERTCS" || ck == "VERTCRS" || ck == "VERTICALCRS") {
        if (!vertical) vertical = item.node.get();
      } else if (ck != "AUTHORITY" && ck != "ID" && ck != "USAGE" && ck != "REMARK" &&
                 !horizontal) {
        horizontal = item.node.get();
      }
    }
    if (!horizontal) return invalid("WKT " + k + " has no horizontal CRS");
    auto crs = interpret(*horizontal, ctx, depth + 1);
    if (!crs.ok()) return crs;
    if (vertical) crs.value().vertical = vertical_of(*vertical, ctx);
    return crs;
  }
  if (k == "BOUNDCRS") {
    const WktNode* source = node.child({"SOURCECRS"});
    const WktNode* target = node.child({"TARGETCRS"});
    const WktNode* transformation = node.child({"ABRIDGEDTRANSFORMATION"});
    if (!source || source->items.empty() || source->items[0].kind != WktItem::Kind::Node) {
      return invalid("WKT BOUNDCRS without SOURCECRS");
    }
    auto crs = interpret(*source->items[0].node, ctx, depth + 1);
    if (!crs.ok()) return crs;
    bool to_wgs84 = false;
    if (target && !target->items.empty() && target->items[0].kind == WktItem::Kind::Node) {
      const WktNode& t = *target->items[0].node;
      to_wgs84 = epsg_code(t) == 4326 || detail::normalise_name(t.name()) == "wgs84";
    }
    if (!to_wgs84 || !transformation) {
      ctx.warnings.push_back(
          "WKT BOUNDCRS: only an abridged transformation to WGS 84 is used; ignored");
      return crs;
    }
    const WktNode* method = transformation->child({"METHOD"});
    const std::string mn = method ? detail::normalise_name(method->name()) : std::string();
    const int mc = method ? epsg_code(*method) : 0;
    const bool position_vector =
        mn.find("positionvector") != std::string::npos || mc == 9606 || mc == 1033;
    const bool coordinate_frame =
        mn.find("coordinateframe") != std::string::npos || mc == 9607 || mc == 1032;
    const bool translation =
        mn.find("geocentrictranslation") != std::string::npos || mc == 9603 || mc == 1031;
    if (!position_vector && !coordinate_frame && !translation) {
      return unsupported("WKT BOUNDCRS transformation method '" +
                         (method ? method->name() : std::string()) +
                         "' is not supported (Helmert methods only)");
    }
    double v[7] = {0, 0, 0, 0, 0, 0, 0};
    for (const WktNode* parameter : transformation->children({"PARAMETER"})) {
      const int code = epsg_code(*parameter);
      const std::string pn = detail::normalise_name(parameter->name());
      int slot = -1;
      if (code >= 8605 && code <= 8611)
        slot = code - 8605;
      else if (pn == "xaxistranslation")
        slot = 0;
      else if (pn == "yaxistranslation")
        slot = 1;
      else if (pn == "zaxistranslation")
        slot = 2;
      else if (pn == "xaxisrotation")
        slot = 3;
      else if (pn == "yaxisrotation")
        slot = 4;
      else if (pn == "zaxisrotation")
        slot = 5;
      else if (pn == "scaledifference")
        slot = 6;
      if (slot >= 0) v[slot] = parameter->number(0).value_or(0.0);
    }
    Helmert7 h{v[0], v[1], v[2], v[3], v[4], v[5], v[6]};
    if (position_vector)
      h = detail::helmert_from_position_vector(v[0], v[1], v[2], v[3], v[4], v[5], v[6]);
    crs.value().datum.to_wgs84 = h;
    crs.value().datum.to_wgs84_source = "WKT BOUNDCRS " + (method ? method->name() : std::string());
    return crs;
  }
  if (k == "PROJCS" || k == "PROJCRS" || k == "PROJECTEDCRS") {
    auto crs = projected_of(node, ctx);
    if (!crs.ok()) return crs;
    // Some writers (Global Mapper) nest the vertical CRS inside PROJCS.
    if (const WktNode* v = node.child({"VERT_CS", "VERTCS", "VERTCRS"}))
      crs.value().vertical = vertical_of(*v, ctx);
    return crs;
  }
  if (k == "GEOGCS" || k == "GEOGCRS" || k == "GEODCRS" || k == "GEOGRAPHICCRS" ||
      k == "GEODETICCRS") {
    auto crs = geographic_of(node, ctx);
    if (!crs.ok()) return crs;
    if (const WktNode* v = node.child({"VERT_CS", "VERTCS", "VERTCRS"}))
      crs.value().vertical = vertical_of(*v, ctx);
    return crs;
  }
  if (k == "GEOCCS") return unsupported("WKT GEOCCS (geocentric CRS) is not supported");
  if (k == "VERT_CS" || k == "VERTCS" || k == "VERTCRS" || k == "VERTICALCRS") {
    return invalid("WKT " + k + " alone describes heights only: a horizontal CRS is needed");
  }
  if (k == "LOCAL_CS" || k == "ENGCRS" || k == "ENGINEERINGCRS") {
    return unsupported("WKT " + k + " (local / engineering CRS) cannot be georeferenced");
  }
  return invalid("WKT starts with " + k + ", which is not a CRS keyword");
}

// ---- writing -----------------------------------------------------------------------------

std::string quoted(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"')
      out += "\"\"";
    else
      out.push_back(c);
  }
  return out + "\"";
}

std::string authority(int code) {
  return code ? ",AUTHORITY[\"EPSG\",\"" + std::to_string(code) + "\"]" : std::string();
}

std::string num(double v) { return detail::format_number(v); }

std::string unit_wkt(const LinearUnit& u) {
  return "UNIT[" + quoted(u.name) + "," + num(u.metres) + authority(u.epsg) + "]";
}

// DATUM[...] with its SPHEROID, TOWGS84 (when the datum has a Helmert) and AUTHORITY.
std::string datum_wkt(const GeodeticDatum& d) {
  const Ellipsoid& e = d.ellipsoid;
  std::string s = "DATUM[" + quoted(d.name) + ",SPHEROID[" + quoted(e.name) + "," +
                  num(e.semi_major_m) + "," + num(e.inverse_flattening) + authority(e.epsg) + "]";
  if (d.to_wgs84 && d.epsg != 6326) {
    const Helmert7& h = *d.to_wgs84;  // WKT 1 TOWGS84 is position vector: negate rotations
    s += ",TOWGS84[" + num(h.tx_m) + "," + num(h.ty_m) + "," + num(h.tz_m) + "," +
         num(-h.rx_arcsec + 0.0) + "," + num(-h.ry_arcsec + 0.0) + "," + num(-h.rz_arcsec + 0.0) +
         "," + num(h.scale_ppm) + "]";
  }
  return s + authority(d.epsg) + "]";
}

// PRIMEM[...] of the datum, its longitude given as `longitude` (WKT 1 writes it in the
// GEOGCS's angular unit, a GEOCCS in degrees).
std::string primem_wkt(const GeodeticDatum& d, double longitude) {
  return "PRIMEM[" + quoted(d.prime_meridian_deg == 0.0 ? "Greenwich" : "user-defined") + "," +
         num(longitude) + "]";
}

std::string geogcs_wkt(const Crs& crs) {
  const GeodeticDatum& d = crs.datum;
  const AngularUnit& a = crs.angular_unit;
  std::string s = "GEOGCS[" + quoted(crs.kind == CrsKind::Geographic ? crs.name : d.name) + "," +
                  datum_wkt(d) + "," +
                  primem_wkt(d, d.prime_meridian_deg * detail::kDegree / a.radians) + ",";
  s += "UNIT[" + quoted(a.name) + "," + num(a.radians) + authority(a.epsg == 9102 ? 9122 : a.epsg) +
       "]";
  if (crs.kind == CrsKind::Geographic)
    s += ",AXIS[\"Longitude\",EAST],AXIS[\"Latitude\",NORTH]" + authority(crs.epsg);
  return s + "]";
}

// DATUM, PRIMEM (degrees), UNIT and AXIS of a WKT 1 GEOCCS.
std::string geocentric_body_wkt(const Crs& crs) {
  return datum_wkt(crs.datum) + "," + primem_wkt(crs.datum, crs.datum.prime_meridian_deg) + "," +
         unit_wkt(crs.linear_unit) +
         ",AXIS[\"Geocentric X\",OTHER],AXIS[\"Geocentric Y\",OTHER],AXIS[\"Geocentric Z\",NORTH]";
}

}  // namespace

namespace detail {

Result<Crs> crs_from_wkt_own(std::string_view wkt) {
  if (wkt.size() > kMaxWktLength) {
    return Error{ErrorCode::InvalidArgument,
                 "WKT longer than " + std::to_string(kMaxWktLength) + " bytes"};
  }
  auto trim = [](std::string_view s) {
    auto blank = [](char c) {
      return c == '\0' || c == ' ' || c == '\t' || c == '\r' || c == '\n';
    };
    while (!s.empty() && blank(s.back())) s.remove_suffix(1);
    while (!s.empty() && blank(s.front())) s.remove_prefix(1);
    return s;
  };
  wkt = trim(wkt);
  // Some writers store an "empty" WKT as a quoted empty string ('' in pdal/warsaw_small.las).
  if (wkt.size() >= 2 && (wkt.front() == '\'' || wkt.front() == '"') && wkt.back() == wkt.front()) {
    wkt = trim(wkt.substr(1, wkt.size() - 2));
  }
  if (wkt.empty()) return Error{ErrorCode::InvalidArgument, "WKT is empty"};
  Parser parser(wkt);
  auto tree = parser.parse();
  if (!tree.ok()) return tree.error();
  Context ctx;
  if (parser.trailing()) ctx.warnings.push_back("text after the WKT CRS ignored");
  auto crs = interpret(*tree.value(), ctx);
  if (!crs.ok()) return crs;
  Crs out = std::move(crs).value();
  out.source = "WKT";
  out.warnings.insert(out.warnings.end(), ctx.warnings.begin(), ctx.warnings.end());
  if (auto status = validate_crs(out); !status.ok()) return status.error();
  return out;
}

}  // namespace detail

Result<Crs> crs_from_wkt(std::string_view wkt) {
  auto own = detail::crs_from_wkt_own(wkt);
  if (own.ok() || own.error().code != ErrorCode::Unsupported) return own;
  // A valid CRS our reader does not model (a method, a geocentric CRS): PROJ reads it.
  auto by_proj = detail::crs_from_proj_text(wkt, "WKT");
  if (by_proj.ok()) return by_proj;
  return Error{ErrorCode::Unsupported, own.error().message + "; PROJ: " + by_proj.error().message};
}

std::string crs_to_wkt1(const Crs& crs) {
  std::string s;
  if (crs.kind == CrsKind::Geocentric) {
    s = "GEOCCS[" + quoted(crs.name) + "," + geocentric_body_wkt(crs) + authority(crs.epsg) + "]";
  } else if (crs.projection && crs.projection->method == ProjectionMethod::ComputedByProj) {
    s = crs.projection->wkt1.empty() ? detail::proj_projected_wkt1(crs) : crs.projection->wkt1;
  } else if (crs.kind == CrsKind::Geographic || !crs.projection) {
    s = geogcs_wkt(crs);
  } else {
    const Projection& p = *crs.projection;
    const double unit = crs.linear_unit.metres;
    auto parameter = [](const char* name, double value) {
      return std::string(",PARAMETER[\"") + name + "\"," + num(value) + "]";
    };
    s = "PROJCS[" + quoted(crs.name) + "," + geogcs_wkt(crs);
    switch (p.method) {
      case ProjectionMethod::TransverseMercator:
      case ProjectionMethod::LambertConicConformal1SP:
      case ProjectionMethod::ObliqueStereographic:
      case ProjectionMethod::PolarStereographicA:
        s += std::string(",PROJECTION[\"") +
             (p.method == ProjectionMethod::TransverseMercator ? "Transverse_Mercator"
              : p.method == ProjectionMethod::LambertConicConformal1SP
                  ? "Lambert_Conformal_Conic_1SP"
              : p.method == ProjectionMethod::ObliqueStereographic ? "Oblique_Stereographic"
                                                                   : "Polar_Stereographic") +
             "\"]";
        s += parameter("latitude_of_origin", p.latitude_of_origin_deg);
        s += parameter("central_meridian", p.longitude_of_origin_deg);
        s += parameter("scale_factor", p.scale_factor);
        break;
      case ProjectionMethod::LambertConicConformal2SP:
        s += ",PROJECTION[\"Lambert_Conformal_Conic_2SP\"]";
        s += parameter("standard_parallel_1", p.standard_parallel_1_deg);
        s += parameter("standard_parallel_2", p.standard_parallel_2_deg);
        s += parameter("latitude_of_origin", p.latitude_of_origin_deg);
        s += parameter("central_meridian", p.longitude_of_origin_deg);
        break;
      case ProjectionMethod::PolarStereographicB:
        s += ",PROJECTION[\"Polar_Stereographic\"]";
        s += parameter("latitude_of_origin", p.standard_parallel_1_deg);
        s += parameter("central_meridian", p.longitude_of_origin_deg);
        s += parameter("scale_factor", 1.0);
        break;
      case ProjectionMethod::ComputedByProj:  // written by PROJ above
        break;
    }
    s += parameter("false_easting", p.false_easting_m / unit);
    s += parameter("false_northing", p.false_northing_m / unit);
    s += "," + unit_wkt(crs.linear_unit) + ",AXIS[\"Easting\",EAST],AXIS[\"Northing\",NORTH]" +
         authority(crs.epsg) + "]";
  }
  if (!crs.vertical) return s;
  const VerticalCrs& v = *crs.vertical;
  return "COMPD_CS[" + quoted(crs.name + " + " + v.name) + "," + s + ",VERT_CS[" + quoted(v.name) +
         ",VERT_DATUM[" + quoted(v.name) + ",2005]," + unit_wkt(v.unit) +
         ",AXIS[\"Gravity-related height\",UP]" + authority(v.epsg) + "]]";
}

}  // namespace csgtile::geo
