#pragma once
/// \file
/// Private pieces shared by the loading steps: the document being built (JSON plus where each
/// value came from), schema lookups, YAML conversion, environment overrides and validation.
///
/// The steps run in order: yaml_to_document → apply_environment → validate → (config.cpp)
/// conversion to structs. Each step appends problems instead of stopping, so that one load
/// reports everything wrong at once.

#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "csgtile/config/config.h"

namespace csgtile::config::detail {

/// Where a value of the document came from: a 1-based line of the text (the line of its key,
/// or of the item for list items), or an environment variable (then `line` is 0).
struct Origin {
  int line = 0;
  std::string variable;
};

/// The configuration as JSON (the form the schema validates), with the origin of every value
/// keyed by JSON pointer ("/queue/max_attempts", "/run/inputs/0").
struct Document {
  nlohmann::json json = nlohmann::json::object();
  std::map<std::string, Origin> origins;

  /// Origin of `pointer`, or of its nearest ancestor that has one (root: line 0).
  Origin origin_of(const nlohmann::json::json_pointer& pointer) const;
};

// ---- schema (schema.cpp) ----------------------------------------------------------------------

/// The embedded schema, parsed once (thread-safe). Throws only if the embedded text is broken.
const nlohmann::json& schema_document();
/// Subschema describing the value at `pointer` ("properties" for object members, "items" for
/// list items), or nullptr when the schema does not describe it (an unknown key).
const nlohmann::json* schema_at(const nlohmann::json::json_pointer& pointer);
/// The "type" of a subschema when it is a single type name, else "".
std::string schema_type(const nlohmann::json* schema);
/// Property names of an object subschema, sorted by name.
std::vector<std::string> property_names(const nlohmann::json& schema);

/// JSON value of a plain (unquoted) scalar, decided by the type the schema expects there:
/// the raw text when a string is expected (so "001" stays "001"); otherwise an integer, then a
/// floating-point number, then true/false, else the text as a string.
nlohmann::json plain_scalar_to_json(std::string_view text, const nlohmann::json* schema);

// ---- messages (messages.cpp) -----------------------------------------------------------------

/// The candidate closest to `word` by edit distance (case-insensitive, transpositions count
/// one), if close enough to be a likely typo. Ties go to the earlier candidate.
std::optional<std::string> closest_match(std::string_view word,
                                         const std::vector<std::string>& candidates);
/// "unknown key (did you mean max_attempts?)" or "unknown key; allowed: a, b, c".
std::string unknown_key_message(std::string_view key, const std::vector<std::string>& allowed);
/// Dotted display path of a pointer into `json`: "queue.max_attempts", "run.inputs[1]".
std::string display_path(const nlohmann::json& json, const nlohmann::json::json_pointer& pointer);
/// Words a YAML user knows: "string \"five\"", "integer 5", "a list", "a mapping", "null".
std::string describe_value(const nlohmann::json& value);
/// "integer", "number", "string", "boolean", "list", "mapping".
std::string describe_type(std::string_view schema_type_name);

// ---- the fit section (fit_config.cpp) -------------------------------------------------------

/// Reads `fit:` of a valid document into `fit` (absent keys keep their defaults).
void read_fit(const nlohmann::json& document, FitConfig& fit);
/// `fit` as the canonical JSON object of to_json.
nlohmann::json fit_to_json(const FitConfig& fit);

// ---- steps -----------------------------------------------------------------------------------

/// Parses `yaml` into `document` (yaml_to_json.cpp). Reports syntax errors, duplicate keys,
/// non-mapping top level and non-string keys.
void yaml_to_document(std::string_view yaml, Document& document, std::vector<Problem>& problems);

/// Applies CSGTILE_<SECTION>__<KEY> overrides (environment.cpp).
void apply_environment(const Environment& env, Document& document, std::vector<Problem>& problems);

/// Validates `document` against the schema with valijson (validate.cpp) and turns each error
/// into a Problem with key path, line and a readable message.
void validate(const Document& document, std::vector<Problem>& problems);

}  // namespace csgtile::config::detail
