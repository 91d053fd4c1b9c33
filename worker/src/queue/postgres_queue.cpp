// The PostgreSQL job queue: the SQLite queue's semantics (sqlite_queue.cpp) for workers on
// many machines. Claims take the first runnable row in claim order (priority, runnable time,
// id) with FOR UPDATE SKIP LOCKED, so concurrent claimers pass over each other's rows instead
// of waiting or colliding.

#include <mutex>
#include <string_view>
#include <utility>

#include "csgtile/worker/queue.h"
#include "queue/postgres_connection.h"
#include "queue/postgres_schema.h"
#include "queue/queue_random.h"

namespace csgtile::worker {
namespace {

using detail::PgResult;

std::string text(const PgResult& result, int row, int column) {
  return std::string(PQgetvalue(result.get(), row, column),
                     static_cast<std::size_t>(PQgetlength(result.get(), row, column)));
}

std::int64_t number(const PgResult& result, int row, int column) {
  return std::stoll(PQgetvalue(result.get(), row, column));
}

constexpr std::pair<std::string_view, std::int64_t QueueCounts::*> kCountOfState[] = {
    {"queued", &QueueCounts::queued},
    {"running", &QueueCounts::running},
    {"done", &QueueCounts::done},
    {"retry", &QueueCounts::retry},
    {"dead", &QueueCounts::dead}};

bool changed_one_row(const PgResult& result) {
  return std::string_view(PQcmdTuples(result.get())) == "1";
}

class PostgresQueue final : public JobQueue {
 public:
  PostgresQueue(std::unique_ptr<detail::PostgresConnection> connection, const QueuePolicy& policy)
      : connection_(std::move(connection)), policy_(policy), random_(policy.seed) {}

  std::optional<Job> claim(const std::string& worker_id, Failure& failure) override {
    const std::lock_guard lock(mutex_);
    if (!connection_->ensure_open(failure) ||
        !connection_->exec_script("claim: begin", "BEGIN", failure)) {
      return std::nullopt;
    }
    // A job whose last allowed attempt lost its lease (the worker crashed, was killed or hung)
    // ends dead here instead of being claimed again: a job that kills its worker every time
    // must not loop.
    const PgResult bury = connection_->exec(
        "claim: bury",
        "UPDATE csgtile_jobs SET state = 'dead', last_error = $2, lease_token = NULL, "
        "lease_expires = NULL, updated_at = now() "
        "WHERE state = 'running' AND lease_expires < now() AND attempts >= $1::integer",
        {std::to_string(policy_.max_attempts), std::string(kLeaseLost)}, failure);
    if (!bury) return abandon();
    // now() is the transaction's start on the server: one clock for every worker. The first
    // term repeats the claim index's predicate, so the planner can prove the partial index
    // covers the query and read it in order.
    const PgResult pick = connection_->exec(
        "claim",
        "SELECT id, key, kind, payload, attempts, (extract(epoch FROM now()) * 1000)::bigint "
        "FROM csgtile_jobs "
        "WHERE state IN ('queued','retry','running') "
        "  AND ((state IN ('queued','retry') AND run_after <= now()) "
        "    OR (state = 'running' AND lease_expires < now())) "
        "ORDER BY priority DESC, run_after, id LIMIT 1 FOR UPDATE SKIP LOCKED",
        {}, failure);
    if (!pick) return abandon();
    if (PQntuples(pick.get()) == 0) {
      connection_->exec_script("claim: commit", "COMMIT", failure);
      return std::nullopt;
    }
    Job job;
    job.id = number(pick, 0, 0);
    job.key = text(pick, 0, 1);
    job.kind = text(pick, 0, 2);
    job.payload = text(pick, 0, 3);
    job.attempts = static_cast<int>(number(pick, 0, 4)) + 1;
    job.lease_token = random_.lease_token(worker_id, number(pick, 0, 5));
    const auto lease_ms = std::chrono::duration_cast<std::chrono::milliseconds>(policy_.lease);
    const PgResult lease = connection_->exec(
        "claim: lease",
        "UPDATE csgtile_jobs SET state = 'running', attempts = $2::integer, lease_token = $3, "
        "lease_expires = now() + $4::bigint * interval '1 millisecond', worker = $5, "
        "updated_at = now() WHERE id = $1::bigint",
        {std::to_string(job.id), std::to_string(job.attempts), job.lease_token,
         std::to_string(lease_ms.count()), worker_id},
        failure);
    if (!lease) return abandon();
    // A lost COMMIT leaves the job leased or not; either way its lease expires and it is
    // claimed again (at-least-once).
    if (!connection_->exec_script("claim: commit", "COMMIT", failure)) return abandon();
    return job;
  }

  bool complete(const Job& job, const std::string& result, Failure& failure) override {
    const std::lock_guard lock(mutex_);
    if (!connection_->ensure_open(failure)) return false;
    const PgResult update = connection_->exec(
        "complete",
        "UPDATE csgtile_jobs SET state = 'done', result = $3, lease_token = NULL, "
        "lease_expires = NULL, updated_at = now() "
        "WHERE id = $1::bigint AND lease_token = $2 AND state = 'running'",
        {std::to_string(job.id), job.lease_token, result}, failure);
    return update && changed_one_row(update);
  }

  bool renew(const Job& job, Failure& failure) override {
    const std::lock_guard lock(mutex_);
    if (!connection_->ensure_open(failure)) return false;
    const auto lease_ms = std::chrono::duration_cast<std::chrono::milliseconds>(policy_.lease);
    const PgResult update = connection_->exec(
        "renew",
        "UPDATE csgtile_jobs SET lease_expires = now() + $3::bigint * interval '1 millisecond', "
        "updated_at = now() WHERE id = $1::bigint AND lease_token = $2 AND state = 'running'",
        {std::to_string(job.id), job.lease_token, std::to_string(lease_ms.count())}, failure);
    return update && changed_one_row(update);
  }

