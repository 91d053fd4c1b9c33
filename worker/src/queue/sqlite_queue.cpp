#include <sqlite3.h>
#include <sys/vfs.h>

#include <algorithm>
#include <chrono>
#include <iterator>
#include <thread>

#include "csgtile/worker/queue.h"
#include "queue/queue_random.h"

namespace csgtile::worker {

const char* job_state_name(JobState state) {
  switch (state) {
    case JobState::Queued:
      return "queued";
    case JobState::Running:
      return "running";
    case JobState::Done:
      return "done";
    case JobState::Retry:
      return "retry";
    case JobState::Dead:
      return "dead";
  }
  return "unknown";
}

namespace {

struct Migration {
  int version;
  const char* sql;
};

// Migration v brings the schema from version v - 1 to v; never edit one that has shipped.
// Version 1 is the schema of files made before versions were counted (every such file records
// 1, so its CREATEs are skipped there).
constexpr Migration kMigrations[] = {
    {1, R"sql(
CREATE TABLE IF NOT EXISTS jobs (
  id            INTEGER PRIMARY KEY AUTOINCREMENT,
  key           TEXT NOT NULL UNIQUE,
  kind          TEXT NOT NULL,
  payload       TEXT NOT NULL,
  state         TEXT NOT NULL DEFAULT 'queued'
                CHECK (state IN ('queued','running','done','retry','dead')),
  attempts      INTEGER NOT NULL DEFAULT 0,
  run_after_ms  INTEGER NOT NULL DEFAULT 0,
  lease_token   TEXT,
  lease_expires_ms INTEGER,
  worker        TEXT,
  last_error    TEXT,
  result        TEXT,
  created_ms    INTEGER NOT NULL,
  updated_ms    INTEGER NOT NULL
);
CREATE INDEX IF NOT EXISTS jobs_runnable ON jobs (state, run_after_ms, id);
)sql"},
    // Priorities. The claim index holds only unfinished jobs, in claim order, so a claim reads
    // the first rows of it however many jobs are queued or done; the lease index serves the
    // burial of jobs whose last attempt lost its lease. The old index goes: with it, SQLite
    // preferred to gather every runnable job and sort them.
    {2, R"sql(
ALTER TABLE jobs ADD COLUMN priority INTEGER NOT NULL DEFAULT 0;
DROP INDEX IF EXISTS jobs_runnable;
CREATE INDEX jobs_claim ON jobs (priority DESC, run_after_ms, id)
  WHERE state IN ('queued','retry','running');
CREATE INDEX jobs_leased ON jobs (lease_expires_ms) WHERE state = 'running';
)sql"},
};
constexpr int kSchemaVersion = static_cast<int>(std::size(kMigrations));

std::int64_t now_ms() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// Magic numbers of network file systems, where SQLite's locking is not reliable.
bool on_network_filesystem(const std::filesystem::path& dir) {
  struct statfs fs {};
  if (statfs(dir.c_str(), &fs) != 0) return false;
  switch (static_cast<unsigned long>(fs.f_type)) {
    case 0x6969:      // NFS
    case 0xFF534D42:  // CIFS
    case 0xFE534D42:  // SMB2
    case 0x517B:      // SMB
    case 0x65735546:  // FUSE (sshfs, s3fs, ...)
      return true;
    default:
      return false;
  }
}

// A prepared statement that finalizes itself.
class Statement {
 public:
  Statement(sqlite3* db, const char* sql) {
    rc_ = sqlite3_prepare_v2(db, sql, -1, &stmt_, nullptr);
  }
  ~Statement() { sqlite3_finalize(stmt_); }
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;
  bool ok() const { return rc_ == SQLITE_OK; }
  Statement& bind(int i, const std::string& v) {
    sqlite3_bind_text(stmt_, i, v.data(), static_cast<int>(v.size()), SQLITE_TRANSIENT);
    return *this;
  }
  Statement& bind(int i, std::int64_t v) {
    sqlite3_bind_int64(stmt_, i, v);
    return *this;
  }
  int step() { return sqlite3_step(stmt_); }
  std::int64_t int64(int col) const { return sqlite3_column_int64(stmt_, col); }
  std::string text(int col) const {
    const auto* p = sqlite3_column_text(stmt_, col);
    return p ? std::string(reinterpret_cast<const char*>(p),
                           static_cast<std::size_t>(sqlite3_column_bytes(stmt_, col)))
             : std::string();
  }

