// GCC 12 reports a false -Wrestrict inside libstdc++'s std::string::replace when inlined into
// valijson's JSON-pointer code (GCC bug 105329); the warning escapes the system-header filter.
#if defined(__GNUC__) && !defined(__clang__) && __GNUC__ == 12
#pragma GCC diagnostic ignored "-Wrestrict"
#endif

#include <cstdint>
#include <set>
#include <string>
#include <string_view>
#include <utility>
#include <valijson/adapters/nlohmann_json_adapter.hpp>
#include <valijson/schema.hpp>
#include <valijson/schema_parser.hpp>
#include <valijson/validation_results.hpp>
#include <valijson/validator.hpp>
#include <vector>

#include "document.h"

namespace csgtile::config::detail {
namespace {

using nlohmann::json;

/// The compiled schema, built once. valijson only reads it while validating, so one instance
/// serves every thread.
struct CompiledSchema {
  CompiledSchema() {
    valijson::SchemaParser parser(valijson::SchemaParser::kDraft7);
    const valijson::adapters::NlohmannJsonAdapter adapter(schema_document());
    parser.populateSchema(adapter, schema);
  }
  valijson::Schema schema;
};

const valijson::Schema& compiled_schema() {
  static const CompiledSchema kCompiled;
  return kCompiled.schema;
}

/// valijson names a value by a context like {"<root>", "[queue]", "[max_attempts]"}; list
/// items are "[0]". Whether a part is a key or an index is read off the document itself.
json::json_pointer pointer_of(const std::vector<std::string>& context, const json& document) {
  json::json_pointer pointer;
  const json* node = &document;
  for (std::size_t i = 1; i < context.size(); ++i) {
    const std::string& part = context[i];
    const std::string token = part.size() >= 2 && part.front() == '[' && part.back() == ']'
                                  ? part.substr(1, part.size() - 2)
                                  : part;
    if (node != nullptr && node->is_array()) {
      const std::size_t index = std::stoul(token);
      pointer /= index;
      node = index < node->size() ? &(*node)[index] : nullptr;
    } else {
      pointer /= token;
      node = (node != nullptr && node->is_object() && node->contains(token)) ? &(*node)[token]
                                                                             : nullptr;
    }
  }
  return pointer;
}

std::string number_text(const json* schema, const char* keyword) {
  if (schema == nullptr || !schema->contains(keyword)) return "?";
  return schema->at(keyword).dump();
}

std::string join_strings(const json& values) {
  std::string out;
  for (const json& value : values) {
    if (!out.empty()) out += ", ";
    // An empty name is shown quoted, as "".
    const bool plain = value.is_string() && !value.get<std::string>().empty();
    out += plain ? value.get<std::string>() : value.dump();
  }
  return out;
}

/// Exact a < b for two integer JSON numbers, signed or unsigned.
bool integer_less(const json& a, const json& b) {
  if (a.is_number_unsigned()) {
    const auto x = a.get<std::uint64_t>();
    return b.is_number_unsigned() ? x < b.get<std::uint64_t>()
                                  : std::cmp_less(x, b.get<std::int64_t>());
  }
  const auto x = a.get<std::int64_t>();
  return b.is_number_unsigned() ? std::cmp_less(x, b.get<std::uint64_t>())
                                : x < b.get<std::int64_t>();
}

class ProblemCollector {
 public:
  ProblemCollector(const Document& document, std::vector<Problem>& problems)
      : document_(document), problems_(problems) {}

  /// Adds the problem once; the origin decides the line or names the environment variable.
  void add(const json::json_pointer& pointer, std::string message) {
    const Origin origin = document_.origin_of(pointer);
    if (!origin.variable.empty()) message += " (from environment variable " + origin.variable + ")";
    Problem problem{display_path(document_.json, pointer), origin.line, std::move(message)};
    if (seen_.insert({problem.path, problem.message}).second) problems_.push_back(problem);
  }

