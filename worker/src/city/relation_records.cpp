// A cell's relations in its record (relation_records.h).

#include "city/relation_records.h"

#include <utility>

namespace csgtile::worker::city::detail {

namespace {

RelationKind kind_of(const std::string& name, bool& ok) {
  ok = true;
  for (RelationKind k : {RelationKind::Touches, RelationKind::Overlaps, RelationKind::Contains,
                         RelationKind::Within, RelationKind::Equals, RelationKind::Unknown}) {
    if (name == relation_kind_name(k)) return k;
  }
  ok = false;
  return RelationKind::Unknown;
}

}  // namespace

ordered_json relations_json(const std::vector<ObjectRelation>& relations,
                            const std::vector<IndexObject>& objects) {
  ordered_json out = ordered_json::array();
  for (const ObjectRelation& r : relations) {
    out.push_back({{"a", objects.at(r.a).id},
                   {"b", objects.at(r.b).id},
                   {"kind", relation_kind_name(r.kind)},
                   {"shared_area", r.shared_area},
                   {"common_volume", r.common_volume},
                   {"reason", r.reason}});
  }
  return out;
}

Failure read_relations(const ordered_json& record,
                       const std::map<std::string, std::size_t>& index_of,
                       std::vector<ObjectRelation>& out, bool& found) {
  found = record.contains("relations");
  if (!found) return {};
  const ordered_json& list = record.at("relations");
  const auto malformed = [&](const std::string& why) {
    return Failure{ErrorCode::Internal, "cell " + record.value("cell", std::string("?")) +
                                            ": its record's relations " + why};
  };
  if (!list.is_array()) return malformed("are not a list");
  for (const ordered_json& e : list) {
    if (!e.is_object() || !e.contains("a") || !e.contains("b") || !e.contains("kind") ||
        !e.at("a").is_string() || !e.at("b").is_string() || !e.at("kind").is_string() ||
        !e.value("shared_area", ordered_json()).is_number() ||
        !e.value("common_volume", ordered_json()).is_number()) {
      return malformed("hold a malformed entry: " + e.dump());
    }
    const auto a = index_of.find(e.at("a").get<std::string>());
    const auto b = index_of.find(e.at("b").get<std::string>());
    if (a == index_of.end() || b == index_of.end() || a->second == b->second) {
      return malformed("name an object the run does not hold: " + e.dump());
    }
    bool ok = false;
    ObjectRelation r;
    r.kind = kind_of(e.at("kind").get<std::string>(), ok);
    if (!ok) return malformed("name an unknown kind: " + e.dump());
    r.a = a->second;
    r.b = b->second;
    if (r.a > r.b) {
      std::swap(r.a, r.b);
      r.kind = converse(r.kind);
    }
    r.shared_area = e.at("shared_area").get<double>();
    r.common_volume = e.at("common_volume").get<double>();
    if (e.contains("reason") && e.at("reason").is_string())
      r.reason = e.at("reason").get<std::string>();
    out.push_back(std::move(r));
  }
  return {};
}

}  // namespace csgtile::worker::city::detail
