// Done jobs' records and their timings (see job_records.h).

#include "job_records.h"

#include "csgtile/worker/publish.h"

namespace csgtile::worker {

namespace {
using nlohmann::ordered_json;
constexpr const char* kTimingsKey = "timings";
}  // namespace

ordered_json timings_json(const StageTimings& timings, double seconds, const std::string& worker_id,
                          int attempt, std::optional<double> peak_rss_mib) {
  ordered_json stages = ordered_json::object();
  for (const auto& [stage, s] : timings.seconds) stages[stage] = s;
  ordered_json out = {{"stages", stages}, {"seconds", seconds}};
  if (!worker_id.empty()) out["worker"] = worker_id;
  out["attempt"] = attempt;
  if (peak_rss_mib) out["peak_rss_mib"] = *peak_rss_mib;
  return out;
}

std::string with_timings(const std::string& result, const StageTimings& timings, double seconds,
                         const std::string& worker_id, int attempt,
                         std::optional<double> peak_rss_mib) {
  ordered_json record = ordered_json::parse(result, nullptr, false);
  if (!record.is_object()) return result;
  record[kTimingsKey] = timings_json(timings, seconds, worker_id, attempt, peak_rss_mib);
  return record.dump();
}

void JobRecords::add(const std::string& key, ordered_json record) {
  if (const auto t = record.find(kTimingsKey); t != record.end()) {
    ordered_json entry = {{"key", key}};
    entry.update(*t);
    timings.push_back(std::move(entry));
    record.erase(t);
  }
  jobs.push_back({{"key", key}, {"result", std::move(record)}});
}

bool is_job_of_run(const std::string& key, const std::string& run) {
  const std::size_t colon = key.find(':');
  return colon != std::string::npos && key.size() > colon + run.size() + 1 &&
         key.compare(colon + 1, run.size(), run) == 0 && key[colon + 1 + run.size()] == ':';
}

ordered_json dead_jobs_json(const std::vector<DeadJob>& dead) {
  ordered_json out = ordered_json::array();
  for (const DeadJob& d : dead) {
    out.push_back({{"key", d.key}, {"attempts", d.attempts}, {"error", d.last_error}});
  }
  return out;
}

Failure write_timings(const std::filesystem::path& run_dir, const std::string& run,
                      const JobRecords& records) {
  const ordered_json file = {
      {"run", run},
      {"note",
       "wall-clock seconds of the attempt that produced each job's result; not "
       "deterministic, unlike manifest.json"},
      {"jobs", records.timings}};
  return write_file_atomic(run_dir / "timings.json", file.dump(2) + "\n");
}

}  // namespace csgtile::worker
