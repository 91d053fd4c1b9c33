#pragma once
/// \file
/// A throwaway PostgreSQL 15 server for tests: initdb in a temporary directory, listening on
/// 127.0.0.1 at a free port and on a Unix socket in that directory; stopped and removed at
/// the end. As root, the server runs as the `postgres` user (initdb refuses root).
///
/// Role `csgtile`, password kPostgresTestPassword: trusted on the Unix socket, checked
/// (scram-sha-256) over TCP. When the `openssl` tool is there, TCP also offers TLS with a
/// self-signed certificate for 127.0.0.1.

#include <filesystem>
#include <string>

namespace csgtile::test {

inline constexpr const char* kPostgresTestPassword = "csgtile-test-secret";

class PostgresServer {
 public:
  PostgresServer() = default;
  ~PostgresServer();  ///< stops the server and removes its directory
  PostgresServer(const PostgresServer&) = delete;
  PostgresServer& operator=(const PostgresServer&) = delete;

  /// $CSGTILE_PG_BINDIR, else /usr/lib/postgresql/15/bin.
  static std::filesystem::path bin_dir();
  /// Whether initdb and pg_ctl are there.
  static bool installed();

  /// initdb and start. False with error() set when that fails.
  bool start();
  /// Stops the server: `-m fast`, or `-m immediate` when `crash` (no shutdown checkpoint, as
  /// after a power cut of the server process; the next start recovers from the WAL).
  bool stop(bool crash = false);
  /// Starts the stopped server again on the same directory and port.
  bool restart();
  /// Creates database `name` (owned by csgtile), collated by ICU's en-US rules.
  bool create_database(const std::string& name);

  int port() const { return port_; }
  /// The server's self-signed certificate (its own root), or empty without TLS.
  std::filesystem::path tls_certificate() const;
  /// A certificate of the same kind that did not sign the server's, or empty without TLS.
  std::filesystem::path unrelated_certificate() const;
  /// libpq keyword/value string for `database` over the Unix socket (no password needed).
  std::string socket_conninfo(const std::string& database) const;
  /// libpq keyword/value string for `database` over TCP to 127.0.0.1, without the password.
  std::string tcp_conninfo(const std::string& database) const;
  /// Why the last call failed, with the tail of the server log.
  const std::string& error() const { return error_; }

 private:
  bool run(const std::string& command, const std::string& what);
  bool pg_ctl_start();
  bool make_certificates();

  std::filesystem::path dir_;
  int port_ = 0;
  bool running_ = false;
  bool tls_ = false;
  std::string error_;
};

/// The test binary's one server, started on first use and stopped when the tests end (a gtest
/// environment). nullptr when PostgreSQL is not installed or does not start; `reason` says
/// why.
PostgresServer* shared_postgres_server(std::string& reason);

/// CSGTILE_REQUIRE_POSTGRES=1: a missing server fails the tests instead of skipping them.
bool postgres_required();

}  // namespace csgtile::test
