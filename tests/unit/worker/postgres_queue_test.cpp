// The PostgreSQL queue against a real PostgreSQL 15 server: concurrent claimers, leases on
// server time, a server crash, a dropped connection, schema migrations, passwords and TLS.
// The behaviour it shares with the SQLite queue is in queue_test.cpp.

#include <gtest/gtest.h>

#include <cstdlib>
#include <map>
#include <mutex>
#include <thread>

#include "csgtile/worker/queue.h"
#include "queue_backends.h"

namespace csgtile::worker {
namespace {

class PostgresQueueTest : public ::testing::Test {
 protected:
  void SetUp() override { CSGTILE_PREPARE_QUEUE_BACKEND(backend_); }

  std::unique_ptr<JobQueue> open(QueuePolicy policy = {}) {
    Failure f;
    auto q = backend_.open(policy, f);
    EXPECT_TRUE(f.ok()) << f.message;
    return q;
  }
  /// A fresh database besides the test's own.
  std::string another_database() {
    const std::string name = backend_.database() + "_other";
    EXPECT_TRUE(backend_.server().create_database(name)) << backend_.server().error();
    return name;
  }
  test::PostgresBackend backend_;
};

/// Sets (or, with nullptr, unsets) an environment variable for one scope.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const char* value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    if (value != nullptr)
      ::setenv(name, value, 1);
    else
      ::unsetenv(name);
  }
  ~ScopedEnv() {
    if (old_)
      ::setenv(name_.c_str(), old_->c_str(), 1);
    else
      ::unsetenv(name_.c_str());
  }
  ScopedEnv(const ScopedEnv&) = delete;
  ScopedEnv& operator=(const ScopedEnv&) = delete;

 private:
  std::string name_;
  std::optional<std::string> old_;
};

TEST_F(PostgresQueueTest, FourWorkersDoTwoHundredJobsEachExactlyOnce) {
  auto producer = open();
  Failure f;
  for (int i = 0; i < 200; ++i) producer->enqueue("job-" + std::to_string(i), "build", "{}", f);
  ASSERT_TRUE(f.ok()) << f.message;

  std::mutex mutex;
  std::map<std::string, int> claims;
  std::vector<std::string> errors;
  std::vector<std::thread> workers;
  for (int w = 0; w < 4; ++w) {
    workers.emplace_back([&, w] {
      Failure wf;
      auto q = backend_.open({}, wf);  // a connection of its own
      const std::string name = "w" + std::to_string(w);
      while (q && wf.ok()) {
        const auto job = q->claim(name, wf);
        if (!job) break;
        const bool completed = q->complete(*job, "{\"by\":\"" + name + "\"}", wf);
        const std::lock_guard lock(mutex);
        ++claims[job->key];
        if (!completed) errors.push_back("not completed: " + job->key);
      }
      const std::lock_guard lock(mutex);
      if (!wf.ok()) errors.push_back(wf.message);
    });
  }
  for (auto& worker : workers) worker.join();

  EXPECT_TRUE(errors.empty()) << (errors.empty() ? "" : errors.front());
  EXPECT_EQ(claims.size(), 200u);
  for (const auto& [key, n] : claims) EXPECT_EQ(n, 1) << key;
  const QueueCounts counts = producer->counts(f);
  EXPECT_EQ(counts.done, 200);
  EXPECT_EQ(counts.unfinished(), 0);
  EXPECT_EQ(producer->results(f).size(), 200u);
}

TEST_F(PostgresQueueTest, ExpiredLeaseGoesToAnotherWorkerAndTheFirstIsFenced) {
  QueuePolicy policy;
  policy.lease = std::chrono::seconds(1);
  auto first_worker = open(policy);
  auto second_worker = open(policy);
  Failure f;
  first_worker->enqueue("a", "build", "{}", f);
  const auto first = first_worker->claim("w1", f);
  ASSERT_TRUE(first);
  EXPECT_FALSE(second_worker->claim("w2", f));  // the lease holds
  std::this_thread::sleep_for(std::chrono::milliseconds(1200));
  const auto second = second_worker->claim("w2", f);
  ASSERT_TRUE(second);
  EXPECT_EQ(second->attempts, 2);
  EXPECT_FALSE(first_worker->complete(*first, "{\"by\":\"w1\"}", f));
  EXPECT_FALSE(first_worker->fail(*first, "io: late", true, f));
  EXPECT_TRUE(second_worker->complete(*second, "{\"by\":\"w2\"}", f));
  EXPECT_EQ(first_worker->results(f).at(0).second, "{\"by\":\"w2\"}");
  EXPECT_EQ(backend_.query("SELECT worker FROM csgtile_jobs"), "w2");
  EXPECT_TRUE(f.ok()) << f.message;
}

