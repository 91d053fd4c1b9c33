#pragma once
// One libpq connection: parameterised statements, failures as typed errors, reconnection
// after a lost connection, and messages that never carry the password.

#include <libpq-fe.h>

#include <initializer_list>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "csgtile/worker/errors.h"
#include "csgtile/worker/queue.h"

namespace csgtile::worker::detail {

struct ResultDeleter {
  void operator()(PGresult* result) const { PQclear(result); }
};
using PgResult = std::unique_ptr<PGresult, ResultDeleter>;

/// The worker code of a PostgreSQL SQLSTATE: connection, shutdown, resource, lock and
/// serialization classes are Io (a retry may succeed); authorization and privilege are
/// ConfigInvalid; data exceptions InputInvalid; the rest Internal.
ErrorCode error_code_of_sqlstate(std::string_view sqlstate);

/// Every password written in `conninfo` (keyword `password=`, URI user:password@ or
/// ?password=), found even when the text does not parse, so that messages can hide them.
std::vector<std::string> passwords_in(std::string_view conninfo);

/// `message` with every non-empty secret replaced by "***".
std::string redact(std::string message, const std::vector<std::string>& secrets);

/// "HOST:PORT/DATABASE" of a conninfo (libpq defaults for what it leaves out); empty when it
/// does not parse.
std::string describe_postgres_target(const std::string& conninfo);

class PostgresConnection {
 public:
  /// Connects. On failure returns nullptr with ConfigInvalid (conninfo does not parse) or Io
  /// (the server cannot be reached or refuses: the message names host, port and database).
  static std::unique_ptr<PostgresConnection> open(const std::string& conninfo,
                                                  const PostgresOptions& options, Failure& failure);
  ~PostgresConnection();
  PostgresConnection(const PostgresConnection&) = delete;
  PostgresConnection& operator=(const PostgresConnection&) = delete;

  /// Reconnects when the connection was lost and rolls back a transaction left open by a
  /// failed call. Io when the server cannot be reached.
  bool ensure_open(Failure& failure);
  /// Runs one statement with text parameters $1..$n; nullptr and `failure` on error, where
  /// `what` names the operation.
  PgResult exec(const char* what, const char* sql, std::initializer_list<std::string> params,
                Failure& failure);
  /// Runs constant SQL text without parameters (may hold several statements).
  bool exec_script(const char* what, const char* sql, Failure& failure);
  /// Ends an open transaction after a failure; errors are ignored (the failure is reported).
  void rollback();

 private:
  PostgresConnection(PGconn* connection, std::vector<std::string> secrets, std::string target)
      : connection_(connection), secrets_(std::move(secrets)), target_(std::move(target)) {}
  bool check(const char* what, const PgResult& result, Failure& failure);
  std::string last_error() const;

  PGconn* connection_;
  std::vector<std::string> secrets_;
  std::string target_;  ///< "HOST:PORT/DATABASE" for messages
  bool lost_ = false;   ///< the session ended: reconnect before the next statement
};

}  // namespace csgtile::worker::detail