 private:
  sqlite3_stmt* stmt_ = nullptr;
  int rc_ = SQLITE_ERROR;
};

class SqliteQueue final : public JobQueue {
 public:
  SqliteQueue(sqlite3* db, const QueuePolicy& policy)
      : db_(db), policy_(policy), random_(policy.seed) {}
  ~SqliteQueue() override { sqlite3_close(db_); }

  bool exec(const char* sql, Failure& failure) {
    char* message = nullptr;
    const int code = sqlite3_exec(db_, sql, nullptr, nullptr, &message);
    if (code != SQLITE_OK) {
      last_busy_ = (code & 0xff) == SQLITE_BUSY || (code & 0xff) == SQLITE_LOCKED;
      failure = {ErrorCode::Io, std::string("sqlite: ") + (message ? message : "error")};
      sqlite3_free(message);
      return false;
    }
    return true;
  }

  // Puts the file in WAL mode and brings its schema up to date. Switching a rollback-journal
  // file to WAL needs an exclusive lock, and where waiting for it could deadlock (two
  // processes opening the same new or old file, each holding a shared lock) SQLite answers
  // "database is locked" at once instead of calling the busy handler; the opening is then
  // tried again, for as long as the busy timeout allows.
  bool prepare(std::chrono::milliseconds patience, Failure& failure) {
    const auto deadline = std::chrono::steady_clock::now() + patience;
    // Not the seeded QueueRandom: its draws are the queue's reproducible sequence.
    std::chrono::milliseconds pause{2};
    for (;;) {
      last_busy_ = false;
      if (exec("PRAGMA journal_mode=WAL; PRAGMA synchronous=NORMAL;", failure) &&
          migrate(failure)) {
        return true;
      }
      if (!last_busy_ || std::chrono::steady_clock::now() >= deadline) return false;
      std::this_thread::sleep_for(pause);
      pause = std::min(pause * 2, std::chrono::milliseconds(50));
    }
  }

  // Brings the file to kSchemaVersion in one BEGIN IMMEDIATE transaction: processes opening
  // the same file at once migrate it once, the others find it done.
  bool migrate(Failure& failure) {
    if (!exec("BEGIN IMMEDIATE", failure)) return false;
    // Its own result is of no interest, and it must not hide why the migration stopped.
    const auto abandon = [&] {
      sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
      return false;
    };
    if (!exec("CREATE TABLE IF NOT EXISTS schema_version (version INTEGER NOT NULL)", failure)) {
      return abandon();
    }
    int version = 0;
    {
      Statement read(db_, "SELECT COALESCE(MAX(version), 0) FROM schema_version");
      if (read.step() != SQLITE_ROW) {
        error(failure);
        return abandon();
      }
      version = static_cast<int>(read.int64(0));
    }
    if (version > kSchemaVersion) {
      failure = {ErrorCode::Unsupported, "the SQLite queue's schema is version " +
                                             std::to_string(version) +
                                             "; this csgtile knows versions up to " +
                                             std::to_string(kSchemaVersion) + " (upgrade csgtile)"};
      return abandon();
    }
    for (const Migration& migration : kMigrations) {
      if (migration.version <= version) continue;
      if (!exec(migration.sql, failure)) return abandon();
    }
    // One row, as files made before migrations hold.
    if (version < kSchemaVersion &&
        (!exec("DELETE FROM schema_version", failure) ||
         !exec(
             ("INSERT INTO schema_version VALUES (" + std::to_string(kSchemaVersion) + ")").c_str(),
             failure))) {
      return abandon();
    }
    return exec("COMMIT", failure) || abandon();
  }

  bool release(const Job& job, Failure& failure) override {
    // attempts - 1: a stop is not the job's failure, so it costs no attempt.
    Statement st(db_,
                 "UPDATE jobs SET state='queued', attempts=MAX(attempts-1, 0), lease_token=NULL, "
                 "lease_expires_ms=NULL, worker=NULL, updated_ms=?3 "
                 "WHERE id=?1 AND state='running' AND lease_token=?2");
    st.bind(1, job.id).bind(2, job.lease_token).bind(3, now_ms());
    if (st.step() != SQLITE_DONE) return error(failure);
    return sqlite3_changes(db_) > 0;
  }

