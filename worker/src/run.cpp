#include "csgtile/worker/run.h"

#include <unistd.h>

#include <tbb/task_arena.h>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <functional>
#include <future>
#include <nlohmann/json.hpp>
#include <optional>
#include <stop_token>
#include <thread>

#include "city/city_jobs.h"
#include "csgtile/assembly/voxel_cull.h"
#include "csgtile/geo/scene.h"
#include "csgtile/kernel/boolean.h"
#include "csgtile/kernel/check.h"
#include "csgtile/kernel/csg.h"
#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/mass_properties.h"
#include "csgtile/kernel/native_format.h"
#include "csgtile/worker/publish.h"
#include "export/cityjson_seq.h"
#include "export/manifest.h"
#include "export/run_index.h"
#include "export/tileset.h"
#include "export_settings.h"
#include "fetch/fetch.h"
#include "fetch/input.h"
#include "job_records.h"
#include "jobs/job_table.h"
#include "ops/memory.h"
#include "ops/metrics.h"
#include "ops/stage_clock.h"
#include "publish/publish_run.h"
#include "queue/heartbeat.h"
#include "stop_signal.h"

namespace csgtile::worker {

namespace {
using nlohmann::ordered_json;
}  // namespace

namespace {
/// A run of LIDAR tiles is a city run (city/city_jobs.h); a run of scenes builds each scene.
bool is_city_run(const config::Config& config) {
  return std::any_of(config.run.inputs.begin(), config.run.inputs.end(), city::is_tile_input);
}
}  // namespace

Failure enqueue_run(const config::Config& config, JobQueue& queue, const Logger& log,
                    std::size_t& added) {
  Failure failure;
  added = 0;
  if (is_city_run(config)) {
    for (const std::string& input : config.run.inputs) {
      if (!city::is_tile_input(input)) {
        return {ErrorCode::ConfigInvalid,
                "run.inputs mixes point-cloud tiles and scene files (" + input +
                    "): a run is either a city of tiles or a set of scenes; use two runs"};
      }
    }
    if (Failure f = city::enqueue_fits(config, queue, added); !f.ok()) return f;
    std::size_t next = 0;  // a run enqueued again after its fits finished goes on
    if (Failure f = city::advance_city_run(config, queue, log, next); !f.ok()) return f;
    added += next;
    log.info("run", "enqueued",
             {{"run", config.run.name},
              {"jobs", std::to_string(added)},
              {"queue", describe_queue(config)}});
    return failure;
  }
  for (const std::string& input : config.run.inputs) {
    const std::string key = "build:" + config.run.name + ":" + input;
    const std::string payload = nlohmann::json({{"input", input}}).dump();
    if (queue.enqueue(key, "build", payload, failure)) ++added;
    if (!failure.ok()) return failure;
  }
  log.info("run", "enqueued",
           {{"run", config.run.name},
            {"jobs", std::to_string(added)},
            {"queue", describe_queue(config)}});
  return failure;
}

namespace {
/// What one job's runner hands back to the work loop.
struct RunOutcome {
  Failure failure;
  std::string result;
  StageTimings timings;
};

/// Runs `job` on a thread of its own, so that the work loop can wait for it with a deadline
/// and ask it to stop through `stop` (its Booleans, assembly and fit return Cancelled).
/// The returned thread must be joined once the future is ready, or left to the process's end.
std::thread start_job(const Job& job, const std::filesystem::path& run_dir,
                      const config::Config& config, JobQueue& queue, const Logger& log,
                      const std::stop_token& stop, std::future<RunOutcome>& outcome) {
  std::packaged_task<RunOutcome()> task([job, run_dir, &config, &queue, &log, stop] {
    hold_stop_signals();  // delivered to the loop's threads, never interrupting the job's I/O
    const LogJobScope log_scope(config.run.name, job.key, job.attempts);  // thread-local
    RunOutcome out;
    const jobs::JobContext context{run_dir, config, queue, log, stop};
    // An exception out of a job (memory exhausted, a library's throw) fails that job with its
    // reason; the worker goes on with the next one.
    try {
      // Every parallel algorithm of the job (the LAZ decoder, the fit, the blocks, the
      // measures, the exports) in one arena of run.threads: the setting bounds the whole job.
      tbb::task_arena arena(config.run.threads > 0 ? config.run.threads
                                                   : tbb::task_arena::automatic);
      arena.execute([&] { out.failure = jobs::run_job(job, context, out.result, &out.timings); });
    } catch (const std::exception& e) {
      out.result.clear();
      out.failure = {ErrorCode::Internal, "job " + job.key + " threw: " + e.what()};
    }
    return out;
  });
  outcome = task.get_future();
  return std::thread(std::move(task));
}

/// Room, at the end of a grace period, to stop the job, release it and exit: a second, or a
/// quarter of a short grace period.
std::chrono::milliseconds grace_margin(std::chrono::seconds grace) {
  using namespace std::chrono_literals;
  return std::min<std::chrono::milliseconds>(1s, std::chrono::milliseconds(grace) / 4);
}

/// Waits until `outcome` is ready, or — once a stop signal came — until the grace period
/// measured from the signal, less its margin, has passed. Returns whether the job ended.
/// `each_poll` runs at every look (the memory bound's check).
bool wait_within_grace(const std::future<RunOutcome>& outcome, std::chrono::seconds grace,
                       const std::function<void()>& each_poll) {
  using namespace std::chrono_literals;
  // A signal handler cannot wake a waiting thread, so the flag is looked at this often.
  constexpr auto kPoll = 50ms;
  const std::chrono::milliseconds margin = grace_margin(grace);
  while (true) {
    auto until = std::chrono::steady_clock::now() + kPoll;
    if (const auto signalled = stop_requested_at()) {
      const auto deadline = *signalled + grace - margin;
      if (std::chrono::steady_clock::now() >= deadline) {
        return outcome.wait_for(0s) == std::future_status::ready;
      }
      until = std::min(until, deadline);
    }
    if (outcome.wait_until(until) == std::future_status::ready) return true;
    each_poll();
  }
}

/// queue.job_memory_mib, watched from the work loop: the first look that finds the process's
/// resident memory over the bound asks the job to stop and remembers what it saw.
class MemoryBound {
 public:
  MemoryBound(int limit_mib, std::stop_source& job_stop)
      : limit_(static_cast<std::uint64_t>(limit_mib) * kMiB), job_stop_(job_stop) {}
  void look() {
    if (limit_ == 0 || seen_ != 0) return;
    const auto resident = ops::resident_bytes();
    if (!resident || *resident <= limit_) return;
    seen_ = *resident;
    job_stop_.request_stop();
  }
  bool exceeded() const { return seen_ != 0; }
  Failure failure(const std::string& job) const {
    return {ErrorCode::ResourceLimit,
            "job " + job + " stopped: the worker's resident memory reached " +
                std::to_string(seen_ / kMiB) +
                " MiB, over queue.job_memory_mib = " + std::to_string(limit_ / kMiB)};
  }

