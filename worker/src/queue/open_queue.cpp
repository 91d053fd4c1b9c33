// The one place that turns the `queue:` section of a config into an open queue.

#include "csgtile/worker/queue.h"
#include "queue/postgres_connection.h"

namespace csgtile::worker {
namespace {

std::filesystem::path sqlite_path(const config::Config& config) {
  return config.queue.sqlite_path.empty()
             ? std::filesystem::path(config.run.output) / "queue.sqlite"
             : std::filesystem::path(config.queue.sqlite_path);
}

}  // namespace

QueuePolicy queue_policy(const config::Config& config) {
  QueuePolicy policy;
  policy.max_attempts = config.queue.max_attempts;
  policy.lease = std::chrono::seconds(config.queue.lease_seconds);
  policy.seed = config.run.seed;
  return policy;
}

std::unique_ptr<JobQueue> open_queue(const config::Config& config, Failure& failure,
                                     const config::Environment& env) {
  switch (config.queue.backend) {
    case config::QueueBackend::Sqlite:
      return open_sqlite_queue(sqlite_path(config), queue_policy(config), failure);
    case config::QueueBackend::Postgres: {
      if (config.queue.postgres_dsn.empty()) {
        failure = {ErrorCode::ConfigInvalid,
                   "queue.backend is postgres but queue.postgres_dsn is empty"};
        return nullptr;
      }
      PostgresOptions options;
      options.sslmode = config.queue.postgres_sslmode;
      options.sslrootcert = config.queue.postgres_sslrootcert;
      // Read here, not from the config file, so that the password stays out of files,
      // manifests and logs. libpq itself falls back to PGPASSWORD and ~/.pgpass.
      if (const auto password = env.find("CSGTILE_PG_PASSWORD"); password != env.end()) {
        options.password = password->second;
      }
      return open_postgres_queue(config.queue.postgres_dsn, queue_policy(config), failure, options);
    }
  }
  failure = {ErrorCode::Internal, "unknown queue backend"};
  return nullptr;
}

std::string describe_queue(const config::Config& config) {
  if (config.queue.backend == config::QueueBackend::Postgres) {
    const std::string target = detail::describe_postgres_target(config.queue.postgres_dsn);
    return "postgres " + (target.empty() ? std::string("(invalid connection string)") : target);
  }
  return sqlite_path(config).string();
}

}  // namespace csgtile::worker
