// The queue factory: config → policy, backend and a description for logs.

#include <gtest/gtest.h>

#include "csgtile/worker/queue.h"
#include "test_support.h"

namespace csgtile::worker {
namespace {

TEST(OpenQueue, PolicyComesFromTheConfig) {
  config::Config config;
  config.queue.max_attempts = 7;
  config.queue.lease_seconds = 90;
  config.run.seed = 42;
  const QueuePolicy policy = queue_policy(config);
  EXPECT_EQ(policy.max_attempts, 7);
  EXPECT_EQ(policy.lease, std::chrono::seconds(90));
  EXPECT_EQ(policy.seed, 42u);
}

TEST(OpenQueue, SqliteByDefaultUnderTheOutputDirectory) {
  const test::TempDir dir("csgtile-open-queue-");
  config::Config config;
  config.run.output = (dir / "out").string();
  EXPECT_EQ(describe_queue(config), (dir / "out" / "queue.sqlite").string());
  Failure f;
  auto q = open_queue(config, f);
  ASSERT_TRUE(q) << f.message;
  EXPECT_TRUE(q->enqueue("a", "build", "{}", f));
  EXPECT_TRUE(std::filesystem::exists(dir / "out" / "queue.sqlite"));
}

TEST(OpenQueue, PostgresNeedsAConnectionString) {
  config::Config config;
  config.queue.backend = config::QueueBackend::Postgres;
  Failure f;
  EXPECT_FALSE(open_queue(config, f));
  EXPECT_EQ(f.code, ErrorCode::ConfigInvalid);
  EXPECT_EQ(f.message, "queue.backend is postgres but queue.postgres_dsn is empty");
}

TEST(OpenQueue, PostgresDescriptionLeavesCredentialsOut) {
  config::Config config;
  config.queue.backend = config::QueueBackend::Postgres;
  config.queue.postgres_dsn = "postgresql://worker:hunter2@db.internal/csgtile";
  EXPECT_EQ(describe_queue(config), "postgres db.internal:5432/csgtile");
  config.queue.postgres_dsn = "port";
  EXPECT_EQ(describe_queue(config), "postgres (invalid connection string)");
}

}  // namespace
}  // namespace csgtile::worker
