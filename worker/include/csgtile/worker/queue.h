#pragma once
/// \file
/// The job queue: one interface, the same states and semantics for every backend.
///
/// States: queued → running (lease: token + expiry, attempt counted) → done | retry (after
/// a backoff) | dead (attempts exhausted or a permanent error, with the last error). A job
/// whose lease expires is claimable again (its worker is presumed dead); a worker whose
/// lease was taken over can no longer complete or fail the job (fencing by token). A worker
/// stopping before its job ends releases it: queued again, the attempt not counted.
///
/// Claim order: higher priority first, then earlier runnable time (enqueue time, not_before,
/// or the end of a retry's backoff), then enqueue order (id).

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "csgtile/config/config.h"
#include "csgtile/worker/errors.h"

namespace csgtile::worker {

enum class JobState { Queued, Running, Done, Retry, Dead };
const char* job_state_name(JobState state);

struct Job {
  std::int64_t id = 0;
  std::string key;      ///< unique: enqueueing the same key twice is a no-op
  std::string kind;     ///< e.g. "build"
  std::string payload;  ///< JSON text, interpreted by the job's runner
  int attempts = 0;     ///< including the current one
  std::string lease_token;
};

struct QueueCounts {
  std::int64_t queued = 0, running = 0, done = 0, retry = 0, dead = 0;
  std::int64_t unfinished() const { return queued + running + retry; }
};

/// last_error of a job buried by claim(): its last allowed attempt's lease expired unrenewed.
inline constexpr const char* kLeaseLost =
    "lease_lost: the worker of the last allowed attempt stopped renewing its lease "
    "(it crashed, was killed or hung)";

struct DeadJob {
  std::string key;
  std::string last_error;
  int attempts = 0;
};

/// How a job is enqueued; the defaults make a job like every other: runnable now, priority 0.
struct EnqueueOptions {
  int priority = 0;  ///< higher is claimed first; any int
  /// Not claimable before this time. SQLite compares it with the local clock; PostgreSQL turns
  /// it into a delay from the caller's clock and adds that to the server's now(), as leases
  /// are timed, so clock skew between machines does not matter. Unset or past: runnable now.
  std::optional<std::chrono::system_clock::time_point> not_before;
};

struct QueuePolicy {
  int max_attempts = 5;
  std::chrono::seconds lease{60};
  std::chrono::milliseconds backoff_base{500};  ///< retry delay = base · 2^(attempt-1) · jitter
  std::uint64_t seed = 1;                       ///< seeds the jitter
};

class JobQueue {
 public:
  virtual ~JobQueue() = default;
  /// Adds a job unless one with the same key exists (whose priority and time stay as they
  /// are). Returns whether it was added.
  bool enqueue(const std::string& key, const std::string& kind, const std::string& payload,
               Failure& failure, const EnqueueOptions& options = {}) {
    return enqueue_job(key, kind, payload, options, failure);
  }
  /// Claims the next runnable job (queued or retry whose time has come, or running with an
  /// expired lease) in claim order (above); nullopt when there is none.
  virtual std::optional<Job> claim(const std::string& worker_id, Failure& failure) = 0;
  /// Marks the job done with its result, only if `job.lease_token` still holds the lease.
  virtual bool complete(const Job& job, const std::string& result, Failure& failure) = 0;
  /// Heartbeat: extends a running job's lease to the policy's lease from now, only while
  /// `job.lease_token` still holds it. False when the lease was lost (taken over or the job
  /// is no longer running): the caller must then neither complete nor publish it.
  virtual bool renew(const Job& job, Failure& failure) = 0;
  /// Records a failure: retry after a backoff if `retryable` and attempts remain, else dead.
  virtual bool fail(const Job& job, const std::string& error, bool retryable, Failure& failure) = 0;
  /// Gives a running job back (a worker stopping before the job ends): queued again with its
  /// priority and runnable time, this attempt not counted against max_attempts, the lease
  /// cleared. Only while `job.lease_token` still holds the lease; false otherwise.
  virtual bool release(const Job& job, Failure& failure) = 0;
  virtual QueueCounts counts(Failure& failure) = 0;
  virtual std::vector<DeadJob> dead_jobs(Failure& failure) = 0;
  /// Results of done jobs, ordered by key (for manifests).
  virtual std::vector<std::pair<std::string, std::string>> results(Failure& failure) = 0;

 protected:
  /// The backend's enqueue (a non-virtual front keeps one default for `options`).
  virtual bool enqueue_job(const std::string& key, const std::string& kind,
                           const std::string& payload, const EnqueueOptions& options,
                           Failure& failure) = 0;
};

/// Opens (creating if needed) a SQLite queue file on local disk, in WAL mode; several
/// processes on one machine may share it. An older file is migrated (version in its
/// schema_version table) in one BEGIN IMMEDIATE transaction. Errors: Io (cannot open, or a
/// network file system), Unsupported (a schema newer than this build).
std::unique_ptr<JobQueue> open_sqlite_queue(const std::filesystem::path& path,
                                            const QueuePolicy& policy, Failure& failure);

/// PostgreSQL settings beyond the connection string; a non-empty field overrides the string's.
struct PostgresOptions {
  std::string sslmode;      ///< disable, allow, prefer, require, verify-ca or verify-full
  std::string sslrootcert;  ///< CA certificate file checked by verify-ca and verify-full
  std::string password;     ///< never logged; empty: the string's, then PGPASSWORD, ~/.pgpass
};

/// Opens a queue in a PostgreSQL database (`conninfo`: libpq keyword/value text or a
/// postgresql:// URI), creating or migrating its tables (version in csgtile_schema_version) in
/// one transaction under an advisory lock, so workers may start together. Claims use
/// FOR UPDATE SKIP LOCKED; lease expiry is server time. A lost connection is reopened on the
/// next call. A handle holds one connection and serialises its calls.
/// Errors: ConfigInvalid (malformed conninfo), Io (cannot connect: names host and port, never
/// the password; connection lost), Unsupported (a schema newer than this build).
std::unique_ptr<JobQueue> open_postgres_queue(const std::string& conninfo,
                                              const QueuePolicy& policy, Failure& failure,
                                              const PostgresOptions& options = {});

/// The policy of `config`: queue.max_attempts, queue.lease_seconds, seeded by run.seed.
QueuePolicy queue_policy(const config::Config& config);

/// Opens the queue `config.queue` selects: the SQLite file (default <run.output>/queue.sqlite)
/// or the PostgreSQL database of queue.postgres_dsn with queue.postgres_sslmode and
/// queue.postgres_sslrootcert; its password is `env`'s CSGTILE_PG_PASSWORD, else libpq's own
/// PGPASSWORD or ~/.pgpass. Errors as the backend's opener; ConfigInvalid for postgres without
/// a postgres_dsn.
std::unique_ptr<JobQueue> open_queue(
    const config::Config& config, Failure& failure,
    const config::Environment& env = config::from_process_environment());

/// Where `config`'s queue is, for logs: the SQLite path, or "postgres HOST:PORT/DATABASE"
/// (never user or password).
std::string describe_queue(const config::Config& config);

}  // namespace csgtile::worker
