#include "postgres_server.h"

#include <gtest/gtest.h>
#include <netinet/in.h>
#include <pwd.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <memory>

#include "test_support.h"

namespace csgtile::test {
namespace {

std::string quote(const std::string& text) {
  std::string out = "'";
  for (char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

/// A port on 127.0.0.1 that was free a moment ago (the kernel's pick for port 0).
int free_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) return 0;
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t length = sizeof address;
  int port = 0;
  if (::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) == 0 &&
      ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length) == 0) {
    port = ntohs(address.sin_port);
  }
  ::close(fd);
  return port;
}

std::string tail(const std::filesystem::path& path) {
  std::string text = read_file(path);
  constexpr std::size_t kKeep = 2000;
  return text.size() > kKeep ? text.substr(text.size() - kKeep) : text;
}

/// Initdb refuses to run as root: as root, the server's commands run as `postgres`.
bool running_as_root() { return ::geteuid() == 0; }

}  // namespace

PostgresServer::~PostgresServer() {
  if (running_) stop();
  if (!dir_.empty()) {
    std::error_code ignored;
    std::filesystem::remove_all(dir_, ignored);
  }
}

std::filesystem::path PostgresServer::bin_dir() {
  const char* dir = std::getenv("CSGTILE_PG_BINDIR");
  return dir != nullptr && *dir != '\0' ? std::filesystem::path(dir)
                                        : std::filesystem::path("/usr/lib/postgresql/15/bin");
}

bool PostgresServer::installed() {
  return std::filesystem::exists(bin_dir() / "initdb") &&
         std::filesystem::exists(bin_dir() / "pg_ctl") &&
         std::filesystem::exists(bin_dir() / "createdb");
}

bool PostgresServer::run(const std::string& command, const std::string& what) {
  const std::string as_server = running_as_root() ? "runuser -u postgres -- " : "";
  const std::string line = as_server + "sh -c " + quote(command) + " >>" +
                           quote((dir_ / "commands.log").string()) + " 2>&1";
  const int status = std::system(line.c_str());
  if (status != -1 && WIFEXITED(status) && WEXITSTATUS(status) == 0) return true;
  error_ = what + " failed (" + line + ")\n--- commands.log\n" + tail(dir_ / "commands.log") +
           "\n--- server log\n" + tail(dir_ / "log");
  return false;
}

bool PostgresServer::start() {
  std::string pattern = (std::filesystem::temp_directory_path() / "csgtile-pg-XXXXXX").string();
  if (::mkdtemp(pattern.data()) == nullptr) {
    error_ = "cannot create a temporary directory";
    return false;
  }
  dir_ = pattern;
  {
    std::ofstream password(dir_ / "password");
    password << kPostgresTestPassword << "\n";
  }
  if (running_as_root()) {
    const passwd* user = ::getpwnam("postgres");
    if (user == nullptr || ::chown(dir_.c_str(), user->pw_uid, user->pw_gid) != 0 ||
        ::chown((dir_ / "password").c_str(), user->pw_uid, user->pw_gid) != 0) {
      error_ = "running as root, but cannot hand " + dir_.string() + " to user postgres";
      return false;
    }
  }
  // --no-sync only skips initdb's final flush; the server itself keeps fsync on, so the
  // crash tests see real WAL recovery.
  if (!run(quote((bin_dir() / "initdb").string()) + " -D " + quote((dir_ / "data").string()) +
               " -U csgtile --auth-local=trust --auth-host=scram-sha-256 --pwfile=" +
               quote((dir_ / "password").string()) + " -E UTF8 --locale=C.UTF-8 --no-sync",
           "initdb")) {
    return false;
  }
  tls_ = make_certificates();
  // The port may be taken between free_port() and the server's bind: try a few.
  for (int attempt = 0; attempt < 5; ++attempt) {
    port_ = free_port();
    if (port_ != 0 && pg_ctl_start()) return true;
  }
  return false;
}

bool PostgresServer::make_certificates() {
  if (!std::filesystem::exists("/usr/bin/openssl")) return false;
  for (const char* name : {"server", "unrelated"}) {
    const std::string base = (dir_ / name).string();
    if (!run("openssl req -x509 -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes -days 2"
             " -subj /CN=127.0.0.1 -addext subjectAltName=IP:127.0.0.1 -keyout " +
                 quote(base + ".key") + " -out " + quote(base + ".crt") + " && chmod 600 " +
                 quote(base + ".key"),
             "openssl req")) {
      return false;
    }
  }
  return true;
}

