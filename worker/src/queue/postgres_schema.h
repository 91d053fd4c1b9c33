#pragma once
// The PostgreSQL queue's tables and their migrations.

#include "csgtile/worker/errors.h"
#include "queue/postgres_connection.h"

namespace csgtile::worker::detail {

/// The newest schema version this build knows (rows of csgtile_schema_version).
constexpr int kPostgresSchemaVersion = 2;

/// Brings the database to kPostgresSchemaVersion: creates csgtile_schema_version, then applies
/// each missing migration and records its version, all in one transaction that first takes an
/// advisory lock, so that workers starting together migrate once. Idempotent.
/// Errors: Unsupported when the database records a newer version; the connection's errors.
bool migrate_postgres_schema(PostgresConnection& connection, Failure& failure);

}  // namespace csgtile::worker::detail
