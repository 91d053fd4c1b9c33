#include "csgtile/config/config.h"

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cstdio>
#include <exception>
#include <memory>
#include <string>
#include <system_error>

#include "document.h"
#include "schema_text.h"

namespace csgtile::config {
namespace {

using nlohmann::json;

constexpr std::string_view kBackendNames[] = {"sqlite", "postgres"};
constexpr std::string_view kLevelNames[] = {"trace", "debug", "info", "warn", "error"};
constexpr std::string_view kFormatNames[] = {"auto", "json", "text"};

/// Index of `name` in `names`; the schema's enum has already admitted only these names.
template <std::size_t N>
int index_of(const std::string& name, const std::string_view (&names)[N]) {
  for (std::size_t i = 0; i < N; ++i) {
    if (names[i] == name) return static_cast<int>(i);
  }
  return 0;
}

/// Reads `section.key` into `target` when present; the document is valid, so types match.
template <typename T>
void read(const json& document, const char* section, const char* key, T& target) {
  const auto found_section = document.find(section);
  if (found_section == document.end()) return;
  const auto found = found_section->find(key);
  if (found == found_section->end()) return;
  target = found->template get<T>();
}

template <typename Enum, std::size_t N>
void read_enum(const json& document, const char* section, const char* key,
               const std::string_view (&names)[N], Enum& target) {
  std::string name;
  read(document, section, key, name);
  if (!name.empty()) target = static_cast<Enum>(index_of(name, names));
}

Config from_document(const json& document) {
  Config config;
  read(document, "run", "name", config.run.name);
  read(document, "run", "inputs", config.run.inputs);
  read(document, "run", "output", config.run.output);
  read(document, "run", "seed", config.run.seed);
  read(document, "run", "threads", config.run.threads);
  read(document, "run", "crs", config.run.crs);
  read(document, "kernel", "linear_tolerance", config.kernel.linear_tolerance);
  read(document, "kernel", "chordal_tolerance", config.kernel.chordal_tolerance);
  read_enum(document, "queue", "backend", kBackendNames, config.queue.backend);
  read(document, "queue", "sqlite_path", config.queue.sqlite_path);
  read(document, "queue", "postgres_dsn", config.queue.postgres_dsn);
  read(document, "queue", "max_attempts", config.queue.max_attempts);
  read(document, "queue", "lease_seconds", config.queue.lease_seconds);
  read(document, "queue", "grace_seconds", config.queue.grace_seconds);
  read(document, "queue", "postgres_sslmode", config.queue.postgres_sslmode);
  read(document, "queue", "postgres_sslrootcert", config.queue.postgres_sslrootcert);
  read(document, "queue", "job_memory_mib", config.queue.job_memory_mib);
  read_enum(document, "log", "level", kLevelNames, config.log.level);
  read_enum(document, "log", "format", kFormatNames, config.log.format);
  read(document, "metrics", "listen", config.metrics.listen);
  read(document, "fetch", "schemes", config.fetch.schemes);
  read(document, "fetch", "connect_timeout_seconds", config.fetch.connect_timeout_seconds);
  read(document, "fetch", "timeout_seconds", config.fetch.timeout_seconds);
  read(document, "fetch", "low_speed_bytes_per_second", config.fetch.low_speed_bytes_per_second);
  read(document, "fetch", "low_speed_seconds", config.fetch.low_speed_seconds);
  read(document, "fetch", "max_bytes", config.fetch.max_bytes);
  read(document, "fetch", "max_redirects", config.fetch.max_redirects);
  read(document, "fetch", "attempts", config.fetch.attempts);
  read(document, "fetch", "ca_bundle", config.fetch.ca_bundle);
  read(document, "fetch", "cache_dir", config.fetch.cache_dir);
  read(document, "fetch", "s3_endpoint", config.fetch.s3_endpoint);
  read(document, "fetch", "s3_region", config.fetch.s3_region);
  read(document, "city", "cell_size", config.city.cell_size);
  read(document, "city", "halo", config.city.halo);
  read(document, "city", "split_points", config.city.split_points);
  read(document, "city", "voxel_size", config.city.voxel_size);
  read(document, "city", "snap_distance", config.city.snap_distance);
  read(document, "city", "snap_angle_degrees", config.city.snap_angle_degrees);
  read(document, "city", "snap_escalate_to", config.city.snap_escalate_to);
  read(document, "city", "building_timeout_seconds", config.city.building_timeout_seconds);
  read(document, "city", "footprints", config.city.footprints);
  read(document, "city", "footprints_layer", config.city.footprints_layer);
  read(document, "city", "footprints_id", config.city.footprints_id);
  detail::read_fit(document, config.fit);
  read(document, "publish", "url", config.publish.url);
  return config;
}

/// A top-level key that is a section of `fit:` (a fit options file of older versions, or a
/// section written one level too high) says where it belongs.
void hint_fit_sections(std::vector<Problem>& problems) {
  const json& fit = detail::schema_document().at("properties").at("fit").at("properties");
  for (Problem& p : problems) {
    if (p.path.find('.') == std::string::npos && fit.contains(p.path) &&
        p.message.starts_with("unknown key")) {
      p.message = "unknown key; fit options go under fit: (fit." + p.path + ")";
    }
  }
}

/// Problems tied to a line come first, in line order; then the others (environment, file),
/// each group in the order found.
void sort_problems(std::vector<Problem>& problems) {
  std::stable_sort(problems.begin(), problems.end(), [](const Problem& a, const Problem& b) {
    const int line_a = a.line == 0 ? INT_MAX : a.line;
    const int line_b = b.line == 0 ? INT_MAX : b.line;
    return line_a < line_b;
  });
}

}  // namespace

LoadResult load_string(std::string_view yaml, std::string_view source, const Environment& env) {
  LoadResult result;
  result.source = std::string(source);
  try {
    detail::Document document;
    detail::yaml_to_document(yaml, document, result.problems);
    detail::apply_environment(env, document, result.problems);
    detail::validate(document, result.problems);
    hint_fit_sections(result.problems);
    sort_problems(result.problems);
    for (const auto& [pointer, origin] : document.origins) {
      if (pointer.empty()) continue;
      const nlohmann::json::json_pointer at(pointer);
      if (document.json.contains(at)) {
        result.lines[detail::display_path(document.json, at)] = origin.line;
      }
    }
    if (result.problems.empty()) {
      Config config = from_document(document.json);
      // Rules between keys, which the schema cannot state.
      if (config.city.halo >= config.city.cell_size) {
        result.problems.push_back({"city.halo", 0,
                                   "must be smaller than city.cell_size (" +
                                       json(config.city.cell_size).dump() + "), got " +
                                       json(config.city.halo).dump()});
      } else {
        result.config = std::move(config);
      }
    }
  } catch (const std::exception& error) {
    // Nothing above should throw on any input; if it does, the caller still gets data.
    result.config.reset();
    result.problems.push_back({"", 0, std::string("internal error: ") + error.what()});
  } catch (...) {
    result.config.reset();
    result.problems.push_back({"", 0, "internal error"});
  }
  return result;
}

LoadResult load_file(const std::filesystem::path& path, const Environment& env) {
  const auto cannot_read = [&](int error_number) {
    LoadResult result;
    result.source = path.string();
    result.problems.push_back(
        {"", 0, "cannot read file: " + std::generic_category().message(error_number)});
    return result;
  };

  errno = 0;
  const std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "rb"),
                                                             &std::fclose);
  if (!file) return cannot_read(errno != 0 ? errno : EIO);
  std::string text;
  char buffer[1 << 14];
  for (;;) {
    const std::size_t count = std::fread(buffer, 1, sizeof buffer, file.get());
    text.append(buffer, count);
    if (count < sizeof buffer) break;
  }
  // A directory opens but does not read (EISDIR).
  if (std::ferror(file.get())) return cannot_read(errno != 0 ? errno : EIO);
  return load_string(text, path.string(), env);
}

