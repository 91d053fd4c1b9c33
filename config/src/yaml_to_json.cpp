#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <string>
#include <string_view>
#include <vector>

#include "document.h"

namespace csgtile::config::detail {
namespace {

using nlohmann::json;

/// yaml-cpp marks are 0-based and -1 when unknown; ours are 1-based and 0 when unknown.
int line_of(const YAML::Mark& mark) { return mark.line < 0 ? 0 : mark.line + 1; }

std::string kind_of(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Sequence:
      return "a list";
    case YAML::NodeType::Map:
      return "a mapping";
    case YAML::NodeType::Scalar:
      return "a scalar";
    default:
      return "nothing";
  }
}

/// Quoted scalars (tag "!") and explicit !!str are strings whatever they look like.
bool is_string_tagged(const YAML::Node& node) {
  return node.Tag() == "!" || node.Tag() == "tag:yaml.org,2002:str";
}

/// A configuration is three levels deep; these bounds only stop hostile input (an alias
/// that contains itself, "billion laughs" alias fan-out, deep nesting) from exhausting the
/// stack or memory while converting.
constexpr std::size_t kMaxDepth = 32;
constexpr std::size_t kMaxValues = 100000;

/// Walks the YAML tree into JSON. yaml-cpp 0.7 keeps every pair of a mapping, duplicates
/// included, in document order, so duplicates are found here: the first occurrence is kept
/// (as yaml-cpp's own lookup does) and each later one is a problem.
class Converter {
 public:
  Converter(Document& document, std::vector<Problem>& problems)
      : document_(document), problems_(problems) {}

  void convert(const YAML::Node& node, const json::json_pointer& pointer, const std::string& path,
               json& out) {
    if (stopped_) return;
    for (const YAML::Node& ancestor : ancestors_) {
      if (ancestor.is(node)) {
        problems_.push_back({path, line_of(node.Mark()), "an alias refers to itself"});
        return;
      }
    }
    if (ancestors_.size() >= kMaxDepth || ++values_ > kMaxValues) {
      problems_.push_back(
          {path, line_of(node.Mark()),
           ancestors_.size() >= kMaxDepth ? "nested too deep" : "too many values (aliases?)"});
      stopped_ = true;
      return;
    }
    ancestors_.push_back(node);
    convert_node(node, pointer, path, out);
    ancestors_.pop_back();
  }

 private:
  void convert_node(const YAML::Node& node, const json::json_pointer& pointer,
                    const std::string& path, json& out) {
    switch (node.Type()) {
      case YAML::NodeType::Null:
        // A section written without a value (`queue:`, e.g. all its keys commented out) is an
        // empty section; anywhere else null is a value the schema will reject.
        out = schema_type(schema_at(pointer)) == "object" ? json::object() : json(nullptr);
        return;
      case YAML::NodeType::Scalar:
        out = is_string_tagged(node) ? json(node.Scalar())
                                     : plain_scalar_to_json(node.Scalar(), schema_at(pointer));
        return;
      case YAML::NodeType::Sequence:
        out = json::array();
        for (std::size_t i = 0; i < node.size(); ++i) {
          const YAML::Node item = node[i];
          const json::json_pointer item_pointer = pointer / i;
          document_.origins[item_pointer.to_string()] = Origin{line_of(item.Mark()), {}};
          out.push_back(nullptr);
          convert(item, item_pointer, path + "[" + std::to_string(i) + "]", out.back());
        }
        return;
      case YAML::NodeType::Map:
        convert_map(node, pointer, path, out);
        return;
      case YAML::NodeType::Undefined:
        return;
    }
  }

  void convert_map(const YAML::Node& node, const json::json_pointer& pointer,
                   const std::string& path, json& out) {
    out = json::object();
    for (const auto& pair : node) {
      const YAML::Node& key = pair.first;
      const int key_line = line_of(key.Mark());
      if (!key.IsScalar()) {
        problems_.push_back({path, key_line, "keys must be plain names, got " + kind_of(key)});
        continue;
      }
      const std::string& name = key.Scalar();
      const json::json_pointer child = pointer / name;
      const std::string child_path = path.empty() ? name : path + "." + name;
      if (out.contains(name)) {
        const int first_line = document_.origins[child.to_string()].line;
        problems_.push_back({child_path, key_line,
                             "duplicate key (first on line " + std::to_string(first_line) + ")"});
        continue;
      }
      document_.origins[child.to_string()] = Origin{key_line, {}};
      convert(pair.second, child, child_path, out[name]);
    }
  }

  Document& document_;
  std::vector<Problem>& problems_;
  std::vector<YAML::Node> ancestors_;
  std::size_t values_ = 0;
  bool stopped_ = false;
};

}  // namespace

void yaml_to_document(std::string_view yaml, Document& document, std::vector<Problem>& problems) {
  // yaml-cpp stops reading at a NUL byte and would accept the part before it.
  if (const std::size_t nul = yaml.find('\0'); nul != std::string_view::npos) {
    const auto line =
        1 + std::count(yaml.begin(), yaml.begin() + static_cast<std::ptrdiff_t>(nul), '\n');
    problems.push_back(
        {"", static_cast<int>(line), "the text contains a NUL byte (not a YAML file?)"});
    return;
  }
  std::vector<YAML::Node> documents;
  try {
    documents = YAML::LoadAll(std::string(yaml));
  } catch (const YAML::Exception& error) {
    problems.push_back({"", line_of(error.mark), "YAML syntax error: " + error.msg});
    return;
  }
  if (documents.empty()) return;  // empty text or only comments: all defaults
  if (documents.size() > 1) {
    problems.push_back({"", line_of(documents[1].Mark()),
                        "expected one YAML document, found " + std::to_string(documents.size())});
  }
  const YAML::Node& root = documents.front();
  if (root.IsNull()) return;
  if (!root.IsMap()) {
    std::string sections;
    for (const std::string& name : property_names(schema_document())) {
      sections += sections.empty() ? name : ", " + name;
    }
    problems.push_back(
        {"", line_of(root.Mark()),
         "the top level must be a mapping of sections (" + sections + "), got " + kind_of(root)});
    return;
  }
  Converter(document, problems).convert(root, nlohmann::json::json_pointer(), "", document.json);
}

}  // namespace csgtile::config::detail
