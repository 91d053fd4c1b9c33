#pragma once
// The queue backends the behavioural tests run against: each gives every test a fresh, empty
// store and opens handles on it. Also reads what the interface does not show (the stored
// retry delay), straight from the store.

#include <gtest/gtest.h>
#include <libpq-fe.h>
#include <sqlite3.h>

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "csgtile/worker/queue.h"
#include "postgres_server.h"
#include "test_support.h"

namespace csgtile::test {

/// Whether a backend is ready for a test; Skip and Fail carry the reason.
struct BackendStatus {
  enum Kind { Ready, Skip, Fail } kind = Ready;
  std::string message;
};

/// Enqueue options of a job at `priority`, not claimable before `not_before` when given.
inline worker::EnqueueOptions at_priority(
    int priority, std::optional<std::chrono::system_clock::time_point> not_before = {}) {
  worker::EnqueueOptions options;
  options.priority = priority;
  options.not_before = not_before;
  return options;
}

/// After a migration from version 1 of a store holding a done job ("old-done", result
/// {"old":true}) and a queued one ("old-queued"): the old jobs are kept, at priority 0, so a
/// new job at priority 2 is claimed first.
inline void expect_old_jobs_kept_at_priority_zero(worker::JobQueue& queue) {
  worker::Failure f;
  EXPECT_TRUE(queue.enqueue("new-urgent", "build", "{}", f, at_priority(2)));
  const auto urgent = queue.claim("w", f);
  const auto old = queue.claim("w", f);
  ASSERT_TRUE(urgent && old) << f.message;
  EXPECT_EQ(urgent->key, "new-urgent");
  EXPECT_EQ(old->key, "old-queued");
  EXPECT_EQ(queue.results(f).at(0).second, "{\"old\":true}");
  EXPECT_TRUE(f.ok()) << f.message;
}

/// A unique name for this process's next store: "<prefix><n>".
inline std::string next_store_name(const std::string& prefix) {
  static int counter = 0;
  return prefix + std::to_string(++counter);
}

/// A fresh SQLite file in a temporary directory.
class SqliteBackend {
 public:
  BackendStatus prepare() {
    dir_ = std::make_unique<TempDir>(next_store_name("csgtile-queue-") + "-");
    return {};
  }
  std::unique_ptr<worker::JobQueue> open(const worker::QueuePolicy& policy,
                                         worker::Failure& failure) const {
    return worker::open_sqlite_queue(dir_->path() / "queue.sqlite", policy, failure);
  }
  /// run_after - updated (ms) of the job `key`: the delay its last failure chose.
  std::int64_t stored_retry_delay_ms(const std::string& key) const {
    sqlite3* db = nullptr;
    std::int64_t delay = -1;
    if (sqlite3_open((dir_->path() / "queue.sqlite").c_str(), &db) == SQLITE_OK) {
      sqlite3_stmt* statement = nullptr;
      sqlite3_prepare_v2(db, "SELECT run_after_ms - updated_ms FROM jobs WHERE key = ?1", -1,
                         &statement, nullptr);
      sqlite3_bind_text(statement, 1, key.c_str(), -1, SQLITE_TRANSIENT);
      if (sqlite3_step(statement) == SQLITE_ROW) delay = sqlite3_column_int64(statement, 0);
      sqlite3_finalize(statement);
    }
    sqlite3_close(db);
    return delay;
  }

 private:
  std::unique_ptr<TempDir> dir_;
};

/// A fresh database on the test binary's PostgreSQL server, reached over its Unix socket.
class PostgresBackend {
 public:
  BackendStatus prepare() {
    std::string reason;
    server_ = shared_postgres_server(reason);
    if (server_ == nullptr) {
      if (postgres_required()) return {BackendStatus::Fail, reason};
      return {BackendStatus::Skip, reason + " (CSGTILE_REQUIRE_POSTGRES=1 makes this a failure)"};
    }
    database_ = next_store_name("queue_");
    if (!server_->create_database(database_)) return {BackendStatus::Fail, server_->error()};
    return {};
  }
  std::unique_ptr<worker::JobQueue> open(const worker::QueuePolicy& policy,
                                         worker::Failure& failure) const {
    return worker::open_postgres_queue(conninfo(), policy, failure);
  }
  std::string conninfo() const { return server_->socket_conninfo(database_); }
  PostgresServer& server() const { return *server_; }
  const std::string& database() const { return database_; }

  /// First column of the first row of `sql` ($1 = `param`), run on a connection of its own;
  /// "<error: ...>" when it fails, "<no row>" when there is none.
  std::string query(const std::string& sql, const std::string& param = "") const {
    PGconn* connection = PQconnectdb(conninfo().c_str());
    std::string value;
    const char* values[] = {param.c_str()};
    PGresult* result = PQexecParams(connection, sql.c_str(), param.empty() ? 0 : 1, nullptr, values,
                                    nullptr, nullptr, 0);
    const ExecStatusType status = PQresultStatus(result);
    if (status != PGRES_TUPLES_OK && status != PGRES_COMMAND_OK) {
      value = "<error: " + std::string(PQerrorMessage(connection)) + ">";
    } else if (PQntuples(result) == 0) {
      value = "<no row>";
    } else {
      value = PQgetvalue(result, 0, 0);
    }
    PQclear(result);
    PQfinish(connection);
    return value;
  }
  std::int64_t stored_retry_delay_ms(const std::string& key) const {
    const std::string delay = query(
        "SELECT (extract(epoch FROM run_after - updated_at) * 1000)::bigint FROM csgtile_jobs "
        "WHERE key = $1",
        key);
    return delay.starts_with("<") ? -1 : std::stoll(delay);
  }

 private:
  PostgresServer* server_ = nullptr;
  std::string database_;
};

/// Prepares `backend` for the running test: skips or fails it when the backend is missing.
#define CSGTILE_PREPARE_QUEUE_BACKEND(backend)                          \
  do {                                                                  \
    const ::csgtile::test::BackendStatus status_ = (backend).prepare(); \
    if (status_.kind == ::csgtile::test::BackendStatus::Fail) {         \
      FAIL() << status_.message;                                        \
    }                                                                   \
    if (status_.kind == ::csgtile::test::BackendStatus::Skip) {         \
      GTEST_SKIP() << status_.message;                                  \
    }                                                                   \
  } while (false)

}  // namespace csgtile::test