std::string_view schema_json() { return detail::embedded_schema_text(); }

std::string to_json(const Config& config) {
  json out;
  out["run"] = {{"name", config.run.name},       {"inputs", config.run.inputs},
                {"output", config.run.output},   {"seed", config.run.seed},
                {"threads", config.run.threads}, {"crs", config.run.crs}};
  out["kernel"] = {{"linear_tolerance", config.kernel.linear_tolerance},
                   {"chordal_tolerance", config.kernel.chordal_tolerance}};
  out["queue"] = {{"backend", std::string(to_string(config.queue.backend))},
                  {"sqlite_path", config.queue.sqlite_path},
                  {"postgres_dsn", config.queue.postgres_dsn},
                  {"max_attempts", config.queue.max_attempts},
                  {"lease_seconds", config.queue.lease_seconds},
                  {"grace_seconds", config.queue.grace_seconds},
                  {"postgres_sslmode", config.queue.postgres_sslmode},
                  {"postgres_sslrootcert", config.queue.postgres_sslrootcert},
                  {"job_memory_mib", config.queue.job_memory_mib}};
  out["log"] = {{"level", std::string(to_string(config.log.level))},
                {"format", std::string(to_string(config.log.format))}};
  out["metrics"] = {{"listen", config.metrics.listen}};
  out["fetch"] = {{"schemes", config.fetch.schemes},
                  {"connect_timeout_seconds", config.fetch.connect_timeout_seconds},
                  {"timeout_seconds", config.fetch.timeout_seconds},
                  {"low_speed_bytes_per_second", config.fetch.low_speed_bytes_per_second},
                  {"low_speed_seconds", config.fetch.low_speed_seconds},
                  {"max_bytes", config.fetch.max_bytes},
                  {"max_redirects", config.fetch.max_redirects},
                  {"attempts", config.fetch.attempts},
                  {"ca_bundle", config.fetch.ca_bundle},
                  {"cache_dir", config.fetch.cache_dir},
                  {"s3_endpoint", config.fetch.s3_endpoint},
                  {"s3_region", config.fetch.s3_region}};
  out["city"] = {{"cell_size", config.city.cell_size},
                 {"halo", config.city.halo},
                 {"split_points", config.city.split_points},
                 {"voxel_size", config.city.voxel_size},
                 {"snap_distance", config.city.snap_distance},
                 {"snap_angle_degrees", config.city.snap_angle_degrees},
                 {"snap_escalate_to", config.city.snap_escalate_to},
                 {"building_timeout_seconds", config.city.building_timeout_seconds},
                 {"footprints", config.city.footprints},
                 {"footprints_layer", config.city.footprints_layer},
                 {"footprints_id", config.city.footprints_id}};
  out["fit"] = detail::fit_to_json(config.fit);
  out["publish"] = {{"url", config.publish.url}};
  // nlohmann::json sorts object keys and prints doubles in their shortest round-trip form, so
  // the bytes depend on the values only. Invalid UTF-8 (possible only through the
  // environment) is replaced rather than thrown on.
  return out.dump(-1, ' ', false, json::error_handler_t::replace);
}

std::string to_json(const FitConfig& fit) {
  return detail::fit_to_json(fit).dump(-1, ' ', false, json::error_handler_t::replace);
}

std::string format_problem(std::string_view source, const Problem& p) {
  std::string out(source);
  if (p.line > 0) {
    // Appended piecewise: `":" + std::to_string(...)` trips GCC 12's -Wrestrict false positive.
    out += ':';
    out += std::to_string(p.line);
  }
  if (!out.empty()) out += ": ";
  if (!p.path.empty()) out += p.path + ": ";
  out += p.message;
  return out;
}

namespace {
/// Name of an enum value; "?" for a value outside the enum (only reachable by a cast).
template <typename Enum, std::size_t N>
std::string_view name_of(Enum value, const std::string_view (&names)[N]) {
  const auto index = static_cast<std::size_t>(value);
  return index < N ? names[index] : std::string_view("?");
}
}  // namespace

std::string_view to_string(QueueBackend backend) { return name_of(backend, kBackendNames); }
std::string_view to_string(LogLevel level) { return name_of(level, kLevelNames); }
std::string_view to_string(LogFormat format) { return name_of(format, kFormatNames); }

}  // namespace csgtile::config