  bool fail(const Job& job, const std::string& error, bool retryable, Failure& failure) override {
    const std::lock_guard lock(mutex_);
    const bool dead = !retryable || job.attempts >= policy_.max_attempts;
    // Drawn before any I/O, as the SQLite queue does, so both draw the same sequence.
    const std::int64_t delay_ms = random_.retry_delay_ms(policy_, job.attempts);
    if (!connection_->ensure_open(failure)) return false;
    const PgResult update = connection_->exec(
        "fail",
        "UPDATE csgtile_jobs SET state = $3, last_error = $4, "
        "run_after = now() + $5::bigint * interval '1 millisecond', lease_token = NULL, "
        "lease_expires = NULL, updated_at = now() "
        "WHERE id = $1::bigint AND lease_token = $2 AND state = 'running'",
        {std::to_string(job.id), job.lease_token, dead ? "dead" : "retry", error,
         std::to_string(delay_ms)},
        failure);
    return update && changed_one_row(update);
  }

  bool release(const Job& job, Failure& failure) override {
    const std::lock_guard lock(mutex_);
    if (!connection_->ensure_open(failure)) return false;
    // attempts - 1: a stop is not the job's failure, so it costs no attempt.
    const PgResult update = connection_->exec(
        "release",
        "UPDATE csgtile_jobs SET state = 'queued', attempts = greatest(attempts - 1, 0), "
        "lease_token = NULL, lease_expires = NULL, worker = NULL, updated_at = now() "
        "WHERE id = $1::bigint AND lease_token = $2 AND state = 'running'",
        {std::to_string(job.id), job.lease_token}, failure);
    return update && changed_one_row(update);
  }

  QueueCounts counts(Failure& failure) override {
    const std::lock_guard lock(mutex_);
    QueueCounts counts;
    if (!connection_->ensure_open(failure)) return counts;
    const PgResult rows = connection_->exec(
        "counts", "SELECT state, count(*) FROM csgtile_jobs GROUP BY state", {}, failure);
    for (int row = 0; rows && row < PQntuples(rows.get()); ++row) {
      const std::string state = text(rows, row, 0);
      for (const auto& [name, member] : kCountOfState) {
        if (state == name) counts.*member = number(rows, row, 1);
      }
    }
    return counts;
  }

  // Keys are ordered byte-wise (COLLATE "C"), as SQLite orders them, whatever the database's
  // collation.
  std::vector<DeadJob> dead_jobs(Failure& failure) override {
    const std::lock_guard lock(mutex_);
    std::vector<DeadJob> out;
    if (!connection_->ensure_open(failure)) return out;
    const PgResult rows =
        connection_->exec("dead jobs",
                          "SELECT key, COALESCE(last_error, ''), attempts FROM csgtile_jobs "
                          "WHERE state = 'dead' ORDER BY key COLLATE \"C\"",
                          {}, failure);
    for (int row = 0; rows && row < PQntuples(rows.get()); ++row) {
      out.push_back(
          {text(rows, row, 0), text(rows, row, 1), static_cast<int>(number(rows, row, 2))});
    }
    return out;
  }

  std::vector<std::pair<std::string, std::string>> results(Failure& failure) override {
    const std::lock_guard lock(mutex_);
    std::vector<std::pair<std::string, std::string>> out;
    if (!connection_->ensure_open(failure)) return out;
    const PgResult rows =
        connection_->exec("results",
                          "SELECT key, COALESCE(result, '') FROM csgtile_jobs WHERE state = 'done' "
                          "ORDER BY key COLLATE \"C\"",
                          {}, failure);
    for (int row = 0; rows && row < PQntuples(rows.get()); ++row) {
      out.emplace_back(text(rows, row, 0), text(rows, row, 1));
    }
    return out;
  }

 protected:
  // The runnable time is the server's now() plus the delay to not_before on the caller's
  // clock: clock skew between machines does not matter, as for leases.
  bool enqueue_job(const std::string& key, const std::string& kind, const std::string& payload,
                   const EnqueueOptions& options, Failure& failure) override {
    std::int64_t delay_ms = 0;
    if (options.not_before) {
      delay_ms = std::chrono::duration_cast<std::chrono::milliseconds>(
                     *options.not_before - std::chrono::system_clock::now())
                     .count();
    }
    const std::lock_guard lock(mutex_);
    if (!connection_->ensure_open(failure)) return false;
    const PgResult result = connection_->exec(
        "enqueue",
        "INSERT INTO csgtile_jobs (key, kind, payload, priority, run_after) "
        "VALUES ($1, $2, $3, $4::integer, now() + greatest($5::bigint, 0) * interval '1 "
        "millisecond') "
        "ON CONFLICT (key) DO NOTHING",
        {key, kind, payload, std::to_string(options.priority), std::to_string(delay_ms)}, failure);
    return result && changed_one_row(result);
  }

 private:
  std::optional<Job> abandon() {
    connection_->rollback();
    return std::nullopt;
  }

  std::mutex mutex_;
  std::unique_ptr<detail::PostgresConnection> connection_;
  QueuePolicy policy_;
  detail::QueueRandom random_;
};

}  // namespace

std::unique_ptr<JobQueue> open_postgres_queue(const std::string& conninfo,
                                              const QueuePolicy& policy, Failure& failure,
                                              const PostgresOptions& options) {
  auto connection = detail::PostgresConnection::open(conninfo, options, failure);
  if (!connection || !detail::migrate_postgres_schema(*connection, failure)) return nullptr;
  return std::make_unique<PostgresQueue>(std::move(connection), policy);
}

}  // namespace csgtile::worker
