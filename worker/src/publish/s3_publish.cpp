#include "publish/s3_publish.h"

#include <algorithm>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "csgtile/worker/files.h"
#include "csgtile/worker/publish.h"
#include "ops/metrics.h"

namespace csgtile::worker::publish {
namespace {

namespace fs = std::filesystem;

// A name as it may appear in a message: control characters escaped, length bounded, so a
// hostile path cannot forge log lines.
std::string printable(std::string_view text) {
  std::string out;
  for (const char ch : text.substr(0, 200)) {
    const auto c = static_cast<unsigned char>(ch);
    if (c < 0x20 || c == 0x7f) {
      static constexpr char kHex[] = "0123456789abcdef";
      out += "\\x";
      out.push_back(kHex[c >> 4]);
      out.push_back(kHex[c & 15]);
    } else {
      out.push_back(ch);
    }
  }
  if (text.size() > 200) out += "…";
  return out;
}

struct Location {
  std::string bucket;
  std::string prefix;  // a safe key, or empty

  std::string key(const std::string& relative) const {
    return prefix.empty() ? relative : prefix + "/" + relative;
  }
  std::string url(const std::string& relative) const {
    return "s3://" + bucket + "/" + key(relative);
  }
};

Failure parse_location(const std::string& s3_prefix, Location& location) {
  constexpr std::string_view kScheme = "s3://";
  if (s3_prefix.rfind(kScheme, 0) != 0) {
    return {ErrorCode::InputInvalid, "publish prefix '" + printable(s3_prefix) +
                                         "' is not of the form s3://bucket[/prefix]"};
  }
  std::string rest = s3_prefix.substr(kScheme.size());
  if (!rest.empty() && rest.back() == '/') rest.pop_back();
  const std::size_t slash = rest.find('/');
  location.bucket = rest.substr(0, slash);
  location.prefix = slash == std::string::npos ? std::string() : rest.substr(slash + 1);
  const bool bucket_ok =
      location.bucket.size() >= 3 && location.bucket.size() <= 63 &&
      std::all_of(location.bucket.begin(), location.bucket.end(), [](unsigned char c) {
        return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '-' || c == '.';
      });
  if (!bucket_ok) {
    return {ErrorCode::InputInvalid, "publish prefix '" + printable(s3_prefix) + "': '" +
                                         printable(location.bucket) +
                                         "' is not a valid bucket name"};
  }
  if (slash != std::string::npos && !is_safe_key(location.prefix)) {
    return {ErrorCode::InputInvalid,
            "publish prefix '" + printable(s3_prefix) + "': unsafe key prefix '" +
                printable(location.prefix) +
                "' (no '..', '.', empty segments or characters outside [A-Za-z0-9._-])"};
  }
  return {};
}

Failure check_run_name(const std::string& run_name) {
  if (!is_safe_key(run_name) || run_name.find('/') != std::string::npos) {
    return {ErrorCode::InputInvalid, "unsafe run name '" + printable(run_name) +
                                         "' (one segment of [A-Za-z0-9._-], not '.' or '..')"};
  }
  return {};
}

// A file of the plan, hashed, with the key of its content-addressed object.
struct LocalFile {
  std::string path;   // relative, as in the plan
  fs::path resolved;  // canonical, inside the root
  std::string sha256;
  std::uint64_t size = 0;
  std::string object_key;  // relative to the publication prefix
};

// ".glb" for "tiles/model.glb", ".jsonl" for "model.city.jsonl", "" when there is none. The
// path is already a safe key, so the extension is too.
std::string extension_of(const std::string& path) {
  const std::string name = path.substr(path.rfind('/') + 1);
  const std::size_t dot = name.rfind('.');
  if (dot == std::string::npos || dot == 0 || dot + 1 == name.size() || name.size() - dot > 16)
    return {};
  return name.substr(dot);
}

Failure resolve_file(const fs::path& root, const std::string& path, LocalFile& file) {
  if (!is_safe_key(path)) {
    return {ErrorCode::InputInvalid, "unsafe relative path '" + printable(path) +
                                         "' in the publish plan (no '..', leading '/', empty or "
                                         "'.' segments, control characters "
                                         "or characters outside [A-Za-z0-9._-])"};
  }
  std::error_code ec;
  file.path = path;
  file.resolved = fs::canonical(root / path, ec);
  if (ec) return {ErrorCode::Io, "cannot resolve " + (root / path).string() + ": " + ec.message()};
  const fs::path inside = file.resolved.lexically_relative(root);
  if (inside.empty() || *inside.begin() == "..") {
    return {ErrorCode::InputInvalid, "'" + path + "' resolves to " + file.resolved.string() +
                                         ", outside the run directory " + root.string()};
  }
  if (!fs::is_regular_file(file.resolved, ec)) {
    return {ErrorCode::InputInvalid, "'" + path + "' in the publish plan is not a regular file"};
  }
  if (Failure f = file_sha256(file.resolved, file.sha256, file.size); !f.ok()) return f;
  file.object_key = "objects/" + file.sha256 + extension_of(path);
  return {};
}

Failure conflict(const std::string& url, const std::string& what) {
  return {ErrorCode::ResultInvalid, "publish conflict: " + url + " " + what +
                                        "; published keys are create-only and never overwritten"};
}

// Reads the bytes at `url` when it exists with exactly `expected_size` bytes (HEAD, then a GET
// capped at that size): `same` tells whether they equal `bytes`.
Failure compare_existing(const std::string& url, std::string_view bytes,
                         const fetch::Policy& policy, bool& exists, bool& same) {
  fetch::S3Object head;
  if (Failure f = fetch::s3_head(url, policy, head); !f.ok()) return f;
  exists = head.exists;
  same = false;
  if (!exists || head.size != bytes.size()) return {};
  fetch::Policy capped = policy;
  capped.max_bytes = bytes.size();
  fetch::S3Object got;
  std::string stored;
  if (Failure f = fetch::s3_get(url, capped, got, stored); !f.ok()) return f;
  exists = got.exists;
  same = got.exists && stored == bytes;
  return {};
}

Failure put(const std::string& url, std::string_view bytes, const fetch::Policy& policy,
            PublishReport& report) {
  if (Failure f = fetch::s3_put(url, bytes, policy); !f.ok()) return f;
  report.bytes += bytes.size();
  ops::metrics().add_bytes_published(bytes.size());
  return {};
}

// Step (2): a manifest at a content-addressed key, created only when absent.
Failure create_only(const std::string& url, std::string_view bytes, const fetch::Policy& policy,
                    PublishReport& report) {
  bool exists = false;
  bool same = false;
  if (Failure f = compare_existing(url, bytes, policy, exists, same); !f.ok()) return f;
  if (exists && same) {
    ++report.skipped_existing;
    return {};
  }
  if (exists) return conflict(url, "already exists with different bytes");
  if (Failure f = put(url, bytes, policy, report); !f.ok()) return f;
  ++report.uploaded;
  return {};
}

// Step (1): one content-addressed object, uploaded unless HEAD finds it.
Failure upload_object(const Location& location, const LocalFile& file, const fetch::Policy& policy,
                      PublishReport& report) {
  const std::string url = location.url(file.object_key);
  fetch::S3Object head;
  if (Failure f = fetch::s3_head(url, policy, head); !f.ok()) return f;
  if (head.exists && head.size == file.size) {
    ++report.skipped_existing;
    return {};
  }
  if (head.exists) {
    return conflict(url, "exists with " + std::to_string(head.size) +
                             " bytes, but its content (SHA-256 " + file.sha256 + ") has " +
                             std::to_string(file.size));
  }
  std::string bytes;
  if (Failure f = read_file_bytes(file.resolved, bytes); !f.ok()) return f;
  if (bytes.size() != file.size || sha256_hex(bytes) != file.sha256) {
    return {ErrorCode::Io, file.resolved.string() + " changed while it was being published"};
  }
  if (Failure f = put(url, bytes, policy, report); !f.ok()) return f;
  ++report.uploaded;
  return {};
}

std::string scope_of(const std::string& manifest_path) {
  const std::size_t slash = manifest_path.rfind('/');
  return slash == std::string::npos ? std::string() : manifest_path.substr(0, slash);
}

bool in_scope(const std::string& path, const std::string& scope) {
  return scope.empty() || (path.size() > scope.size() &&
                           path.compare(0, scope.size(), scope) == 0 && path[scope.size()] == '/');
}

nlohmann::json file_entries(const std::vector<LocalFile>& files, const std::string& scope) {
  nlohmann::json entries = nlohmann::json::object();
  for (const LocalFile& f : files) {
    if (!in_scope(f.path, scope)) continue;
    entries[f.path] = {{"key", f.object_key}, {"sha256", f.sha256}, {"size", f.size}};
  }
  return entries;
}

std::string document(const nlohmann::json& json) { return json.dump(2) + "\n"; }

}  // namespace

Failure plan_run_directory(const std::filesystem::path& root, PublishPlan& plan) {
  plan = {};
  plan.root = root;
  std::vector<std::string> paths;
  std::error_code ec;
  fs::recursive_directory_iterator it(root, ec);
  for (; !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.front() == '.') {
      if (it->is_directory(ec)) it.disable_recursion_pending();
      continue;
    }
    if (it->is_regular_file(ec))
      paths.push_back(it->path().lexically_relative(root).generic_string());
  }
  if (ec)
    return {ErrorCode::Io, "cannot list the run directory " + root.string() + ": " + ec.message()};
  std::sort(paths.begin(), paths.end());
  bool has_run_manifest = false;
  for (const std::string& path : paths) {
    if (path == "manifest.json") {
      has_run_manifest = true;
    } else if (path.size() > 14 && path.compare(path.size() - 14, 14, "/manifest.json") == 0) {
      plan.manifests.push_back(path);
    } else {
      plan.objects.push_back(path);
    }
  }
  if (!has_run_manifest) {
    return {ErrorCode::InputInvalid, "run directory " + root.string() + " has no manifest.json"};
  }
  plan.manifests.push_back("manifest.json");
  return {};
}

