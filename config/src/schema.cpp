#include <charconv>
#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "document.h"
#include "schema_text.h"

namespace csgtile::config::detail {
namespace {

using nlohmann::json;

std::vector<std::string> tokens_of(json::json_pointer pointer) {
  std::vector<std::string> tokens;
  while (!pointer.empty()) {
    tokens.push_back(pointer.back());
    pointer.pop_back();
  }
  return {tokens.rbegin(), tokens.rend()};
}

bool is_digits(std::string_view text) {
  if (text.empty()) return false;
  for (char c : text) {
    if (c < '0' || c > '9') return false;
  }
  return true;
}

/// YAML 1.2 core-schema integer (decimal only): [-+]?[0-9]+. Out of the 64-bit range gives
/// nothing, so that the caller falls back to a floating-point number.
std::optional<json> parse_integer(std::string_view text) {
  bool negative = false;
  std::string_view digits = text;
  if (!digits.empty() && (digits.front() == '-' || digits.front() == '+')) {
    negative = digits.front() == '-';
    digits.remove_prefix(1);
  }
  if (!is_digits(digits)) return std::nullopt;
  std::uint64_t magnitude = 0;
  const auto [end, error] =
      std::from_chars(digits.data(), digits.data() + digits.size(), magnitude);
  if (error != std::errc() || end != digits.data() + digits.size()) return std::nullopt;
  if (negative) {
    constexpr std::uint64_t kMaxNegative = std::uint64_t{1} << 63;
    if (magnitude > kMaxNegative) return std::nullopt;
    if (magnitude == kMaxNegative) return json(INT64_MIN);
    return json(-static_cast<std::int64_t>(magnitude));
  }
  // Signed where it fits, so that equal numbers always get the same JSON representation.
  if (magnitude <= static_cast<std::uint64_t>(INT64_MAX)) {
    return json(static_cast<std::int64_t>(magnitude));
  }
  return json(magnitude);
}

/// YAML 1.2 core-schema float without the .inf/.nan forms (JSON has no such numbers):
/// [-+]?(\.[0-9]+|[0-9]+(\.[0-9]*)?)([eE][-+]?[0-9]+)?
std::optional<json> parse_float(std::string_view text) {
  std::string_view rest = text;
  if (!rest.empty() && (rest.front() == '-' || rest.front() == '+')) rest.remove_prefix(1);
  std::size_t i = 0;
  const auto digits_from = [&](std::size_t at) {
    std::size_t n = 0;
    while (at + n < rest.size() && rest[at + n] >= '0' && rest[at + n] <= '9') ++n;
    return n;
  };
  const std::size_t integer_digits = digits_from(i);
  i += integer_digits;
  std::size_t fraction_digits = 0;
  if (i < rest.size() && rest[i] == '.') {
    ++i;
    fraction_digits = digits_from(i);
    i += fraction_digits;
  }
  if (integer_digits == 0 && fraction_digits == 0) return std::nullopt;
  if (i < rest.size() && (rest[i] == 'e' || rest[i] == 'E')) {
    ++i;
    if (i < rest.size() && (rest[i] == '-' || rest[i] == '+')) ++i;
    const std::size_t exponent_digits = digits_from(i);
    if (exponent_digits == 0) return std::nullopt;
    i += exponent_digits;
  }
  if (i != rest.size()) return std::nullopt;

  // from_chars takes no leading '+'.
  std::string_view number = text.front() == '+' ? text.substr(1) : text;
  double value = 0.0;
  const auto [end, error] = std::from_chars(number.data(), number.data() + number.size(), value);
  if (error != std::errc() || end != number.data() + number.size() || !std::isfinite(value)) {
    return std::nullopt;
  }
  return json(value);
}

}  // namespace

Origin Document::origin_of(const json::json_pointer& pointer) const {
  for (json::json_pointer at = pointer;; at.pop_back()) {
    if (const auto found = origins.find(at.to_string()); found != origins.end()) {
      return found->second;
    }
    if (at.empty()) return {};
  }
}

const json& schema_document() {
  static const json kSchema = json::parse(embedded_schema_text());
  return kSchema;
}

const json* schema_at(const json::json_pointer& pointer) {
  const json* node = &schema_document();
  for (const std::string& token : tokens_of(pointer)) {
    const auto properties = node->find("properties");
    if (properties != node->end() && properties->is_object() && properties->contains(token)) {
      node = &(*properties)[token];
      continue;
    }
    const auto items = node->find("items");
    if (items != node->end() && items->is_object() && is_digits(token)) {
      node = &*items;
      continue;
    }
    return nullptr;
  }
  return node;
}

std::string schema_type(const json* schema) {
  if (schema == nullptr) return {};
  const auto type = schema->find("type");
  if (type == schema->end() || !type->is_string()) return {};
  return type->get<std::string>();
}

std::vector<std::string> property_names(const json& schema) {
  std::vector<std::string> names;
  const auto properties = schema.find("properties");
  if (properties == schema.end() || !properties->is_object()) return names;
  // nlohmann::json keeps object keys sorted, which is also a stable order for messages.
  for (const auto& [name, subschema] : properties->items()) names.push_back(name);
  return names;
}

json plain_scalar_to_json(std::string_view text, const json* schema) {
  if (schema_type(schema) == "string") return json(std::string(text));
  if (auto integer = parse_integer(text)) return *integer;
  if (auto number = parse_float(text)) return *number;
  if (text == "true") return json(true);
  if (text == "false") return json(false);
  return json(std::string(text));
}

}  // namespace csgtile::config::detail
