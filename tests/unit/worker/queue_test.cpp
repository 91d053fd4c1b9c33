// The job queue's behaviour, the same for every backend (SQLite, PostgreSQL): states, unique
// keys, leases, fencing, retries with seeded backoff, dead jobs, result order.

#include <gtest/gtest.h>

#include <algorithm>
#include <thread>
#include <type_traits>

#include "csgtile/worker/queue.h"
#include "queue/heartbeat.h"
#include "queue/queue_random.h"
#include "queue_backends.h"

namespace csgtile::worker {
namespace {

template <typename Backend>
class JobQueueTest : public ::testing::Test {
 protected:
  void SetUp() override { CSGTILE_PREPARE_QUEUE_BACKEND(backend_); }

  std::unique_ptr<JobQueue> open(QueuePolicy policy = {}) {
    Failure f;
    auto q = backend_.open(policy, f);
    EXPECT_TRUE(f.ok()) << f.message;
    return q;
  }
  Backend backend_;
};

struct BackendNames {
  template <typename Backend>
  static std::string GetName(int) {
    return std::is_same_v<Backend, test::SqliteBackend> ? "Sqlite" : "Postgres";
  }
};
using Backends = ::testing::Types<test::SqliteBackend, test::PostgresBackend>;
TYPED_TEST_SUITE(JobQueueTest, Backends, BackendNames);

/// Claims a job, waiting up to a second for a retry's backoff to pass.
std::optional<Job> claim_within_a_second(JobQueue& q, const std::string& worker, Failure& f) {
  std::optional<Job> job;
  for (int wait = 0; wait < 200 && !job && f.ok(); ++wait) {
    job = q.claim(worker, f);
    if (!job) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return job;
}

TYPED_TEST(JobQueueTest, EnqueueIsIdempotentPerKey) {
  auto q = this->open();
  Failure f;
  EXPECT_TRUE(q->enqueue("a", "build", "{}", f));
  EXPECT_FALSE(q->enqueue("a", "build", "{}", f));
  EXPECT_TRUE(q->enqueue("b", "build", "{}", f));
  EXPECT_EQ(q->counts(f).queued, 2);
  EXPECT_TRUE(f.ok()) << f.message;
}

TYPED_TEST(JobQueueTest, ClaimCompleteAndFencing) {
  auto q = this->open();
  Failure f;
  q->enqueue("a", "build", "{\"x\":1}", f);
  auto job = q->claim("w1", f);
  ASSERT_TRUE(job.has_value()) << f.message;
  EXPECT_EQ(job->key, "a");
  EXPECT_EQ(job->kind, "build");
  EXPECT_EQ(job->payload, "{\"x\":1}");
  EXPECT_EQ(job->attempts, 1);
  EXPECT_FALSE(q->claim("w2", f).has_value());  // leased
  Job stale = *job;
  stale.lease_token = "someone-else";
  EXPECT_FALSE(q->complete(stale, "{}", f));       // a wrong token cannot complete
  EXPECT_FALSE(q->fail(stale, "io: x", true, f));  // nor fail
  EXPECT_TRUE(q->complete(*job, "{\"ok\":true}", f));
  EXPECT_FALSE(q->complete(*job, "{}", f));  // done once
  EXPECT_EQ(q->counts(f).done, 1);
  auto results = q->results(f);
  ASSERT_EQ(results.size(), 1u);
  EXPECT_EQ(results[0].second, "{\"ok\":true}");
  EXPECT_TRUE(f.ok()) << f.message;
}

TYPED_TEST(JobQueueTest, OldestJobFirst) {
  auto q = this->open();
  Failure f;
  for (const char* key : {"c", "a", "b"}) q->enqueue(key, "build", "{}", f);
  for (const char* key : {"c", "a", "b"}) {
    auto job = q->claim("w", f);
    ASSERT_TRUE(job);
    EXPECT_EQ(job->key, key);
  }
  EXPECT_FALSE(q->claim("w", f));
  EXPECT_EQ(q->counts(f).running, 3);
}

TYPED_TEST(JobQueueTest, RetriesWithBackoffThenDies) {
  QueuePolicy policy;
  policy.max_attempts = 3;
  policy.backoff_base = std::chrono::milliseconds(1);
  auto q = this->open(policy);
  Failure f;
  q->enqueue("a", "build", "{}", f);
  for (int attempt = 1; attempt <= 3; ++attempt) {
    const std::optional<Job> job = claim_within_a_second(*q, "w", f);
    ASSERT_TRUE(job.has_value()) << "attempt " << attempt << " " << f.message;
    EXPECT_EQ(job->attempts, attempt);
    EXPECT_TRUE(q->fail(*job, "io: flaky", true, f));
    if (attempt < 3) {
      EXPECT_EQ(q->counts(f).retry, 1);
    }
  }
  const QueueCounts c = q->counts(f);
  EXPECT_EQ(c.dead, 1);
  EXPECT_EQ(c.unfinished(), 0);
  auto dead = q->dead_jobs(f);
  ASSERT_EQ(dead.size(), 1u);
  EXPECT_EQ(dead[0].key, "a");
  EXPECT_EQ(dead[0].last_error, "io: flaky");
  EXPECT_EQ(dead[0].attempts, 3);
  EXPECT_TRUE(f.ok()) << f.message;
}

TYPED_TEST(JobQueueTest, RetryWaitsForItsBackoff) {
  QueuePolicy policy;
  policy.backoff_base = std::chrono::milliseconds(60'000);
  auto q = this->open(policy);
  Failure f;
  q->enqueue("a", "build", "{}", f);
  auto job = q->claim("w", f);
  ASSERT_TRUE(job);
  EXPECT_TRUE(q->fail(*job, "io: flaky", true, f));
  EXPECT_FALSE(q->claim("w", f));  // 30 to 90 seconds away
  EXPECT_EQ(q->counts(f).retry, 1);
  EXPECT_TRUE(f.ok()) << f.message;
}

TYPED_TEST(JobQueueTest, PermanentErrorsDieAtOnce) {
  auto q = this->open();
  Failure f;
  q->enqueue("a", "build", "{}", f);
  auto job = q->claim("w", f);
  ASSERT_TRUE(job);
  EXPECT_TRUE(q->fail(*job, "input_invalid: bad scene", false, f));
  EXPECT_EQ(q->counts(f).dead, 1);
  EXPECT_EQ(q->dead_jobs(f).at(0).attempts, 1);
}

TYPED_TEST(JobQueueTest, ExpiredLeaseIsReclaimedAndTheOldHolderIsFenced) {
  QueuePolicy policy;
  policy.lease = std::chrono::seconds(0);
  auto q = this->open(policy);
  Failure f;
  q->enqueue("a", "build", "{}", f);
  auto first = q->claim("w1", f);
  ASSERT_TRUE(first);
  std::this_thread::sleep_for(std::chrono::milliseconds(5));
  auto second = q->claim("w2", f);  // w1's lease has expired
  ASSERT_TRUE(second);
  EXPECT_EQ(second->attempts, 2);
  EXPECT_NE(second->lease_token, first->lease_token);
  EXPECT_FALSE(q->complete(*first, "{}", f));  // fenced
  EXPECT_FALSE(q->fail(*first, "io: late", true, f));
  EXPECT_TRUE(q->complete(*second, "{}", f));
  EXPECT_TRUE(f.ok()) << f.message;
}

// A job that kills its worker on every attempt (the lease expires unrenewed each time) ends
// dead after max_attempts claims, with a reason, instead of being claimed forever.
TYPED_TEST(JobQueueTest, AJobThatKillsItsWorkerEveryTimeEndsDead) {
  QueuePolicy policy;
  policy.lease = std::chrono::seconds(0);
  policy.max_attempts = 3;
  auto q = this->open(policy);
  Failure f;
  q->enqueue("poison", "build", "{}", f);
  q->enqueue("later", "build", "{}", f);
  for (int attempt = 1; attempt <= 3; ++attempt) {
    auto job = q->claim("w" + std::to_string(attempt), f);
    ASSERT_TRUE(job) << attempt;
    EXPECT_EQ(job->key, "poison");
    EXPECT_EQ(job->attempts, attempt);
    std::this_thread::sleep_for(std::chrono::milliseconds(5));  // "crash": never renewed
  }
  auto next = q->claim("w4", f);
  ASSERT_TRUE(next);
  EXPECT_EQ(next->key, "later");
  EXPECT_TRUE(q->complete(*next, "{}", f));
  const auto dead = q->dead_jobs(f);
  ASSERT_EQ(dead.size(), 1u);
  EXPECT_EQ(dead[0].key, "poison");
  EXPECT_EQ(dead[0].attempts, 3);
  EXPECT_EQ(dead[0].last_error, kLeaseLost);
  EXPECT_EQ(q->counts(f).unfinished(), 0);
  EXPECT_TRUE(f.ok()) << f.message;
}

// Heartbeat: renewing keeps a job leased past its original expiry (no one else can claim
// it); a stale token cannot renew, nor can the holder once the job is done.
TYPED_TEST(JobQueueTest, RenewedLeaseIsKeptAndStaleTokensCannotRenew) {
  QueuePolicy policy;
  policy.lease = std::chrono::seconds(1);
  auto q = this->open(policy);
  Failure f;
  q->enqueue("a", "build", "{}", f);
  auto job = q->claim("w1", f);
  ASSERT_TRUE(job);
  for (int beat = 0; beat < 3; ++beat) {
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    EXPECT_TRUE(q->renew(*job, f)) << "beat " << beat;
  }
  // 1.5 s after the claim, the 1 s lease still holds thanks to the renewals.
  EXPECT_FALSE(q->claim("w2", f));
  Job stale = *job;
  stale.lease_token = "not-the-token";
  EXPECT_FALSE(q->renew(stale, f));
  EXPECT_TRUE(q->complete(*job, "{}", f));
  EXPECT_FALSE(q->renew(*job, f));  // done: nothing to renew
  EXPECT_TRUE(f.ok()) << f.message;
}

// The heartbeat thread keeps a short lease alive across a long job, and notices a lease
// that is gone.
TYPED_TEST(JobQueueTest, HeartbeatKeepsALongJobLeasedAndNoticesALostLease) {
  QueuePolicy policy;
  policy.lease = std::chrono::seconds(1);
  auto q = this->open(policy);
  auto other = this->open(policy);
  Failure f;
  q->enqueue("a", "build", "{}", f);
  auto job = q->claim("w1", f);
  ASSERT_TRUE(job);
  {
    LeaseHeartbeat beat(*q, *job, std::chrono::milliseconds(250));
    std::this_thread::sleep_for(std::chrono::milliseconds(1600));  // longer than the lease
    EXPECT_FALSE(other->claim("w2", f));
    beat.stop();
    EXPECT_FALSE(beat.lost());
    EXPECT_GE(beat.beats(), 3);
  }
  Job stale = *job;
  stale.lease_token = "taken-over";
  LeaseHeartbeat lost(*q, stale, std::chrono::milliseconds(20));
  for (int wait = 0; wait < 100 && !lost.lost(); ++wait)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  EXPECT_TRUE(lost.lost());
  EXPECT_TRUE(q->complete(*job, "{}", f));
  EXPECT_TRUE(f.ok()) << f.message;
}

TYPED_TEST(JobQueueTest, TwoHandlesNeverClaimTheSameJob) {
  auto a = this->open();
  auto b = this->open();
  Failure f;
  for (int i = 0; i < 50; ++i) a->enqueue("job-" + std::to_string(i), "build", "{}", f);
  std::vector<std::string> got_a, got_b;
  std::thread ta([&] {
    Failure fa;
    while (auto j = a->claim("a", fa)) got_a.push_back(j->key);
  });
  std::thread tb([&] {
    Failure fb;
    while (auto j = b->claim("b", fb)) got_b.push_back(j->key);
  });
  ta.join();
  tb.join();
  EXPECT_EQ(got_a.size() + got_b.size(), 50u);
  for (const auto& k : got_a) EXPECT_EQ(std::count(got_b.begin(), got_b.end(), k), 0);
}

// Byte order, whatever the database's collation (the PostgreSQL test databases use ICU
// en-US, which sorts these keys differently): manifests list keys the same everywhere.
TYPED_TEST(JobQueueTest, ResultsAndDeadJobsAreInByteOrderOfKeys) {
  auto q = this->open();
  Failure f;
  const std::vector<std::string> keys{"b", "B", "a_b", "aB", "\xC3\xA9", "a b", "10", "9"};
  for (const auto& key : keys) q->enqueue(key, "build", "{}", f);
  for (std::size_t i = 0; i < keys.size(); ++i) {
    auto job = q->claim("w", f);
    ASSERT_TRUE(job) << f.message;
    if (i % 2 == 0)
      q->complete(*job, "{}", f);
    else
      q->fail(*job, "input_invalid: bad", false, f);
  }
  std::vector<std::string> done, dead;
  for (const auto& [key, result] : q->results(f)) done.push_back(key);
  for (const DeadJob& job : q->dead_jobs(f)) dead.push_back(job.key);
  EXPECT_EQ(done, (std::vector<std::string>{"10", "a_b", "b", "\xC3\xA9"}));
  EXPECT_EQ(dead, (std::vector<std::string>{"9", "B", "a b", "aB"}));
  EXPECT_TRUE(f.ok()) << f.message;
}

// Lease tokens and retry delays come from one generator seeded with policy.seed, drawn in
// the same order by every backend: one draw per successful claim, one per fail (dead or not).
TYPED_TEST(JobQueueTest, SeededDrawsAreTheSameOnEveryBackend) {
  QueuePolicy policy;
  policy.seed = 7;
  policy.backoff_base = std::chrono::milliseconds(1000);
  auto q = this->open(policy);
  const auto draw_of = [](const std::string& token) { return token.substr(token.rfind('-') + 1); };
  Failure f;
  q->enqueue("a", "build", "{}", f);
  q->enqueue("b", "build", "{}", f);
  const auto a = q->claim("w", f);
  const auto b = q->claim("w", f);
  ASSERT_TRUE(a && b) << f.message;
  EXPECT_FALSE(q->claim("w", f));  // nothing to claim: no draw
  EXPECT_TRUE(q->fail(*b, "io: flaky", true, f));
  EXPECT_TRUE(q->fail(*a, "input_invalid: bad", false, f));

  detail::QueueRandom reference(policy.seed);
  EXPECT_EQ(draw_of(a->lease_token), draw_of(reference.lease_token("w", 0)));
  EXPECT_EQ(draw_of(b->lease_token), draw_of(reference.lease_token("w", 0)));
  const std::int64_t delay_b = reference.retry_delay_ms(policy, 1);
  const std::int64_t delay_a = reference.retry_delay_ms(policy, 1);
  EXPECT_NE(delay_a, delay_b);
  for (const std::int64_t delay : {delay_a, delay_b}) {
    EXPECT_GE(delay, 500);
    EXPECT_LE(delay, 1500);
  }
  EXPECT_EQ(this->backend_.stored_retry_delay_ms("b"), delay_b);
  EXPECT_EQ(this->backend_.stored_retry_delay_ms("a"), delay_a);
  EXPECT_TRUE(f.ok()) << f.message;
}

// Claim order: priority (higher first), then runnable time, then enqueue order.
TYPED_TEST(JobQueueTest, HigherPriorityFirstThenOldest) {
  auto q = this->open();
  Failure f;
  q->enqueue("low", "build", "{}", f);  // priority 0: the default
  q->enqueue("high", "build", "{}", f, test::at_priority(5));
  q->enqueue("negative", "build", "{}", f, test::at_priority(-3));
  q->enqueue("mid", "build", "{}", f, test::at_priority(1));
  q->enqueue("high-later", "build", "{}", f, test::at_priority(5));
  EXPECT_FALSE(q->enqueue("low", "build", "{}", f, test::at_priority(100)));  // still a no-op
  std::vector<std::string> order;
  while (auto job = q->claim("w", f)) order.push_back(job->key);
  EXPECT_EQ(order, (std::vector<std::string>{"high", "high-later", "mid", "low", "negative"}));
  EXPECT_TRUE(f.ok()) << f.message;
}

// not_before: the job is not claimable before it, whatever its priority; once it is, it
// ranks by that time among jobs of its priority.
TYPED_TEST(JobQueueTest, NotBeforeIsRespected) {
  // Windows wide enough for a loaded machine: "later" becomes runnable 2 s after the enqueue,
  // "urgent-later" (higher priority) only in an hour.
  auto q = this->open();
  Failure f;
  const auto now = std::chrono::system_clock::now();
  q->enqueue("urgent-later", "build", "{}", f, test::at_priority(10, now + std::chrono::hours(1)));
  q->enqueue("past", "build", "{}", f, test::at_priority(0, now - std::chrono::hours(1)));
  q->enqueue("later", "build", "{}", f, test::at_priority(0, now + std::chrono::seconds(2)));
  auto first = q->claim("w", f);
  ASSERT_TRUE(first) << f.message;
  EXPECT_EQ(first->key, "past");  // a time gone by is runnable now
  if (std::chrono::system_clock::now() < now + std::chrono::milliseconds(1500)) {
    EXPECT_FALSE(q->claim("w", f));  // "later" is not due yet
  }
  EXPECT_EQ(q->counts(f).queued, 2);
  std::optional<Job> second;
  for (int wait = 0; wait < 100 && !second && f.ok(); ++wait) {  // up to 10 s
    second = q->claim("w", f);
    if (!second) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  ASSERT_TRUE(second) << f.message;
  EXPECT_EQ(second->key, "later");
  EXPECT_GE(std::chrono::system_clock::now(), now + std::chrono::seconds(2));
  EXPECT_FALSE(q->claim("w", f));  // the urgent job is an hour away
  EXPECT_EQ(q->counts(f).queued, 1);
  EXPECT_TRUE(f.ok()) << f.message;
}

// A released job is queued again at once with its priority; the attempt it had does not
// count (with one attempt allowed, it still completes); only the lease holder can release.
TYPED_TEST(JobQueueTest, ReleasePutsTheJobBackWithoutUsingAnAttempt) {
  QueuePolicy policy;
  policy.max_attempts = 1;
  auto q = this->open(policy);
  Failure f;
  q->enqueue("other", "build", "{}", f);
  q->enqueue("urgent", "build", "{}", f, test::at_priority(3));
  const auto job = q->claim("w1", f);
  ASSERT_TRUE(job) << f.message;
  EXPECT_EQ(job->key, "urgent");
  EXPECT_EQ(job->attempts, 1);
  Job stale = *job;
  stale.lease_token = "not-the-token";
  EXPECT_FALSE(q->release(stale, f));  // fenced
  EXPECT_EQ(q->counts(f).running, 1);
  EXPECT_TRUE(q->release(*job, f));
  EXPECT_FALSE(q->release(*job, f));  // no longer running
  const QueueCounts counts = q->counts(f);
  EXPECT_EQ(counts.queued, 2);
  EXPECT_EQ(counts.running, 0);
  EXPECT_FALSE(q->renew(*job, f));  // the released lease is gone: the old holder is fenced
  EXPECT_FALSE(q->complete(*job, "{}", f));
  const auto again = q->claim("w2", f);
  ASSERT_TRUE(again) << f.message;
  EXPECT_EQ(again->key, "urgent");  // still first: its priority stayed
  EXPECT_EQ(again->attempts, 1);    // the released attempt was not counted
  EXPECT_NE(again->lease_token, job->lease_token);
  EXPECT_FALSE(q->release(*job, f));  // a stale token cannot release the new lease
  EXPECT_TRUE(q->complete(*again, "{}", f));
  EXPECT_EQ(q->counts(f).done, 1);
  EXPECT_TRUE(q->dead_jobs(f).empty());
  EXPECT_TRUE(f.ok()) << f.message;
}

// A queue file made before priorities (schema version 1, as csgtile wrote it then) is
// migrated when opened: its jobs keep their state and run at priority 0.
TEST(SqliteQueueMigration, AVersionOneFileIsMigrated) {
  const test::TempDir dir("csgtile-queue-migration-");
  const auto path = dir.path() / "queue.sqlite";
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(db, R"sql(
CREATE TABLE schema_version (version INTEGER NOT NULL);
INSERT INTO schema_version VALUES (1);
CREATE TABLE jobs (
  id INTEGER PRIMARY KEY AUTOINCREMENT, key TEXT NOT NULL UNIQUE, kind TEXT NOT NULL,
  payload TEXT NOT NULL, state TEXT NOT NULL DEFAULT 'queued'
  CHECK (state IN ('queued','running','done','retry','dead')),
  attempts INTEGER NOT NULL DEFAULT 0, run_after_ms INTEGER NOT NULL DEFAULT 0,
  lease_token TEXT, lease_expires_ms INTEGER, worker TEXT, last_error TEXT, result TEXT,
  created_ms INTEGER NOT NULL, updated_ms INTEGER NOT NULL);
CREATE INDEX jobs_runnable ON jobs (state, run_after_ms, id);
INSERT INTO jobs (key, kind, payload, state, result, created_ms, updated_ms)
  VALUES ('old-done', 'build', '{}', 'done', '{"old":true}', 1, 1);
INSERT INTO jobs (key, kind, payload, created_ms, updated_ms) VALUES ('old-queued', 'build', '{}', 1, 1);
)sql",
                         nullptr, nullptr, nullptr),
            SQLITE_OK)
      << sqlite3_errmsg(db);
  sqlite3_close(db);

  Failure f;
  {
    // Opened by two workers starting together: one migrates, the other waits for its
    // BEGIN IMMEDIATE and finds the file migrated.
    std::unique_ptr<JobQueue> first, second;
    Failure second_failure;
    std::thread other([&] { second = open_sqlite_queue(path, {}, second_failure); });
    first = open_sqlite_queue(path, {}, f);
    other.join();
    ASSERT_TRUE(first && second) << f.message << second_failure.message;
    test::expect_old_jobs_kept_at_priority_zero(*first);
    EXPECT_EQ(second->counts(f).running, 2);
  }
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  sqlite3_stmt* statement = nullptr;
  sqlite3_prepare_v2(db, "SELECT group_concat(version) FROM schema_version", -1, &statement,
                     nullptr);
  ASSERT_EQ(sqlite3_step(statement), SQLITE_ROW);
  EXPECT_STREQ(reinterpret_cast<const char*>(sqlite3_column_text(statement, 0)), "2");
  sqlite3_finalize(statement);
  // A file from a newer csgtile is refused, not misread.
  sqlite3_exec(db, "UPDATE schema_version SET version = 3", nullptr, nullptr, nullptr);
  sqlite3_close(db);
  f = {};
  EXPECT_FALSE(open_sqlite_queue(path, {}, f));
  EXPECT_EQ(f.code, ErrorCode::Unsupported);
  EXPECT_NE(f.message.find("schema is version 3"), std::string::npos) << f.message;
}

}  // namespace
}  // namespace csgtile::worker
