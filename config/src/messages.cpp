#include <algorithm>
#include <cctype>
#include <string>
#include <string_view>
#include <vector>

#include "document.h"

namespace csgtile::config::detail {
namespace {

using nlohmann::json;

std::string lowercase(std::string_view text) {
  std::string out(text);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

/// Optimal string alignment distance: Levenshtein plus adjacent transpositions, the usual
/// typing slips ("levle" → "level" is one edit).
std::size_t edit_distance(std::string_view a, std::string_view b) {
  const std::size_t rows = a.size() + 1;
  const std::size_t columns = b.size() + 1;
  std::vector<std::size_t> d(rows * columns);
  const auto at = [&](std::size_t i, std::size_t j) -> std::size_t& { return d[i * columns + j]; };
  for (std::size_t i = 0; i < rows; ++i) at(i, 0) = i;
  for (std::size_t j = 0; j < columns; ++j) at(0, j) = j;
  for (std::size_t i = 1; i < rows; ++i) {
    for (std::size_t j = 1; j < columns; ++j) {
      const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      at(i, j) = std::min({at(i - 1, j) + 1, at(i, j - 1) + 1, at(i - 1, j - 1) + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) {
        at(i, j) = std::min(at(i, j), at(i - 2, j - 2) + 1);
      }
    }
  }
  return at(rows - 1, columns - 1);
}

std::string join(const std::vector<std::string>& words) {
  std::string out;
  for (const std::string& word : words) {
    if (!out.empty()) out += ", ";
    out += word;
  }
  return out;
}

}  // namespace

std::optional<std::string> closest_match(std::string_view word,
                                         const std::vector<std::string>& candidates) {
  const std::string lower = lowercase(word);
  // About one slip per three letters: close enough to be a typo, far enough not to suggest
  // an unrelated key for a short word.
  const std::size_t limit = std::clamp<std::size_t>(lower.size() / 3, 1, 3);
  std::optional<std::string> best;
  std::size_t best_distance = limit + 1;
  for (const std::string& candidate : candidates) {
    const std::size_t distance = edit_distance(lower, lowercase(candidate));
    if (distance < best_distance) {
      best = candidate;
      best_distance = distance;
    }
  }
  return best;
}

std::string unknown_key_message(std::string_view key, const std::vector<std::string>& allowed) {
  if (const auto match = closest_match(key, allowed)) {
    return "unknown key (did you mean " + *match + "?)";
  }
  if (allowed.empty()) return "unknown key";
  return "unknown key; allowed: " + join(allowed);
}

std::string display_path(const json& document, const json::json_pointer& pointer) {
  std::vector<std::string> tokens;
  for (json::json_pointer at = pointer; !at.empty(); at.pop_back()) tokens.push_back(at.back());
  std::reverse(tokens.begin(), tokens.end());

  std::string path;
  const json* node = &document;
  for (const std::string& token : tokens) {
    if (node != nullptr && node->is_array()) {
      path += "[" + token + "]";
      const std::size_t index = std::stoul(token);
      node = index < node->size() ? &(*node)[index] : nullptr;
      continue;
    }
    if (!path.empty()) path += ".";
    path += token;
    node =
        (node != nullptr && node->is_object() && node->contains(token)) ? &(*node)[token] : nullptr;
  }
  return path;
}

std::string describe_value(const json& value) {
  switch (value.type()) {
    case json::value_t::null:
      return "null";
    case json::value_t::boolean:
      return "boolean " + value.dump();
    case json::value_t::number_integer:
    case json::value_t::number_unsigned:
      return "integer " + value.dump();
    case json::value_t::number_float:
      return "number " + value.dump();
    case json::value_t::string:
      // Replace invalid UTF-8 rather than throw: the text is only shown to a person.
      return "string " + value.dump(-1, ' ', false, json::error_handler_t::replace);
    case json::value_t::array:
      return "a list";
    case json::value_t::object:
      return "a mapping";
    default:
      return "an unsupported value";
  }
}

std::string describe_type(std::string_view schema_type_name) {
  if (schema_type_name == "object") return "mapping";
  if (schema_type_name == "array") return "list";
  return std::string(schema_type_name);
}

}  // namespace csgtile::config::detail