 private:
  static constexpr std::uint64_t kMiB = 1024 * 1024;
  std::uint64_t limit_;
  std::stop_source& job_stop_;
  std::uint64_t seen_ = 0;
};
}  // namespace

Failure work_queue(const config::Config& config, JobQueue& queue, const Logger& log,
                   const WorkOptions& options, WorkSummary& work) {
  const std::filesystem::path run_dir =
      std::filesystem::path(config.run.output) / "runs" / config.run.name;
  const std::string worker_id =
      options.worker_id.empty() ? "local-" + std::to_string(getpid()) : options.worker_id;
  // Looked at once: it lists input directories, and the loop polls every few milliseconds.
  const bool city_run = is_city_run(config);
  // A city run's cells are assembled: the OpenVDB module the culling needs loads meanwhile.
  const std::jthread culling = city_run ? assembly::load_culling_in_background() : std::jthread();
  Failure failure;
  while (true) {
    ops::metrics().mark_progress();  // liveness (/healthz): the loop turns
    if (stop_requested()) {
      // Drain: nothing more is claimed; the queue keeps the rest.
      work.stopped = true;
      log.info("worker", "stopped by signal", {{"jobs", std::to_string(work.jobs)}});
      return failure;
    }
    auto job = queue.claim(worker_id, failure);
    if (!failure.ok()) return failure;
    if (!job) {
      const QueueCounts c = queue.counts(failure);
      if (!failure.ok()) return failure;
      if (c.unfinished() == 0) {
        // The next stage of a city run may be due (its enqueue lost to a crash, or not yet
        // made): enqueueing is idempotent, so every idle worker may try.
        std::size_t next = 0;
        if (city_run) {
          if (Failure f = city::advance_city_run(config, queue, log, next); !f.ok()) {
            // Logged, not fatal: the worker goes on (the run then ends without its next stage,
            // which status and the missing manifest show).
            log.error("run", "cannot advance the city run", {{"reason", f.message}});
          }
        }
        if (next > 0) continue;
        work.finished = true;
        if (options.exit_when_idle) return failure;
      } else {
        work.finished = false;
      }
      // Retries wait for their backoff; a running job of another process holds its lease.
      std::this_thread::sleep_for(options.poll);
      continue;
    }
    const auto start = std::chrono::steady_clock::now();
    ops::metrics().job_claimed(job->attempts);
    const LogJobScope log_scope(config.run.name, job->key, job->attempts);  // run/job in logs
    // The lease is renewed every third of its length while the job runs.
    LeaseHeartbeat heartbeat(queue, *job,
                             std::chrono::milliseconds(config.queue.lease_seconds * 1000 / 3));
    std::future<RunOutcome> outcome;
    std::stop_source job_stop;
    MemoryBound memory(config.queue.job_memory_mib, job_stop);
    ops::reset_peak_resident();  // the peak recorded for this job is its own
    std::thread runner =
        start_job(*job, run_dir, config, queue, log, job_stop.get_token(), outcome);
    const std::chrono::seconds grace(config.queue.grace_seconds);
    std::optional<RunOutcome> ran;  // once the job's thread has returned
    bool asked_to_stop = false;
    if (wait_within_grace(outcome, grace, [&memory] { memory.look(); })) {
      runner.join();
      ran = outcome.get();
    } else {
      // Stopped, and the job does not fit the grace period: it is asked to stop (its
      // Booleans, assembly and fit return Cancelled at their next step) and given half the
      // margin to return.
      job_stop.request_stop();
      asked_to_stop = true;
      if (outcome.wait_for(grace_margin(grace) / 2) == std::future_status::ready) {
        runner.join();
        ran = outcome.get();
      }
    }
    // A job asked to stop that did not finish (Cancelled, or still running) goes back to the
    // queue without using an attempt. Returned, its thread is gone and the worker returns
    // through main; still running, the process ends now, its job's thread with it. The
    // outputs a job may have begun are temporary files renamed only when complete, so none
    // is partial.
    if (asked_to_stop && !(ran && ran->failure.ok())) {
      heartbeat.stop();
      Failure released_failure;
      const bool released = queue.release(*job, released_failure);
      if (released) {
        log.info(
            "job", "released at shutdown",
            {{"job", job->key}, {"grace_seconds", std::to_string(config.queue.grace_seconds)}});
      } else {
        // Lost already, or the queue is unreachable: the lease expires and another worker
        // takes the job over (this attempt then counts).
        log.error("job", "release at shutdown failed; the lease will expire",
                  {{"job", job->key},
                   {"reason", released_failure.ok() ? "lease lost" : released_failure.message}});
      }
      log.info("worker", "stopped by signal",
               {{"jobs", std::to_string(work.jobs)}, {"job", ran ? "cancelled" : "abandoned"}});
      if (ran) {
        work.stopped = true;
        work.released_job = job->key;
        work.released = released;
        return failure;
      }
      if (options.on_forced_exit) options.on_forced_exit(job->key, released);
      exit_leaving_threads(0);
    }
    heartbeat.stop();
    // A job stopped by its memory bound fails with that reason, whatever it returned on the
    // way out (Cancelled, or a step's error); one that completed before it saw the request
    // keeps its result.
    if (memory.exceeded() && !ran->failure.ok()) ran->failure = memory.failure(job->key);
    const Failure& job_failure = ran->failure;
    const std::optional<double> peak_mib = ops::peak_resident_mib();
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ++work.jobs;
    if (heartbeat.lost()) {
      // Another worker holds the job now (fencing): this attempt's outcome is not recorded.
      ops::metrics().job_finished(ops::JobOutcome::LeaseLost, seconds);
      log.error("job", "lease lost; outcome discarded",
                {{"job", job->key}, {"seconds", std::to_string(seconds)}});
      continue;
    }
    if (job_failure.ok()) {
      const std::string record =
          with_timings(ran->result, ran->timings, seconds, worker_id, job->attempts, peak_mib);
      const bool completed = queue.complete(*job, record, failure);
      if (failure.ok()) {
        ops::metrics().job_finished(completed ? ops::JobOutcome::Done : ops::JobOutcome::LeaseLost,
                                    seconds);
      }
      if (completed) {
        log.info("job", "done", {{"job", job->key}, {"seconds", std::to_string(seconds)}});
        const jobs::JobKind* kind = jobs::find_job_kind(job->kind);
        if (kind != nullptr && kind->advances_city_run) {
          std::size_t next = 0;
          if (Failure f = city::advance_city_run(config, queue, log, next); !f.ok()) {
            log.error("run", "cannot advance the city run", {{"reason", f.message}});
          }
        }
      } else if (failure.ok()) {
        // The lease expired between the last renewal and the completion (fencing).
        log.error("job", "lease lost; outcome discarded",
                  {{"job", job->key}, {"seconds", std::to_string(seconds)}});
      }
    } else {
      const ErrorInfo& info = error_info(job_failure.code);
      queue.fail(*job, std::string(info.name) + ": " + job_failure.message, info.retryable,
                 failure);
      const bool dead = !info.retryable || job->attempts >= config.queue.max_attempts;
      ops::metrics().job_finished(dead ? ops::JobOutcome::Dead : ops::JobOutcome::Retry, seconds);
      log.error("job", "failed",
                {{"job", job->key},
                 {"error", info.name},
                 {"reason", job_failure.message}});  // attempt: LogJobScope
    }
    if (!failure.ok()) return failure;
    // Progress of the whole queue after each job (the run's progress display in the logs).
    const QueueCounts c = queue.counts(failure);
    if (!failure.ok()) return failure;
    log.info("run", "progress",
             {{"finished", std::to_string(c.done + c.dead)},
              {"of", std::to_string(c.done + c.dead + c.unfinished())},
              {"dead", std::to_string(c.dead)}});
  }
}

Failure run_embedded(const config::Config& config, const Logger& log, RunSummary& summary,
                     const ForcedExitReport& on_forced_exit) {
  summary.run_dir = std::filesystem::path(config.run.output) / "runs" / config.run.name;
  Failure failure;
  auto queue = open_queue(config, failure);
  if (!queue) return failure;
  std::size_t added = 0;
  if (Failure f = enqueue_run(config, *queue, log, added); !f.ok()) return f;
  WorkOptions options;
  options.exit_when_idle = true;
  options.on_forced_exit = on_forced_exit;
  WorkSummary work;
  if (Failure f = work_queue(config, *queue, log, options, work); !f.ok()) return f;
  if (work.stopped) {
    summary.counts = queue->counts(failure);
    summary.stopped = true;
    summary.released_job = work.released_job;
    summary.released = work.released;
    return failure;
  }
  return publish_run(config, *queue, log, summary);
}

namespace {

// Whether `manifest` already publishes this run as it stands: the same run, version, config,
// seed, jobs and dead jobs, and every export it names present with its recorded size and
// SHA-256. Then publishing again would write the same bytes (the exports are deterministic),
// so a worker that finds the run finished need not rebuild them.
bool already_published(const std::filesystem::path& manifest_path, const ordered_json& head,
                       const std::filesystem::path& run_dir) {
  std::error_code ec;
  if (!std::filesystem::exists(manifest_path, ec)) return false;
  ordered_json manifest;
  try {
    std::ifstream in(manifest_path, std::ios::binary);
    manifest = ordered_json::parse(in);
  } catch (const std::exception&) {
    return false;  // unreadable or half-written by an older version: publish again
  }
  for (const auto& [key, value] : head.items()) {
    if (!manifest.contains(key) || manifest[key] != value) return false;
  }
  auto present = [&](const ordered_json& entry, const char* key, const char* sha,
                     const char* bytes) {
    if (!entry.is_object() || !entry.contains(key) || !entry.contains(sha) ||
        !entry.contains(bytes))
      return false;
    std::string hex;
    std::uint64_t size = 0;
    if (!file_sha256(run_dir / entry[key].get<std::string>(), hex, size).ok()) return false;
    return hex == entry[sha].get<std::string>() && size == entry[bytes].get<std::uint64_t>();
  };
  try {
    if (!present(manifest["index"], "key", "sha256", "bytes")) return false;
    if (!present(manifest["cityjson"], "key", "sha256", "bytes")) return false;
    const ordered_json& tiles = manifest["tiles"];
    if (!tiles.is_null() && (!present(tiles, "key", "sha256", "bytes") ||
                             !present(tiles, "content", "content_sha256", "content_bytes"))) {
      return false;
    }
  } catch (const std::exception&) {
    return false;
  }
  return true;
}

}  // namespace

Failure publish_run(const config::Config& config, JobQueue& queue_ref, const Logger& log,
                    RunSummary& summary) {
  summary.run_dir = std::filesystem::path(config.run.output) / "runs" / config.run.name;
  const ops::LongStepScope long_step(ops::metrics(), "publish");  // live while publishing
  JobQueue* queue = &queue_ref;
  Failure failure;
  summary.counts = queue->counts(failure);
  // A queue may hold several runs (one PostgreSQL database for a cluster, or one SQLite file
  // for runs sharing an output folder): a run publishes only its own jobs, whose keys are
  // "<kind>:<run name>:..." (run names have no ':').
  auto of_this_run = [&config](const std::string& key) {
    return is_job_of_run(key, config.run.name);
  };
  summary.dead.clear();
  for (DeadJob& d : queue->dead_jobs(failure)) {
    if (of_this_run(d.key)) summary.dead.push_back(std::move(d));
  }
  if (is_city_run(config)) {
    // The run's index job published it (city/index_job.cpp); nothing is written here.
    summary.manifest = summary.run_dir / "manifest.json";
    std::error_code ec;
    if (failure.ok() && summary.dead.empty() && !std::filesystem::exists(summary.manifest, ec)) {
      return {ErrorCode::Internal, "run " + config.run.name +
                                       " finished without its index job: no manifest.json (see "
                                       "the log's \"cannot advance\" lines)"};
    }
    return failure;
  }
  std::vector<std::pair<std::string, std::string>> results;
  for (auto& entry : queue->results(failure)) {
    if (of_this_run(entry.first)) results.push_back(std::move(entry));
  }
  if (!failure.ok()) return failure;
  // The manifest's head: what identifies this publication. Another worker (or this one,
  // earlier) may have published exactly this already; then nothing is rebuilt.
  JobRecords records;
  for (const auto& [key, result] : results) records.add(key, ordered_json::parse(result));
  const ordered_json head = manifest_head(jobs::manifest_identity(config), "scenes");
  ordered_json published = head;  // and the jobs it was published from
  published["jobs"] = records.jobs;
  published["dead"] = dead_jobs_json(summary.dead);
  summary.manifest = summary.run_dir / "manifest.json";
  if (already_published(summary.manifest, published, summary.run_dir)) {
    log.info("run", "already published", {{"manifest", summary.manifest.string()}});
    return publish::publish_run_directory(jobs::publish_target(config), summary.run_dir, log);
  }
  // The run's exports (export/), published before the manifest names them.
  const RunExportOptions settings = jobs::export_options(config);
  RunObjects objects;
  if (Failure f =
          collect_run_objects(jobs::run_jobs(config), settings, results, summary.run_dir, objects);
      !f.ok())
    return f;
  RunIndexReport index;
  if (Failure f = write_run_index(settings, objects, summary.run_dir, index); !f.ok()) return f;
  log.info("index", "written",
           {{"key", index.key},
            {"objects", std::to_string(index.stats.objects)},
            {"bytes", std::to_string(index.bytes)},
            {"seconds", std::to_string(index.seconds)}});
  for (const std::string& w : index.stats.warnings) log.info("index", w);
  CityJsonReport cityjson;
  if (Failure f = write_run_cityjson(settings, objects, summary.run_dir, cityjson); !f.ok())
    return f;
  log.info("cityjson", "written",
           {{"key", cityjson.key},
            {"features", std::to_string(cityjson.stats.features)},
            {"bytes", std::to_string(cityjson.bytes)}});
  for (const std::string& w : cityjson.stats.warnings) {
    log.log(config::LogLevel::Warn, "cityjson", w);
  }
  TilesReport tiles;
  if (Failure f = write_run_tiles(settings, objects, summary.run_dir, tiles); !f.ok()) return f;
  if (tiles.written) {
    log.info("tiles", "written",
             {{"key", tiles.key},
              {"objects", std::to_string(tiles.objects)},
              {"bytes", std::to_string(tiles.content_bytes)}});
  } else {
    log.info("tiles", "not written", {{"reason", tiles.skipped}});
  }
  for (const std::string& w : tiles.warnings) log.log(config::LogLevel::Warn, "tiles", w);
  ordered_json manifest = head;
  manifest["index"] = index_entry(index);
  manifest["cityjson"] = cityjson_entry(cityjson);
  manifest["tiles"] = tiles_entry(tiles);
  if (!tiles.written) manifest["tiles_skipped"] = tiles.skipped;
  std::string text;
  if (Failure f = write_run_manifest(summary.run_dir, config.run.name, std::move(manifest), records,
                                     summary.dead, text);
      !f.ok()) {
    return f;
  }
  return publish::publish_run_directory(jobs::publish_target(config), summary.run_dir, log);
}

}  // namespace csgtile::worker