TEST_F(PostgresQueueTest, ServerCrashLosesNothing) {
  QueuePolicy policy;
  policy.backoff_base = std::chrono::milliseconds(600'000);
  auto q = open(policy);
  Failure f;
  for (int i = 0; i < 20; ++i) q->enqueue("job-" + std::to_string(i), "build", "{}", f);
  std::vector<Job> running;
  for (int i = 0; i < 13; ++i) {
    auto job = q->claim("w", f);
    ASSERT_TRUE(job) << f.message;
    if (i < 5)
      q->complete(*job, "{\"n\":" + std::to_string(i) + "}", f);
    else if (i < 8)
      q->fail(*job, "input_invalid: bad", false, f);
    else if (i < 10)
      q->fail(*job, "io: flaky", true, f);
    else
      running.push_back(*job);
  }
  ASSERT_TRUE(f.ok()) << f.message;
  const QueueCounts before = q->counts(f);
  EXPECT_EQ(before.done, 5);
  EXPECT_EQ(before.dead, 3);
  EXPECT_EQ(before.retry, 2);
  EXPECT_EQ(before.running, 3);
  EXPECT_EQ(before.queued, 7);
  const auto results_before = q->results(f);
  const auto dead_before = q->dead_jobs(f);

  ASSERT_TRUE(backend_.server().stop(/*crash=*/true)) << backend_.server().error();
  Failure down;
  q->counts(down);
  EXPECT_EQ(down.code, ErrorCode::Io) << down.message;
  EXPECT_TRUE(error_info(down.code).retryable);
  EXPECT_NE(down.message.find("lost the connection to PostgreSQL at"), std::string::npos)
      << down.message;
  ASSERT_TRUE(backend_.server().restart()) << backend_.server().error();

  // The same handle reconnects; a new one sees the same.
  Failure after;
  const QueueCounts counts = q->counts(after);
  ASSERT_TRUE(after.ok()) << after.message;
  EXPECT_EQ(counts.done, before.done);
  EXPECT_EQ(counts.dead, before.dead);
  EXPECT_EQ(counts.retry, before.retry);
  EXPECT_EQ(counts.running, before.running);
  EXPECT_EQ(counts.queued, before.queued);
  auto fresh = open(policy);
  EXPECT_EQ(fresh->results(after), results_before);
  ASSERT_EQ(fresh->dead_jobs(after).size(), dead_before.size());
  // Leases survive too: the holders can still finish, others cannot take them.
  EXPECT_TRUE(fresh->complete(running[0], "{}", after));
  const auto next = fresh->claim("w2", after);
  ASSERT_TRUE(next);
  EXPECT_EQ(next->key, "job-13");
  EXPECT_TRUE(after.ok()) << after.message;
}

TEST_F(PostgresQueueTest, ConnectionDroppedMidJobIsARetryableIoError) {
  auto q = open();
  Failure f;
  q->enqueue("a", "build", "{}", f);
  const auto job = q->claim("w", f);
  ASSERT_TRUE(job);
  // Another session ends the worker's connection while "the job runs".
  EXPECT_EQ(backend_.query("SELECT count(pg_terminate_backend(pid)) FROM pg_stat_activity "
                           "WHERE datname = current_database() AND pid <> pg_backend_pid() "
                           "AND application_name = 'csgtile'"),
            "1");
  Failure dropped;
  EXPECT_FALSE(q->complete(*job, "{}", dropped));
  EXPECT_EQ(dropped.code, ErrorCode::Io) << dropped.message;
  EXPECT_TRUE(error_info(dropped.code).retryable);
  EXPECT_NE(dropped.message.find("complete"), std::string::npos) << dropped.message;
  // The retry reconnects, and the lease is still the worker's.
  Failure retry;
  EXPECT_TRUE(q->complete(*job, "{}", retry)) << retry.message;
  EXPECT_EQ(q->counts(retry).done, 1);
}

TEST_F(PostgresQueueTest, SchemaIsMigratedOnceAndItsVersionRecorded) {
  for (int i = 0; i < 3; ++i) open();
  EXPECT_EQ(backend_.query("SELECT string_agg(version::text, ',' ORDER BY version) "
                           "FROM csgtile_schema_version"),
            "1,2");

  // Workers starting together on an empty database: the advisory lock serialises them.
  const std::string database = another_database();
  std::vector<std::thread> starters;
  std::vector<Failure> failures(6);
  for (auto& failure : failures) {
    starters.emplace_back([&] {
      auto q = open_postgres_queue(backend_.server().socket_conninfo(database), {}, failure);
    });
  }
  for (auto& starter : starters) starter.join();
  for (const Failure& failure : failures) EXPECT_TRUE(failure.ok()) << failure.message;
  Failure f;
  auto q = open_postgres_queue(backend_.server().socket_conninfo(database), {}, f);
  ASSERT_TRUE(q) << f.message;
  EXPECT_TRUE(q->enqueue("a", "build", "{}", f));
  EXPECT_EQ(q->counts(f).queued, 1);
}

TEST_F(PostgresQueueTest, FailedMigrationLeavesNothingBehind) {
  // A table of the same name that is not ours: migration 1 cannot create its own.
  EXPECT_EQ(backend_.query("CREATE TABLE csgtile_jobs (x integer)"), "<no row>");
  Failure f;
  EXPECT_FALSE(backend_.open({}, f));
  EXPECT_EQ(f.code, ErrorCode::Internal);
  EXPECT_NE(f.message.find("already exists"), std::string::npos) << f.message;
  EXPECT_EQ(backend_.query("SELECT to_regclass('csgtile_schema_version') IS NULL"), "t");
}

TEST_F(PostgresQueueTest, NewerSchemaIsRefused) {
  open();
  backend_.query("INSERT INTO csgtile_schema_version (version) VALUES (3)");
  Failure f;
  EXPECT_FALSE(backend_.open({}, f));
  EXPECT_EQ(f.code, ErrorCode::Unsupported);
  EXPECT_NE(f.message.find("schema is version 3"), std::string::npos) << f.message;
}

// A database of schema version 1 (before priorities, as csgtile made it then, with jobs in
// it) is migrated by the workers that open it, together: priority column and claim index
// added, version 2 recorded, the jobs kept.
TEST_F(PostgresQueueTest, AVersionOneDatabaseIsMigrated) {
  const char* const version_one[] = {
      "CREATE TABLE csgtile_schema_version ("
      "  version integer PRIMARY KEY, applied_at timestamptz NOT NULL DEFAULT now())",
      "INSERT INTO csgtile_schema_version (version) VALUES (1)",
      "CREATE TABLE csgtile_jobs ("
      "  id bigint GENERATED ALWAYS AS IDENTITY PRIMARY KEY, key text NOT NULL UNIQUE,"
      "  kind text NOT NULL, payload text NOT NULL, state text NOT NULL DEFAULT 'queued'"
      "  CHECK (state IN ('queued','running','done','retry','dead')),"
      "  attempts integer NOT NULL DEFAULT 0, run_after timestamptz NOT NULL DEFAULT '-infinity',"
      "  lease_token text, lease_expires timestamptz, worker text, last_error text, result text,"
      "  created_at timestamptz NOT NULL DEFAULT now(),"
      "  updated_at timestamptz NOT NULL DEFAULT now())",
      "CREATE INDEX csgtile_jobs_runnable ON csgtile_jobs (state, run_after, id)",
      "INSERT INTO csgtile_jobs (key, kind, payload, state, result)"
      "  VALUES ('old-done', 'build', '{}', 'done', '{\"old\":true}')",
      "INSERT INTO csgtile_jobs (key, kind, payload) VALUES ('old-queued', 'build', '{}')"};
  for (const char* statement : version_one) ASSERT_EQ(backend_.query(statement), "<no row>");

  std::vector<std::thread> starters;
  std::vector<Failure> failures(4);
  for (auto& failure : failures) {
    starters.emplace_back([&] { auto q = backend_.open({}, failure); });
  }
  for (auto& starter : starters) starter.join();
  for (const Failure& failure : failures) EXPECT_TRUE(failure.ok()) << failure.message;
  EXPECT_EQ(backend_.query("SELECT string_agg(version::text, ',' ORDER BY version) "
                           "FROM csgtile_schema_version"),
            "1,2");
  EXPECT_EQ(backend_.query("SELECT string_agg(key || '=' || priority, ',' ORDER BY id) "
                           "FROM csgtile_jobs"),
            "old-done=0,old-queued=0");
  EXPECT_EQ(backend_.query("SELECT to_regclass('csgtile_jobs_claim') IS NOT NULL"), "t");
  EXPECT_EQ(backend_.query("SELECT to_regclass('csgtile_jobs_runnable') IS NULL"), "t");

  test::expect_old_jobs_kept_at_priority_zero(*open());
}

// not_before is timed by the server's clock: the stored runnable time is the server's now()
// plus the delay asked for.
TEST_F(PostgresQueueTest, NotBeforeIsServerTime) {
  auto q = open();
  Failure f;
  q->enqueue("later", "build", "{}", f,
             test::at_priority(0, std::chrono::system_clock::now() + std::chrono::minutes(10)));
  ASSERT_TRUE(f.ok()) << f.message;
  const std::string minutes =
      backend_.query("SELECT round(extract(epoch FROM run_after - now()) / 60) FROM csgtile_jobs");
  EXPECT_EQ(minutes, "10");
  EXPECT_FALSE(q->claim("w", f));
}

TEST_F(PostgresQueueTest, PasswordComesFromOptionsOrTheEnvironmentAndIsNeverShown) {
  const ScopedEnv no_pgpass("PGPASSFILE", "/nonexistent");
  const ScopedEnv no_pgpassword("PGPASSWORD", nullptr);
  const std::string tcp = backend_.server().tcp_conninfo(backend_.database());
  const std::string where = "127.0.0.1:" + std::to_string(backend_.server().port());
  Failure f;

  EXPECT_FALSE(open_postgres_queue(tcp, {}, f));
  EXPECT_EQ(f.code, ErrorCode::Io);
  EXPECT_NE(f.message.find(where), std::string::npos) << f.message;

  PostgresOptions wrong;
  wrong.password = "not-the-password";
  f = {};
  EXPECT_FALSE(open_postgres_queue(tcp, {}, f, wrong));
  EXPECT_EQ(f.code, ErrorCode::Io);
  EXPECT_NE(f.message.find("password authentication failed"), std::string::npos) << f.message;
  EXPECT_EQ(f.message.find("not-the-password"), std::string::npos) << f.message;

  PostgresOptions right;
  right.password = test::kPostgresTestPassword;
  f = {};
  EXPECT_TRUE(open_postgres_queue(tcp, {}, f, right)) << f.message;
  {
    const ScopedEnv pgpassword("PGPASSWORD", test::kPostgresTestPassword);
    EXPECT_TRUE(open_postgres_queue(tcp, {}, f)) << f.message;
  }

  // Through the config: CSGTILE_PG_PASSWORD wins over PGPASSWORD.
  config::Config config;
  config.queue.backend = config::QueueBackend::Postgres;
  config.queue.postgres_dsn = tcp;
  const ScopedEnv pgpassword("PGPASSWORD", "not-the-password");
  f = {};
  EXPECT_FALSE(open_queue(config, f, {}));
  EXPECT_EQ(f.message.find("not-the-password"), std::string::npos) << f.message;
  f = {};
  auto q = open_queue(config, f, {{"CSGTILE_PG_PASSWORD", test::kPostgresTestPassword}});
  ASSERT_TRUE(q) << f.message;
  EXPECT_TRUE(q->enqueue("a", "build", "{}", f));
  EXPECT_EQ(describe_queue(config), "postgres " + where + "/" + backend_.database());
}

TEST_F(PostgresQueueTest, TlsOptionsReachTheConnection) {
  const std::filesystem::path certificate = backend_.server().tls_certificate();
  if (certificate.empty()) {
    if (test::postgres_required()) FAIL() << "the test server has no TLS (openssl missing)";
    GTEST_SKIP() << "the test server has no TLS: the openssl tool is missing";
  }
  const config::Environment env{{"CSGTILE_PG_PASSWORD", test::kPostgresTestPassword}};
  config::Config config;
  config.queue.backend = config::QueueBackend::Postgres;
  config.queue.postgres_dsn =
      backend_.server().tcp_conninfo(backend_.database()) + " sslmode=disable";
  Failure f;

  // The config's sslmode overrides the connection string's.
  config.queue.postgres_sslmode = "verify-full";
  config.queue.postgres_sslrootcert = certificate.string();
  auto q = open_queue(config, f, env);
  ASSERT_TRUE(q) << f.message;
  EXPECT_EQ(backend_.query("SELECT bool_and(ssl) FROM pg_stat_ssl JOIN pg_stat_activity "
                           "USING (pid) WHERE datname = current_database() "
                           "AND application_name = 'csgtile'"),
            "t");

  config.queue.postgres_sslrootcert = backend_.server().unrelated_certificate().string();
  f = {};
  EXPECT_FALSE(open_queue(config, f, env));
  EXPECT_EQ(f.code, ErrorCode::Io);
  EXPECT_NE(f.message.find("certificate verify failed"), std::string::npos) << f.message;
}

}  // namespace
}  // namespace csgtile::worker
