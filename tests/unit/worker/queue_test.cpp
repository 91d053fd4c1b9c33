// The SQLite job queue: states, unique keys, leases, fencing, retries and dead jobs.

#include <gtest/gtest.h>

#include <filesystem>
#include <thread>

#include "csgtile/worker/queue.h"

namespace csgtile::worker {
namespace {

class SqliteQueueTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("csgtile-queue-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  std::unique_ptr<JobQueue> open(QueuePolicy policy = {}) {
    Failure f;
    auto q = open_sqlite_queue(dir_ / "queue.sqlite", policy, f);
    EXPECT_TRUE(f.ok()) << f.message;
    return q;
  }
  std::filesystem::path dir_;
};

TEST_F(SqliteQueueTest, EnqueueIsIdempotentPerKey) {
  auto q = open();
  Failure f;
  EXPECT_TRUE(q->enqueue("a", "build", "{}", f));
  EXPECT_FALSE(q->enqueue("a", "build", "{}", f));
  EXPECT_TRUE(q->enqueue("b", "build", "{}", f));
  EXPECT_EQ(q->counts(f).queued, 2);
}

TEST_F(SqliteQueueTest, ClaimCompleteAndFencing) {
  auto q = open();
  Failure f;
  q->enqueue("a", "build", "{\"x\":1}", f);
  auto job = q->claim("w1", f);
  ASSERT_TRUE(job.has_value());
  EXPECT_EQ(job->key, "a");
  EXPECT_EQ(job->attempts, 1);
  EXPECT_FALSE(q->claim("w2", f).has_value());  // leased
  Job stale = *job;
  stale.lease_token = "someone-else";
  EXPECT_FALSE(q->complete(stale, "{}", f));    // a wrong token cannot complete
  EXPECT_TRUE(q->complete(*job, "{\"ok\":true}", f));
  EXPECT_FALSE(q->complete(*job, "{}", f));     // done once
  EXPECT_EQ(q->counts(f).done, 1);
  auto results = q->results(f);
  ASSERT_EQ(results.size(), 1u);
  EXPECT_EQ(results[0].second, "{\"ok\":true}");
}

TEST_F(SqliteQueueTest, RetriesWithBackoffThenDies) {
  QueuePolicy policy;
  policy.max_attempts = 3;
  policy.backoff_base = std::chrono::milliseconds(1);
  auto q = open(policy);
  Failure f;
  q->enqueue("a", "build", "{}", f);
  for (int attempt = 1; attempt <= 3; ++attempt) {
    std::optional<Job> job;
    for (int wait = 0; wait < 200 && !job; ++wait) {
      job = q->claim("w", f);
      if (!job) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    ASSERT_TRUE(job.has_value()) << "attempt " << attempt;
    EXPECT_EQ(job->attempts, attempt);
    EXPECT_TRUE(q->fail(*job, "io: flaky", true, f));
  }
  const QueueCounts c = q->counts(f);
  EXPECT_EQ(c.dead, 1);
  EXPECT_EQ(c.unfinished(), 0);
  auto dead = q->dead_jobs(f);
  ASSERT_EQ(dead.size(), 1u);
  EXPECT_EQ(dead[0].last_error, "io: flaky");
  EXPECT_EQ(dead[0].attempts, 3);
}

TEST_F(SqliteQueueTest, PermanentErrorsDieAtOnce) {
  auto q = open();
  Failure f;
  q->enqueue("a", "build", "{}", f);
  auto job = q->claim("w", f);
  ASSERT_TRUE(job);
  EXPECT_TRUE(q->fail(*job, "input_invalid: bad scene", false, f));
  EXPECT_EQ(q->counts(f).dead, 1);
}

TEST_F(SqliteQueueTest, ExpiredLeaseIsReclaimedAndTheOldHolderIsFenced) {
  QueuePolicy policy;
  policy.lease = std::chrono::seconds(0);
  auto q = open(policy);
  Failure f;
  q->enqueue("a", "build", "{}", f);
  auto first = q->claim("w1", f);
  ASSERT_TRUE(first);
  std::this_thread::sleep_for(std::chrono::milliseconds(5));
  auto second = q->claim("w2", f);  // w1's lease has expired
  ASSERT_TRUE(second);
  EXPECT_EQ(second->attempts, 2);
  EXPECT_FALSE(q->complete(*first, "{}", f));  // fenced
  EXPECT_TRUE(q->complete(*second, "{}", f));
}

TEST_F(SqliteQueueTest, TwoHandlesOnOneFileNeverClaimTheSameJob) {
  auto a = open();
  auto b = open();
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

}  // namespace
}  // namespace csgtile::worker