  std::optional<Job> claim(const std::string& worker_id, Failure& failure) override {
    // BEGIN IMMEDIATE takes the write lock up front, so two processes never claim one job.
    if (!exec("BEGIN IMMEDIATE", failure)) return std::nullopt;
    const std::int64_t now = now_ms();
    // A job whose last allowed attempt lost its lease (the worker crashed, was killed or hung)
    // ends dead here instead of being claimed again: a job that kills its worker every time
    // must not loop.
    Statement bury(db_,
                   "UPDATE jobs SET state='dead', last_error=?3, lease_token=NULL, "
                   "lease_expires_ms=NULL, updated_ms=?1 "
                   "WHERE state='running' AND lease_expires_ms < ?1 AND attempts >= ?2");
    bury.bind(1, now)
        .bind(2, static_cast<std::int64_t>(policy_.max_attempts))
        .bind(3, std::string(kLeaseLost));
    if (bury.step() != SQLITE_DONE) {
      error(failure);
      exec("ROLLBACK", failure);
      return std::nullopt;
    }
    // The first term repeats the claim index's condition word for word: that is how SQLite
    // knows the partial index covers the query.
    Statement pick(db_,
                   "SELECT id, key, kind, payload, attempts FROM jobs "
                   "WHERE state IN ('queued','retry','running') "
                   "  AND ((state IN ('queued','retry') AND run_after_ms <= ?1) "
                   "    OR (state = 'running' AND lease_expires_ms < ?1)) "
                   "ORDER BY priority DESC, run_after_ms, id LIMIT 1");
    pick.bind(1, now);
    const int rc = pick.step();
    if (rc != SQLITE_ROW) {
      exec("COMMIT", failure);
      if (rc != SQLITE_DONE) error(failure);
      return std::nullopt;
    }
    Job job;
    job.id = pick.int64(0);
    job.key = pick.text(1);
    job.kind = pick.text(2);
    job.payload = pick.text(3);
    job.attempts = static_cast<int>(pick.int64(4)) + 1;
    job.lease_token = random_.lease_token(worker_id, now);
    Statement lease(db_,
                    "UPDATE jobs SET state='running', attempts=?2, lease_token=?3, "
                    "lease_expires_ms=?4, worker=?5, updated_ms=?6 WHERE id=?1");
    lease.bind(1, job.id)
        .bind(2, static_cast<std::int64_t>(job.attempts))
        .bind(3, job.lease_token)
        .bind(4, now + std::chrono::duration_cast<std::chrono::milliseconds>(policy_.lease).count())
        .bind(5, worker_id)
        .bind(6, now);
    if (lease.step() != SQLITE_DONE) {
      error(failure);
      exec("ROLLBACK", failure);
      return std::nullopt;
    }
    if (!exec("COMMIT", failure)) return std::nullopt;
    return job;
  }

  bool complete(const Job& job, const std::string& result, Failure& failure) override {
    Statement st(db_,
                 "UPDATE jobs SET state='done', result=?3, lease_token=NULL, "
                 "lease_expires_ms=NULL, updated_ms=?4 "
                 "WHERE id=?1 AND state='running' AND lease_token=?2");
    st.bind(1, job.id).bind(2, job.lease_token).bind(3, result).bind(4, now_ms());
    if (st.step() != SQLITE_DONE) return error(failure);
    return sqlite3_changes(db_) > 0;
  }

  bool renew(const Job& job, Failure& failure) override {
    const std::int64_t now = now_ms();
    Statement st(db_,
                 "UPDATE jobs SET lease_expires_ms=?3, updated_ms=?4 "
                 "WHERE id=?1 AND state='running' AND lease_token=?2");
    st.bind(1, job.id)
        .bind(2, job.lease_token)
        .bind(3, now + std::chrono::duration_cast<std::chrono::milliseconds>(policy_.lease).count())
        .bind(4, now);
    if (st.step() != SQLITE_DONE) return error(failure);
    return sqlite3_changes(db_) > 0;
  }

  bool fail(const Job& job, const std::string& message, bool retryable, Failure& failure) override {
    const bool dead = !retryable || job.attempts >= policy_.max_attempts;
    const std::int64_t delay = random_.retry_delay_ms(policy_, job.attempts);
    Statement st(db_,
                 "UPDATE jobs SET state=?3, last_error=?4, run_after_ms=?5, lease_token=NULL, "
                 "lease_expires_ms=NULL, updated_ms=?6 "
                 "WHERE id=?1 AND state='running' AND lease_token=?2");
    const std::int64_t now = now_ms();
    st.bind(1, job.id)
        .bind(2, job.lease_token)
        .bind(3, std::string(dead ? "dead" : "retry"))
        .bind(4, message)
        .bind(5, now + delay)
        .bind(6, now);
    if (st.step() != SQLITE_DONE) return error(failure);
    return sqlite3_changes(db_) > 0;
  }

