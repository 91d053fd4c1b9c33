#include <unistd.h>

#include <cctype>
#include <string>
#include <string_view>
#include <vector>

#include "document.h"

namespace csgtile::config {

Environment from_process_environment() {
  Environment env;
  for (char** entry = environ; entry != nullptr && *entry != nullptr; ++entry) {
    const std::string_view text(*entry);
    const std::size_t equals = text.find('=');
    if (equals == std::string_view::npos) continue;
    env.emplace(std::string(text.substr(0, equals)), std::string(text.substr(equals + 1)));
  }
  return env;
}

namespace detail {
namespace {

using nlohmann::json;

constexpr std::string_view kPrefix = "CSGTILE_";
constexpr std::string_view kSeparator = "__";

std::vector<std::string> split(std::string_view text, std::string_view separator) {
  std::vector<std::string> parts;
  for (;;) {
    const std::size_t at = text.find(separator);
    parts.emplace_back(text.substr(0, at));
    if (at == std::string_view::npos) return parts;
    text.remove_prefix(at + separator.size());
  }
}

std::string trim(std::string_view text) {
  const auto is_space = [](char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; };
  while (!text.empty() && is_space(text.front())) text.remove_prefix(1);
  while (!text.empty() && is_space(text.back())) text.remove_suffix(1);
  return std::string(text);
}

std::string lowercase(std::string_view text) {
  std::string out(text);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

std::string suffix(const std::string& variable) {
  return " (from environment variable " + variable + ")";
}

/// One override: resolves the key against the schema, then replaces the value in the
/// document. Values are converted as unquoted YAML scalars would be; a list key takes a
/// comma-separated list (items trimmed; an empty value is an empty list).
void apply_one(const std::string& variable, const std::string& value, Document& document,
               std::vector<Problem>& problems) {
  const std::vector<std::string> segments =
      split(std::string_view{variable}.substr(kPrefix.size()), kSeparator);
  json::json_pointer pointer;
  std::string path;
  const json* schema = &schema_document();
  for (std::size_t i = 0; i < segments.size(); ++i) {
    const std::string key = lowercase(segments[i]);
    const std::vector<std::string> allowed = property_names(*schema);
    if (key.empty()) {
      problems.push_back({path, 0, "empty key name" + suffix(variable)});
      return;
    }
    path += path.empty() ? key : "." + key;
    if (!schema->contains("properties") || !schema->at("properties").contains(key)) {
      problems.push_back({path, 0, unknown_key_message(key, allowed) + suffix(variable)});
      return;
    }
    pointer /= key;
    schema = &schema->at("properties").at(key);
  }
  if (schema_type(schema) == "object") {
    problems.push_back({path, 0,
                        "is a section; set its keys one by one (e.g. " + variable + "__<KEY>)" +
                            suffix(variable)});
    return;
  }

  // Create missing sections; when the file has a non-mapping there, the schema check reports
  // the file's value and the override has nowhere to go.
  std::vector<std::string> parents;
  for (json::json_pointer at = pointer.parent_pointer(); !at.empty(); at.pop_back()) {
    parents.push_back(at.back());
  }
  json* parent = &document.json;
  for (auto name = parents.rbegin(); name != parents.rend(); ++name) {
    if (!parent->is_object()) return;
    json& child = (*parent)[*name];
    if (child.is_null()) child = json::object();
    parent = &child;
  }
  if (!parent->is_object()) return;

  json converted;
  if (schema_type(schema) == "array") {
    converted = json::array();
    const json* item_schema = schema_at(pointer / 0);
    if (!trim(value).empty()) {
      for (const std::string& item : split(value, ",")) {
        converted.push_back(plain_scalar_to_json(trim(item), item_schema));
      }
    }
  } else {
    converted = plain_scalar_to_json(value, schema);
  }

  // The override replaces the whole value: forget where the old one's parts came from.
  const std::string key = pointer.to_string();
  for (auto it = document.origins.lower_bound(key + "/");
       it != document.origins.end() && it->first.starts_with(key + "/");) {
    it = document.origins.erase(it);
  }
  document.origins[key] = Origin{0, variable};
  (*parent)[pointer.back()] = std::move(converted);
}

}  // namespace

void apply_environment(const Environment& env, Document& document, std::vector<Problem>& problems) {
  // std::map order: overrides apply in a fixed order whatever the process environment's.
  for (const auto& [variable, value] : env) {
    if (!variable.starts_with(kPrefix)) continue;
    // Without "__" the variable is not an override (CSGTILE_LOG_LEVEL, or read by a tool).
    if (std::string_view{variable}.substr(kPrefix.size()).find(kSeparator) ==
        std::string_view::npos) {
      continue;
    }
    apply_one(variable, value, document, problems);
  }
}

}  // namespace detail
}  // namespace csgtile::config