Failure pointer_key(const std::string& s3_prefix, const std::string& run_name, std::string& key) {
  Location location;
  if (Failure f = parse_location(s3_prefix, location); !f.ok()) return f;
  if (Failure f = check_run_name(run_name); !f.ok()) return f;
  key = location.key("runs/" + run_name + "/CURRENT");
  return {};
}

Failure publish_run_to_s3(const PublishPlan& plan, const std::string& s3_prefix,
                          const std::string& run_name, const fetch::Policy& policy,
                          PublishReport& report) {
  report = {};
  // ---- everything checked and hashed before the first request ----
  Location location;
  if (Failure f = parse_location(s3_prefix, location); !f.ok()) return f;
  if (Failure f = check_run_name(run_name); !f.ok()) return f;
  if (plan.manifests.empty()) {
    return {ErrorCode::InputInvalid, "publish plan for run '" + run_name + "' names no manifest"};
  }
  std::error_code ec;
  const fs::path root = fs::canonical(plan.root, ec);
  if (ec || !fs::is_directory(root, ec)) {
    return {ErrorCode::Io, "run directory " + plan.root.string() + " is not a readable directory"};
  }
  std::vector<LocalFile> files;  // objects, then manifests, in plan order
  std::set<std::string> seen;
  for (const std::vector<std::string>* list : {&plan.objects, &plan.manifests}) {
    for (const std::string& path : *list) {
      LocalFile file;
      if (Failure f = resolve_file(root, path, file); !f.ok()) return f;
      if (!seen.insert(path).second) {
        return {ErrorCode::InputInvalid, "'" + path + "' is listed twice in the publish plan"};
      }
      files.push_back(std::move(file));
    }
  }
  const std::string run_dir = "runs/" + run_name;

  // ---- (1) content-addressed objects; equal contents share one key, visited in key order ----
  std::map<std::string, const LocalFile*> by_key;
  for (const LocalFile& f : files) by_key.emplace(f.object_key, &f);
  for (const auto& [key, file] : by_key) {
    if (Failure f = upload_object(location, *file, policy, report); !f.ok()) return f;
  }

  // ---- (2) publication manifests: cells first, the run last ----
  auto local_of = [&](const std::string& path) -> const LocalFile& {
    return *std::find_if(files.begin(), files.end(),
                         [&](const LocalFile& f) { return f.path == path; });
  };
  nlohmann::json cells = nlohmann::json::array();
  std::string run_manifest_key;
  std::string run_manifest_sha;
  for (std::size_t i = 0; i < plan.manifests.size(); ++i) {
    const bool is_run = i + 1 == plan.manifests.size();
    const LocalFile& local = local_of(plan.manifests[i]);
    const std::string scope = is_run ? std::string() : scope_of(local.path);
    nlohmann::json manifest = {{"format", "csgtile.publication/1"},
                               {"run", run_name},
                               {"scope", scope},
                               {"local_manifest", local.path},
                               {"files", file_entries(files, scope)}};
    if (is_run) manifest["cells"] = cells;
    const std::string bytes = document(manifest);
    const std::string sha = sha256_hex(bytes);
    const std::string key = run_dir + "/manifests/" + sha + ".json";
    if (Failure f = create_only(location.url(key), bytes, policy, report); !f.ok()) return f;
    if (is_run) {
      run_manifest_key = key;
      run_manifest_sha = sha;
    } else {
      cells.push_back(
          {{"local_manifest", local.path}, {"scope", scope}, {"key", key}, {"sha256", sha}});
    }
  }
  report.manifest_key = location.key(run_manifest_key);

  // ---- (3) the pointer, last, and only when it changes ----
  const std::string pointer = document({{"format", "csgtile.pointer/1"},
                                        {"run", run_name},
                                        {"manifest", run_manifest_key},
                                        {"sha256", run_manifest_sha}});
  const std::string pointer_url = location.url(run_dir + "/CURRENT");
  bool exists = false;
  bool same = false;
  if (Failure f = compare_existing(pointer_url, pointer, policy, exists, same); !f.ok()) return f;
  if (!same) {
    if (Failure f = put(pointer_url, pointer, policy, report); !f.ok()) return f;
    report.pointer_changed = true;
  }
  report.pointer_key = location.key(run_dir + "/CURRENT");
  return {};
}

}  // namespace csgtile::worker::publish