std::filesystem::path PostgresServer::tls_certificate() const {
  return tls_ ? dir_ / "server.crt" : std::filesystem::path();
}

std::filesystem::path PostgresServer::unrelated_certificate() const {
  return tls_ ? dir_ / "unrelated.crt" : std::filesystem::path();
}

bool PostgresServer::pg_ctl_start() {
  std::string options =
      "-p " + std::to_string(port_) + " -k " + dir_.string() + " -c listen_addresses=127.0.0.1";
  if (tls_) {
    options += " -c ssl=on -c ssl_cert_file=" + (dir_ / "server.crt").string() +
               " -c ssl_key_file=" + (dir_ / "server.key").string();
  }
  running_ =
      run(quote((bin_dir() / "pg_ctl").string()) + " -D " + quote((dir_ / "data").string()) +
              " -o " + quote(options) + " -l " + quote((dir_ / "log").string()) + " -w -t 60 start",
          "pg_ctl start");
  return running_;
}

bool PostgresServer::stop(bool crash) {
  const bool stopped =
      run(quote((bin_dir() / "pg_ctl").string()) + " -D " + quote((dir_ / "data").string()) +
              " -m " + (crash ? "immediate" : "fast") + " -w -t 60 stop",
          "pg_ctl stop");
  if (stopped) running_ = false;
  return stopped;
}

bool PostgresServer::restart() { return pg_ctl_start(); }

bool PostgresServer::create_database(const std::string& name) {
  // As the calling user: the socket trusts every local connection. A natural-language
  // collation (ICU en-US, as production databases often have) so that tests notice code that
  // relies on byte order without asking for it.
  const std::string line = quote((bin_dir() / "createdb").string()) + " -h " +
                           quote(dir_.string()) + " -p " + std::to_string(port_) +
                           " -U csgtile -T template0 --locale-provider=icu --icu-locale=en-US " +
                           quote(name) + " >>" + quote((dir_ / "createdb.log").string()) + " 2>&1";
  const int status = std::system(line.c_str());
  if (status != -1 && WIFEXITED(status) && WEXITSTATUS(status) == 0) return true;
  error_ = "createdb " + name + " failed: " + tail(dir_ / "createdb.log");
  return false;
}

std::string PostgresServer::socket_conninfo(const std::string& database) const {
  return "host=" + dir_.string() + " port=" + std::to_string(port_) +
         " user=csgtile dbname=" + database;
}

std::string PostgresServer::tcp_conninfo(const std::string& database) const {
  return "host=127.0.0.1 port=" + std::to_string(port_) + " user=csgtile dbname=" + database;
}

namespace {

struct SharedServer {
  bool tried = false;
  std::string failure;
  std::unique_ptr<PostgresServer> server;
};

SharedServer& shared() {
  static SharedServer state;
  return state;
}

/// Stops the shared server after the last test (of each --gtest_repeat round).
class PostgresEnvironment : public ::testing::Environment {
 public:
  void TearDown() override { shared() = SharedServer{}; }
};

[[maybe_unused]] ::testing::Environment* const kEnvironment =
    ::testing::AddGlobalTestEnvironment(new PostgresEnvironment);

}  // namespace

PostgresServer* shared_postgres_server(std::string& reason) {
  SharedServer& state = shared();
  if (!state.tried) {
    state.tried = true;
    if (!PostgresServer::installed()) {
      state.failure = "PostgreSQL 15 is not installed (no initdb/pg_ctl/createdb in " +
                      PostgresServer::bin_dir().string() +
                      "); apt-get install postgresql-15, or set CSGTILE_PG_BINDIR";
    } else {
      auto server = std::make_unique<PostgresServer>();
      if (server->start()) {
        state.server = std::move(server);
      } else {
        state.failure = "cannot start a PostgreSQL test server: " + server->error();
      }
    }
  }
  reason = state.failure;
  return state.server.get();
}

bool postgres_required() {
  const char* value = std::getenv("CSGTILE_REQUIRE_POSTGRES");
  return value != nullptr && std::string(value) == "1";
}

}  // namespace csgtile::test