  /// Turns one valijson error into problems. valijson also reports every enclosing object or
  /// list whose member failed ("Failed to validate against schema associated with property
  /// name ..."); those repeat a more precise error and are dropped.
  void add_error(const valijson::ValidationResults::Error& error) {
    const json::json_pointer pointer = pointer_of(error.context, document_.json);
    const json& value = document_.json.contains(pointer) ? document_.json.at(pointer) : kNull;
    const json* schema = schema_at(pointer);
    const std::string_view text = error.description;
    const auto starts = [&](std::string_view prefix) { return text.starts_with(prefix); };

    if (starts("Failed to validate") || starts("Cannot validate")) return;
    // A fraction for an integer key also fails its bounds when large; the type error says it.
    if (starts("Expected number") && schema_type(schema) == "integer" &&
        !value.is_number_integer()) {
      return;
    }
    if (starts("Value type not permitted")) {
      add(pointer,
          "expected " + describe_type(schema_type(schema)) + ", got " + describe_value(value));
    } else if (starts("Expected number less than or equal to")) {
      add(pointer, "must be <= " + number_text(schema, "maximum") + " (got " + value.dump() + ")");
    } else if (starts("Expected number less than")) {
      add(pointer,
          "must be < " + number_text(schema, "exclusiveMaximum") + " (got " + value.dump() + ")");
    } else if (starts("Expected number greater than or equal to")) {
      add(pointer, "must be >= " + number_text(schema, "minimum") + " (got " + value.dump() + ")");
    } else if (starts("Expected number greater than")) {
      add(pointer,
          "must be > " + number_text(schema, "exclusiveMinimum") + " (got " + value.dump() + ")");
    } else if (starts("Failed to match against any enum values")) {
      add_enum_error(pointer, value, schema);
    } else if (starts("Failed to match regex")) {
      add(pointer,
          "must match " + number_text(schema, "pattern") + " (got " + describe_value(value) + ")");
    } else if (starts("String should be no fewer than")) {
      const bool non_empty = schema != nullptr && schema->value("minLength", 0) == 1;
      add(pointer, non_empty
                       ? std::string("must not be empty")
                       : "must have at least " + number_text(schema, "minLength") + " characters");
    } else if (starts("Object contains a property that could not be validated")) {
      add_unknown_keys(pointer, value, schema);
    } else {
      add(pointer, error.description);
    }
  }

  /// valijson compares numbers as doubles, so 2^53 + 1 passes "maximum: 2^53". Integer
  /// bounds of integer keys are checked again exactly; the messages match valijson's, so a
  /// value both catch is reported once.
  void check_integer_bounds(const json& value, const json::json_pointer& pointer) {
    if (value.is_object()) {
      for (const auto& [key, member] : value.items()) check_integer_bounds(member, pointer / key);
      return;
    }
    if (value.is_array()) {
      for (std::size_t i = 0; i < value.size(); ++i) check_integer_bounds(value[i], pointer / i);
      return;
    }
    const json* schema = schema_at(pointer);
    if (!value.is_number_integer() || schema == nullptr || schema_type(schema) != "integer") return;
    const auto bound = [&](const char* keyword) -> const json* {
      const auto found = schema->find(keyword);
      return found != schema->end() && found->is_number_integer() ? &*found : nullptr;
    };
    if (const json* maximum = bound("maximum"); maximum && integer_less(*maximum, value)) {
      add(pointer, "must be <= " + maximum->dump() + " (got " + value.dump() + ")");
    }
    if (const json* minimum = bound("minimum"); minimum && integer_less(value, *minimum)) {
      add(pointer, "must be >= " + minimum->dump() + " (got " + value.dump() + ")");
    }
  }

 private:
  void add_enum_error(const json::json_pointer& pointer, const json& value, const json* schema) {
    const json choices = schema != nullptr ? schema->value("enum", json::array()) : json::array();
    std::string message =
        "must be one of " + join_strings(choices) + " (got " + describe_value(value);
    if (value.is_string()) {
      std::vector<std::string> names;
      for (const json& choice : choices) {
        if (choice.is_string()) names.push_back(choice.get<std::string>());
      }
      if (const auto match = closest_match(value.get<std::string>(), names)) {
        message += "; did you mean " + *match + "?";
      }
    }
    add(pointer, message + ")");
  }

  /// valijson names only the first unknown key of an object; report each of them.
  void add_unknown_keys(const json::json_pointer& pointer, const json& value, const json* schema) {
    if (schema == nullptr || !value.is_object()) return;
    const std::vector<std::string> allowed = property_names(*schema);
    for (const auto& [key, member] : value.items()) {
      if (schema->contains("properties") && schema->at("properties").contains(key)) continue;
      add(pointer / key, unknown_key_message(key, allowed));
    }
  }

  static inline const json kNull = nullptr;
  const Document& document_;
  std::vector<Problem>& problems_;
  std::set<std::pair<std::string, std::string>> seen_;
};

}  // namespace

void validate(const Document& document, std::vector<Problem>& problems) {
  valijson::Validator validator(valijson::Validator::kStrongTypes);
  valijson::ValidationResults results;
  const valijson::adapters::NlohmannJsonAdapter target(document.json);
  validator.validate(compiled_schema(), target, &results);

  ProblemCollector collector(document, problems);
  valijson::ValidationResults::Error error;
  while (results.popError(error)) collector.add_error(error);
  collector.check_integer_bounds(document.json, json::json_pointer());
}

}  // namespace csgtile::config::detail
