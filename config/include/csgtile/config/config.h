#pragma once
/// \file
/// The csgtile configuration: YAML text → validated plain structs.
///
/// The structs below are the single source of defaults; config/schema/csgtile.schema.json
/// describes every key (and its "default" values are checked against these structs by the
/// tests). config/examples/csgtile.yaml shows every key with a comment.

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "csgtile/config/fit_config.h"

namespace csgtile::config {

/// `run:` — what to process and where to write it.
struct RunConfig {
  std::string name = "csgtile";     ///< [A-Za-z0-9_-]{1,64}
  std::vector<std::string> inputs;  ///< paths or URLs, each non-empty
  std::string output = "out";       ///< output directory, non-empty
  std::uint64_t seed = 1;           ///< 0..2^53
  int threads = 0;                  ///< 0 = all cores; 0..1024
  /// CRS of the run's tiles: "" takes each tile's own; else "EPSG:N", "EPSG:N+V" (with a
  /// vertical CRS) or WKT, for tiles that carry none. A tile whose own CRS differs fails.
  std::string crs;
  bool operator==(const RunConfig&) const = default;
};

/// `kernel:` — tolerances in metres.
struct KernelConfig {
  double linear_tolerance = 1.0e-7;  ///< (0, 1e-2]
  double chordal_tolerance = 0.01;   ///< [1e-6, 10]; mesh chordal error
  bool operator==(const KernelConfig&) const = default;
};

enum class QueueBackend { Sqlite, Postgres };

/// `queue:` — the job queue.
struct QueueConfig {
  QueueBackend backend = QueueBackend::Sqlite;
  std::string sqlite_path;   ///< empty means <run.output>/queue.sqlite
  std::string postgres_dsn;  ///< used when backend is Postgres
  int max_attempts = 5;      ///< 1..100
  int lease_seconds = 60;    ///< 1..86400
  /// 0..86400: after SIGTERM/SIGINT, how long the running job may go on; a job still running
  /// then is released (queued again, no attempt used) and the worker exits 0. The default fits
  /// Kubernetes' default terminationGracePeriodSeconds (30) with room to exit.
  int grace_seconds = 25;
  /// libpq sslmode (disable … verify-full); empty keeps the DSN's (libpq default: prefer).
  std::string postgres_sslmode;
  std::string postgres_sslrootcert;  ///< CA file for verify-ca/verify-full; empty keeps the DSN's
  /// 0..1048576 MiB, 0 for none: a job whose process's resident memory goes over it is asked
  /// to stop (at its next cancellation point) and fails with resource_limit, not retried.
  int job_memory_mib = 0;
  bool operator==(const QueueConfig&) const = default;
};

enum class LogLevel { Trace, Debug, Info, Warn, Error };
/// Auto is text on a terminal, JSON otherwise.
enum class LogFormat { Auto, Json, Text };

/// `log:` — logging.
struct LogConfig {
  LogLevel level = LogLevel::Info;
  LogFormat format = LogFormat::Auto;
  bool operator==(const LogConfig&) const = default;
};

/// `metrics:` — the worker's HTTP endpoint (/healthz, /readyz, /metrics).
struct MetricsConfig {
  /// "HOST:PORT" (e.g. "127.0.0.1:9464"; "[::1]:PORT"; ":PORT" is loopback); "" or "off"
  /// disables it. Checked when the worker starts; `--metrics-listen` overrides it.
  std::string listen;
  bool operator==(const MetricsConfig&) const = default;
};

/// `fetch:` — how inputs named by URL (file://, http(s)://, s3://) are downloaded.
struct FetchConfig {
  std::vector<std::string> schemes{"file", "http", "https", "s3"};  ///< allowed URL schemes
  int connect_timeout_seconds = 10;                                 ///< 1..600
  int timeout_seconds = 600;                                        ///< whole transfer; 1..86400
  int low_speed_bytes_per_second = 1024;  ///< abort when slower than this ... (0 = never)
  int low_speed_seconds = 30;             ///< ... for this long; 1..3600
  std::uint64_t max_bytes = 8589934592;   ///< size cap of one download; 1..2^53
  int max_redirects = 5;                  ///< 0..20
  int attempts = 3;                       ///< tries of a transient failure within one job; 1..10
  std::string ca_bundle;                  ///< CA file for https; empty = the system's
  std::string cache_dir;                  ///< empty means <run.output>/cache
  std::string s3_endpoint;                ///< empty = https://s3.<region>.amazonaws.com
  std::string s3_region = "us-east-1";
  bool operator==(const FetchConfig&) const = default;
};

/// `city:` — how a run of LIDAR tiles becomes a city (DESIGN.md §1): one `fit` job per tile,
/// one `assemble` job per output cell (its primitives plus a halo), one `index` job per run.
struct CityConfig {
  double cell_size = 250.0;  ///< output cell edge, CRS units; (0, 1e6]
  /// Band around a cell whose primitives are read with it; an object reaching past it is
  /// reported. [0, cell_size)
  double halo = 50.0;
  /// A LAS/LAZ tile whose header declares more points than this is fitted in parts: one fit
  /// job per block of cells (as many cells as hold about this many points by the header's
  /// density), each streaming the file and keeping its block grown by the halo, so that a
  /// fit's memory follows this bound rather than the tile's size; 0: never. COPC inputs are
  /// always fitted per cell. [0, 1e12]
  std::uint64_t split_points = 10'000'000;
  double voxel_size = 0.5;  ///< OpenVDB culling voxel edge (m); (0, 100]
  /// Fuzzy mode of the assembly for fitted primitives (kernel/snap.h): plane faces this close
  /// (m) become one plane, axes this close (degrees) one direction; 0: off. [0, 1], [0, 10]
  double snap_distance = 0.005;
  double snap_angle_degrees = 0.5;
  /// Escalation (AssemblyOptions::escalate_to): objects whose fuse fails snapped again at
  /// growing distances up to this bound (m); 0: off. [0, 1]
  double snap_escalate_to = 0.02;
  /// Time limit of one building's (object's) fuse, escalation included, seconds: a building
  /// that reaches it keeps its LoD1.2 block, the limit named as the reason (the outputs of a
  /// run where one is reached depend on the machine's speed); 0: none. [0, 86400]
  double building_timeout_seconds = 60.0;
  /// Building footprints (optional): a path, an http(s) URL or a GDAL connection string of
  /// any vector source GDAL/OGR reads, reprojected to the run's CRS. With them, one building
  /// per footprint, standing exactly on it; building points outside every footprint still
  /// make buildings, with outlines derived from the points. "": none.
  std::string footprints{};
  std::string footprints_layer{};  ///< its layer; "": the source's only layer
  /// The attribute carried to every output as the building's id; "": the feature id.
  std::string footprints_id{};
  bool operator==(const CityConfig&) const = default;
};

/// `publish:` — where a finished run is published besides the local output directory.
struct PublishConfig {
  /// "s3://bucket/prefix": objects, then create-only manifests, then a pointer; "" = local only.
  std::string url;
  bool operator==(const PublishConfig&) const = default;
};

/// A whole configuration. A default-constructed Config is what an empty file gives.
struct Config {
  RunConfig run;
  KernelConfig kernel;
  QueueConfig queue;
  LogConfig log;
  MetricsConfig metrics;
  FetchConfig fetch;
  CityConfig city;
  FitConfig fit;  ///< `fit:` (fit_config.h)
  PublishConfig publish;
  bool operator==(const Config&) const = default;
};

/// One problem found in a config: the key path ("queue.max_attempts", "run.inputs[1]"; empty
/// when about the whole text), the 1-based line (0 when not tied to a line, e.g. an
/// environment override or an unreadable file), and what is wrong.
struct Problem {
  std::string path;
  int line = 0;
  std::string message;
  bool operator==(const Problem&) const = default;
};

/// Environment as name -> value; `from_process_environment()` reads `environ`.
///
/// Overrides: a variable `CSGTILE_<SECTION>__<KEY>` (segments joined by `__`, names
/// case-insensitive) sets `<section>.<key>`, e.g. `CSGTILE_QUEUE__MAX_ATTEMPTS=3`;
/// `CSGTILE_RUN__INPUTS` is a comma-separated list. Overrides win over the file and are
/// validated like it. Any `CSGTILE_` variable containing `__` is an override, and an unknown
/// section or key is a problem; `CSGTILE_` variables without `__` (e.g. `CSGTILE_LOG_LEVEL`,
/// or variables read by the tools) are ignored here.
using Environment = std::map<std::string, std::string>;
Environment from_process_environment();

/// Outcome of a load: a Config when there is no problem, else every problem found, ordered
/// by line (problems without a line last).
struct LoadResult {
  std::optional<Config> config;
  std::vector<Problem> problems;
  std::string source;  ///< the `source` / path given to the load, for format_problem
  /// Line of each value by its display path ("run.crs", "run.inputs[1]"), for problems that
  /// checks after the load (e.g. the worker's, on inputs and CRSs) find; 0 when it came from
  /// the environment.
  std::map<std::string, int> lines;
  bool ok() const { return config.has_value() && problems.empty(); }
  /// The line of `path`, or 0.
  int line_of(const std::string& path) const {
    const auto it = lines.find(path);
    return it == lines.end() ? 0 : it->second;
  }
};

/// Parses YAML text, applies environment overrides, validates against the schema, and
/// converts to Config. Never throws. `source` names the text in messages (the file path).
///
/// An empty text (or only comments) is a valid config with all defaults; a section written
/// with no value (`queue:`) is an empty section. Unknown and duplicate keys, wrong types,
/// out-of-range and bad enum values are all reported, not only the first. Thread-safe.
LoadResult load_string(std::string_view yaml, std::string_view source, const Environment& env = {});
/// Reads `path` and calls load_string with the path as source. A file that cannot be read is
/// one problem ("cannot read file: No such file or directory").
LoadResult load_file(const std::filesystem::path& path, const Environment& env = {});

/// The JSON Schema (draft-07) text shipped in config/schema, embedded at build time.
std::string_view schema_json();

/// Config rendered back as canonical JSON (all keys, defaults filled; keys sorted, no
/// whitespace) — for logs/manifests and for hashing. The same config gives the same bytes,
/// and loading the output gives the same config back.
std::string to_json(const Config& config);
/// The `fit:` section alone, in the same canonical form (a fit record's options hash).
std::string to_json(const FitConfig& fit);

/// One-line rendering: "file.yaml:12: queue.max_attmpts: unknown key (did you mean
/// max_attempts?)". The line is left out when 0, the path when empty.
std::string format_problem(std::string_view source, const Problem& p);

/// Names as written in the config ("sqlite", "info", "auto").
std::string_view to_string(QueueBackend backend);
std::string_view to_string(LogLevel level);
std::string_view to_string(LogFormat format);

}  // namespace csgtile::config