  QueueCounts counts(Failure& failure) override {
    QueueCounts c;
    Statement st(db_, "SELECT state, COUNT(*) FROM jobs GROUP BY state");
    int rc;
    while ((rc = st.step()) == SQLITE_ROW) {
      const std::string s = st.text(0);
      const std::int64_t n = st.int64(1);
      if (s == "queued")
        c.queued = n;
      else if (s == "running")
        c.running = n;
      else if (s == "done")
        c.done = n;
      else if (s == "retry")
        c.retry = n;
      else if (s == "dead")
        c.dead = n;
    }
    if (rc != SQLITE_DONE) error(failure);
    return c;
  }

  std::vector<DeadJob> dead_jobs(Failure& failure) override {
    std::vector<DeadJob> out;
    Statement st(
        db_,
        "SELECT key, COALESCE(last_error,''), attempts FROM jobs WHERE state='dead' ORDER BY key");
    int rc;
    while ((rc = st.step()) == SQLITE_ROW) {
      out.push_back({st.text(0), st.text(1), static_cast<int>(st.int64(2))});
    }
    if (rc != SQLITE_DONE) error(failure);
    return out;
  }

  std::vector<std::pair<std::string, std::string>> results(Failure& failure) override {
    std::vector<std::pair<std::string, std::string>> out;
    Statement st(db_, "SELECT key, result FROM jobs WHERE state='done' ORDER BY key");
    int rc;
    while ((rc = st.step()) == SQLITE_ROW) out.emplace_back(st.text(0), st.text(1));
    if (rc != SQLITE_DONE) error(failure);
    return out;
  }

 protected:
  // The runnable time is when the job may first run: now, or a later not_before. Claims
  // order by it after priority.
  bool enqueue_job(const std::string& key, const std::string& kind, const std::string& payload,
                   const EnqueueOptions& options, Failure& failure) override {
    const std::int64_t now = now_ms();
    std::int64_t run_after = now;
    if (options.not_before) {
      run_after = std::max(now, std::chrono::duration_cast<std::chrono::milliseconds>(
                                    options.not_before->time_since_epoch())
                                    .count());
    }
    Statement st(db_,
                 "INSERT OR IGNORE INTO jobs (key, kind, payload, priority, run_after_ms, "
                 "created_ms, updated_ms) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?6)");
    if (!st.ok()) return error(failure);
    st.bind(1, key)
        .bind(2, kind)
        .bind(3, payload)
        .bind(4, static_cast<std::int64_t>(options.priority))
        .bind(5, run_after)
        .bind(6, now);
    if (st.step() != SQLITE_DONE) return error(failure);
    return sqlite3_changes(db_) > 0;
  }

 private:
  bool error(Failure& failure) {
    const int code = sqlite3_errcode(db_);
    last_busy_ = code == SQLITE_BUSY || code == SQLITE_LOCKED;
    failure = {ErrorCode::Io, std::string("sqlite: ") + sqlite3_errmsg(db_)};
    return false;
  }

  sqlite3* db_;
  QueuePolicy policy_;
  detail::QueueRandom random_;
  bool last_busy_ = false;  // the last failed statement met a lock
};

}  // namespace

std::unique_ptr<JobQueue> open_sqlite_queue(const std::filesystem::path& path,
                                            const QueuePolicy& policy, Failure& failure) {
  std::error_code ec;
  const auto dir = path.has_parent_path() ? path.parent_path() : std::filesystem::path(".");
  std::filesystem::create_directories(dir, ec);
  if (ec) {
    failure = {ErrorCode::Io,
               "cannot create queue directory " + dir.string() + ": " + ec.message()};
    return nullptr;
  }
  if (on_network_filesystem(dir)) {
    failure = {ErrorCode::Io, "queue file " + path.string() +
                                  " is on a network file system; SQLite needs local disk "
                                  "(use the postgres backend for shared queues)"};
    return nullptr;
  }
  sqlite3* db = nullptr;
  if (sqlite3_open_v2(path.c_str(), &db,
                      SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_FULLMUTEX,
                      nullptr) != SQLITE_OK) {
    failure = {ErrorCode::Io, "cannot open queue " + path.string() + ": " +
                                  (db ? sqlite3_errmsg(db) : "out of memory")};
    sqlite3_close(db);
    return nullptr;
  }
  constexpr std::chrono::milliseconds kBusyTimeout{10000};
  sqlite3_busy_timeout(db, static_cast<int>(kBusyTimeout.count()));
  auto queue = std::make_unique<SqliteQueue>(db, policy);
  if (!queue->prepare(kBusyTimeout, failure)) return nullptr;
  return queue;
}

}  // namespace csgtile::worker
