// `csgtile query INDEX.gpkg (--children ID | --ancestors ID --kind K | --relations OBJECT)
// [--json]`: topology questions answered from a published topology index (README "Topology
// index"). ID is a shape's numeric id or its key "<object>/<kind>/<index>".

#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "csgtile/worker/errors.h"
#include "export/topology_index.h"

namespace csgtile::worker::detail {

namespace {

using Json = nlohmann::ordered_json;

struct QueryOptions {
  std::string index;
  std::string children, ancestors, kind, relations;
  bool json = false;
};

Json shape_json(const ShapeRow& s) {
  return Json{{"id", s.id},
              {"key", s.key},
              {"object", s.object_id},
              {"kind", s.kind},
              {"index", s.kind_index}};
}

Json optional_json(const std::optional<double>& v) { return v ? Json(*v) : Json(nullptr); }

std::string optional_text(const std::optional<double>& v) {
  if (!v) return "-";
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.10g", *v);
  return buffer;
}

int run_query(const QueryOptions& o) {
  Json out;
  out["index"] = o.index;
  auto fail = [&](const Failure& f) { return detail::report_failure("query", f, o.json, out); };
  const int questions = !o.children.empty() + !o.ancestors.empty() + !o.relations.empty();
  if (questions != 1 || (!o.ancestors.empty() && o.kind.empty())) {
    std::fprintf(stderr,
                 "csgtile query: give exactly one of --children ID, --ancestors ID --kind K, "
                 "--relations OBJECT\n");
    return error_info(ErrorCode::Usage).exit_code;
  }
  auto reader = TopologyIndexReader::open(o.index);
  if (!reader.ok()) return fail(reader.error());
  const TopologyIndexReader& index = *reader.value();

  if (!o.relations.empty()) {
    auto rows = index.relations(o.relations);
    if (!rows.ok()) return fail(rows.error());
    out["object"] = o.relations;
    Json list = Json::array();
    for (const RelationRow& r : rows.value()) {
      list.push_back({{"other", r.other_id},
                      {"relation", r.relation},
                      {"shared_area", optional_json(r.shared_area)},
                      {"common_volume", optional_json(r.common_volume)},
                      {"reason", r.reason.empty() ? Json(nullptr) : Json(r.reason)}});
      if (!o.json) {
        std::printf("%s\t%s\t%s\t%s\t%s\n", r.other_id.c_str(), r.relation.c_str(),
                    optional_text(r.shared_area).c_str(), optional_text(r.common_volume).c_str(),
                    r.reason.empty() ? "-" : r.reason.c_str());
      }
    }
    out["relations"] = std::move(list);
  } else {
    auto shape = index.shape(o.children.empty() ? o.ancestors : o.children);
    if (!shape.ok()) return fail(shape.error());
    out["shape"] = shape_json(shape.value());
    if (!o.children.empty()) {
      auto rows = index.children(shape->id);
      if (!rows.ok()) return fail(rows.error());
      Json list = Json::array();
      for (const ChildRow& c : rows.value()) {
        Json j = shape_json(c.child);
        j["position"] = c.position;
        j["orientation"] = c.orientation;
        j["location"] = c.location.empty() ? Json(nullptr) : Json::parse(c.location);
        list.push_back(std::move(j));
        if (!o.json) {
          std::printf("%lld\t%lld\t%s\t%s\t%s\n", static_cast<long long>(c.position),
                      static_cast<long long>(c.child.id), c.child.key.c_str(),
                      c.orientation.c_str(), c.location.empty() ? "-" : c.location.c_str());
        }
      }
      out["children"] = std::move(list);
    } else {
      auto rows = index.ancestors(shape->id, o.kind);
      if (!rows.ok()) return fail(rows.error());
      out["kind"] = o.kind;
      Json list = Json::array();
      for (const ShapeRow& a : rows.value()) {
        list.push_back(shape_json(a));
        if (!o.json) std::printf("%lld\t%s\n", static_cast<long long>(a.id), a.key.c_str());
      }
      out["ancestors"] = std::move(list);
    }
  }
  if (o.json) {
    out["error"] = nullptr;
    std::cout << out.dump() << "\n";
  }
  return 0;
}

}  // namespace

void register_query(CLI::App& app, Action& action) {
  auto* cmd = app.add_subcommand(
      "query",
      "Answer topology questions from a topology index (GeoPackage): children of a "
      "shape, its ancestors of a kind, relations of an object");
  auto o = std::make_shared<QueryOptions>();
  cmd->add_option("INDEX", o->index, "Topology index (.gpkg), e.g. a run's index.gpkg")->required();
  auto* children = cmd->add_option("--children", o->children,
                                   "Sub-shape references of shape ID (numeric id or key "
                                   "<object>/<kind>/<index>)");
  auto* ancestors =
      cmd->add_option("--ancestors", o->ancestors, "Ancestors of shape ID (with --kind)");
  auto* kind = cmd->add_option(
      "--kind", o->kind, "Ancestor kind: compound, compsolid, solid, shell, face, wire, edge");
  auto* relations = cmd->add_option("--relations", o->relations, "Relations of object OBJECT");
  children->excludes(ancestors)->excludes(relations);
  ancestors->excludes(relations)->needs(kind);
  kind->needs(ancestors);
  cmd->add_flag("--json", o->json, "Print the answer as one JSON object");
  cmd->callback([&action, o] { action = [o] { return run_query(*o); }; });
}

}  // namespace csgtile::worker::detail
