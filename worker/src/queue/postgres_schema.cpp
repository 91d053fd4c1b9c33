#include "queue/postgres_schema.h"

#include <cstdlib>
#include <iterator>
#include <string>

namespace csgtile::worker::detail {
namespace {

// Key of the advisory lock held while migrating: "csgtile" in ASCII. Transaction-scoped, so a
// worker that dies mid-migration releases it with its rolled-back transaction.
constexpr const char* kMigrationLock = "27992474227723365";

struct Migration {
  int version;
  const char* sql;
};

// Migration v brings the schema from version v - 1 to v; never edit one that has shipped.
// Columns mirror the SQLite queue's; times are the server's (timestamptz).
constexpr Migration kMigrations[] = {
    {1, R"sql(
CREATE TABLE csgtile_jobs (
  id            bigint GENERATED ALWAYS AS IDENTITY PRIMARY KEY,
  key           text NOT NULL UNIQUE,
  kind          text NOT NULL,
  payload       text NOT NULL,
  state         text NOT NULL DEFAULT 'queued'
                CHECK (state IN ('queued','running','done','retry','dead')),
  attempts      integer NOT NULL DEFAULT 0,
  run_after     timestamptz NOT NULL DEFAULT '-infinity',
  lease_token   text,
  lease_expires timestamptz,
  worker        text,
  last_error    text,
  result        text,
  created_at    timestamptz NOT NULL DEFAULT now(),
  updated_at    timestamptz NOT NULL DEFAULT now()
);
CREATE INDEX csgtile_jobs_runnable ON csgtile_jobs (state, run_after, id);
)sql"},
    // Priorities. ADD COLUMN with a constant default rewrites no row. The claim index holds
    // only unfinished jobs, in claim order, so a claim reads the first rows of it however many
    // jobs are queued or done; the lease index serves the burial of jobs whose last attempt
    // lost its lease; the claim index replaces version 1's.
    {2, R"sql(
ALTER TABLE csgtile_jobs ADD COLUMN priority integer NOT NULL DEFAULT 0;
DROP INDEX IF EXISTS csgtile_jobs_runnable;
CREATE INDEX csgtile_jobs_claim ON csgtile_jobs (priority DESC, run_after, id)
  WHERE state IN ('queued','retry','running');
CREATE INDEX csgtile_jobs_leased ON csgtile_jobs (lease_expires) WHERE state = 'running';
)sql"},
};
static_assert(std::size(kMigrations) == kPostgresSchemaVersion);

}  // namespace

bool migrate_postgres_schema(PostgresConnection& connection, Failure& failure) {
  if (!connection.exec_script("migrate: begin", "BEGIN", failure)) return false;
  const auto abandon = [&] {
    connection.rollback();
    return false;
  };
  // The lock comes before anything else: CREATE TABLE IF NOT EXISTS alone is not safe when
  // two sessions run it at once.
  if (!connection.exec("migrate: lock", "SELECT pg_advisory_xact_lock($1::bigint)",
                       {kMigrationLock}, failure) ||
      !connection.exec_script("migrate: version table",
                              "CREATE TABLE IF NOT EXISTS csgtile_schema_version ("
                              " version integer PRIMARY KEY,"
                              " applied_at timestamptz NOT NULL DEFAULT now())",
                              failure)) {
    return abandon();
  }
  const PgResult current =
      connection.exec("migrate: read version",
                      "SELECT COALESCE(max(version), 0) FROM csgtile_schema_version", {}, failure);
  if (!current) return abandon();
  const int version = std::atoi(PQgetvalue(current.get(), 0, 0));
  if (version > kPostgresSchemaVersion) {
    failure = {ErrorCode::Unsupported,
               "the PostgreSQL queue's schema is version " + std::to_string(version) +
                   "; this csgtile knows versions up to " + std::to_string(kPostgresSchemaVersion) +
                   " (upgrade csgtile)"};
    return abandon();
  }
  for (const Migration& migration : kMigrations) {
    if (migration.version <= version) continue;
    if (!connection.exec_script("migrate: apply", migration.sql, failure) ||
        !connection.exec("migrate: record version",
                         "INSERT INTO csgtile_schema_version (version) VALUES ($1::integer)",
                         {std::to_string(migration.version)}, failure)) {
      return abandon();
    }
  }
  return connection.exec_script("migrate: commit", "COMMIT", failure) || abandon();
}

}  // namespace csgtile::worker::detail
