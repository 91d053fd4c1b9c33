#include "queue/postgres_connection.h"

#include <cctype>
#include <map>

namespace csgtile::worker::detail {
namespace {

/// libpq's multi-line messages ("...failed: Connection refused\n\tIs the server running...")
/// as one line.
std::string one_line(const char* text) {
  std::string out;
  bool space = false;
  for (const char* p = text ? text : ""; *p != '\0'; ++p) {
    if (std::isspace(static_cast<unsigned char>(*p))) {
      space = !out.empty();
    } else {
      if (space) out += ' ';
      space = false;
      out += *p;
    }
  }
  return out;
}

/// Option name -> value of a libpq option array, with `fallback`'s values where it has none.
std::map<std::string, std::string> option_values(const PQconninfoOption* options,
                                                 const PQconninfoOption* fallback) {
  std::map<std::string, std::string> values;
  for (const PQconninfoOption* o = fallback; o != nullptr && o->keyword != nullptr; ++o) {
    if (o->val != nullptr) values[o->keyword] = o->val;
  }
  for (const PQconninfoOption* o = options; o != nullptr && o->keyword != nullptr; ++o) {
    if (o->val != nullptr && *o->val != '\0') values[o->keyword] = o->val;
  }
  return values;
}

std::string target_of(std::map<std::string, std::string> values) {
  std::string host = values["host"].empty() ? values["hostaddr"] : values["host"];
  if (host.empty()) host = "localhost";
  const std::string port = values["port"].empty() ? "5432" : values["port"];
  return host + ":" + port + "/" + values["dbname"];
}

/// The value starting at `at` in keyword/value text or a URI query: quoted (with backslash
/// escapes) or up to white space or '&'.
std::string value_at(std::string_view text, std::size_t at) {
  std::string value;
  if (at < text.size() && text[at] == '\'') {
    for (++at; at < text.size() && text[at] != '\''; ++at) {
      if (text[at] == '\\' && at + 1 < text.size()) ++at;
      value += text[at];
    }
    return value;
  }
  while (at < text.size() && !std::isspace(static_cast<unsigned char>(text[at])) &&
         text[at] != '&') {
    value += text[at++];
  }
  return value;
}

}  // namespace

ErrorCode error_code_of_sqlstate(std::string_view sqlstate) {
  const std::string_view sqlclass = sqlstate.substr(0, 2);
  if (sqlclass == "08" || sqlclass == "40" || sqlclass == "53" || sqlclass == "57" ||
      sqlclass == "58" || sqlstate == "55P03" || sqlstate == "25006") {
    return ErrorCode::Io;  // connection, rollback, resources, shutdown, system, lock, standby
  }
  if (sqlclass == "28" || sqlstate == "42501") return ErrorCode::ConfigInvalid;
  if (sqlclass == "22") return ErrorCode::InputInvalid;
  if (sqlstate == "0A000") return ErrorCode::Unsupported;
  return ErrorCode::Internal;
}

std::vector<std::string> passwords_in(std::string_view conninfo) {
  std::vector<std::string> found;
  constexpr std::string_view kKeyword = "password";
  for (std::size_t at = conninfo.find(kKeyword); at != std::string_view::npos;
       at = conninfo.find(kKeyword, at + 1)) {
    std::size_t i = at + kKeyword.size();
    while (i < conninfo.size() && conninfo[i] == ' ') ++i;
    if (i >= conninfo.size() || conninfo[i] != '=') continue;
    ++i;
    while (i < conninfo.size() && conninfo[i] == ' ') ++i;
    found.push_back(value_at(conninfo, i));
  }
  for (const std::string_view scheme : {"postgresql://", "postgres://"}) {
    if (!conninfo.starts_with(scheme)) continue;
    const std::string_view rest = conninfo.substr(scheme.size());
    const std::string_view authority = rest.substr(0, rest.find_first_of("/?"));
    const std::size_t at_sign = authority.rfind('@');
    if (at_sign == std::string_view::npos) continue;
    const std::string_view user_info = authority.substr(0, at_sign);
    const std::size_t colon = user_info.find(':');
    if (colon != std::string_view::npos) found.emplace_back(user_info.substr(colon + 1));
  }
  return found;
}

std::string redact(std::string message, const std::vector<std::string>& secrets) {
  for (const std::string& secret : secrets) {
    if (secret.empty()) continue;
    for (std::size_t at = message.find(secret); at != std::string::npos;
         at = message.find(secret, at + 3)) {
      message.replace(at, secret.size(), "***");
    }
  }
  return message;
}

std::string describe_postgres_target(const std::string& conninfo) {
  PQconninfoOption* parsed = PQconninfoParse(conninfo.c_str(), nullptr);
  if (parsed == nullptr) return "";
  PQconninfoOption* defaults = PQconndefaults();
  std::string target = target_of(option_values(parsed, defaults));
  PQconninfoFree(defaults);
  PQconninfoFree(parsed);
  return target;
}

std::unique_ptr<PostgresConnection> PostgresConnection::open(const std::string& conninfo,
                                                             const PostgresOptions& options,
                                                             Failure& failure) {
  std::vector<std::string> secrets = passwords_in(conninfo);
  secrets.push_back(options.password);
  char* parse_error = nullptr;
  PQconninfoOption* parsed = PQconninfoParse(conninfo.c_str(), &parse_error);
  if (parsed == nullptr) {
    failure = {ErrorCode::ConfigInvalid,
               redact("invalid PostgreSQL connection string: " + one_line(parse_error), secrets)};
    PQfreemem(parse_error);
    return nullptr;
  }
  for (const PQconninfoOption* o = parsed; o->keyword != nullptr; ++o) {
    if (std::string_view(o->keyword) == "password" && o->val != nullptr) {
      secrets.emplace_back(o->val);
    }
  }
  PQconninfoFree(parsed);

  // libpq keeps the last value of a repeated keyword, and the expanded conninfo ("dbname")
  // overrides what precedes it: defaults first, then the string, then the explicit options.
  // TCP keepalives and a user timeout by default (the string may override them): a worker cut
  // off from the server notices within about 30 s instead of the kernel's ~15 minutes, while
  // it holds the queue (a heartbeat renewal blocked on a dead link).
  std::vector<const char*> keywords{
      "connect_timeout",     "application_name", "keepalives",       "keepalives_idle",
      "keepalives_interval", "keepalives_count", "tcp_user_timeout", "dbname",
      "client_encoding"};
  std::vector<const char*> values{"10",    "csgtile",        "1",   "10", "5", "3",
                                  "30000", conninfo.c_str(), "UTF8"};
  const auto add = [&](const char* keyword, const std::string& value) {
    if (value.empty()) return;
    keywords.push_back(keyword);
    values.push_back(value.c_str());
  };
  add("sslmode", options.sslmode);
  add("sslrootcert", options.sslrootcert);
  add("password", options.password);
  keywords.push_back(nullptr);
  values.push_back(nullptr);

  PGconn* connection = PQconnectdbParams(keywords.data(), values.data(), 1);
  if (connection == nullptr) {
    failure = {ErrorCode::Io, "cannot connect to PostgreSQL: out of memory"};
    return nullptr;
  }
  PQconninfoOption* used = PQconninfo(connection);
  std::string target = target_of(option_values(used, nullptr));
  PQconninfoFree(used);
  // Server notices ("relation already exists, skipping") are not the worker's to print.
  PQsetNoticeProcessor(
      connection, [](void*, const char*) {}, nullptr);
  if (PQstatus(connection) != CONNECTION_OK) {
    failure = {ErrorCode::Io, redact("cannot connect to PostgreSQL at " + target + ": " +
                                         one_line(PQerrorMessage(connection)),
                                     secrets)};
    PQfinish(connection);
    return nullptr;
  }
  return std::unique_ptr<PostgresConnection>(
      new PostgresConnection(connection, std::move(secrets), std::move(target)));
}

PostgresConnection::~PostgresConnection() { PQfinish(connection_); }

bool PostgresConnection::ensure_open(Failure& failure) {
  if (lost_ || PQstatus(connection_) != CONNECTION_OK) {
    PQreset(connection_);
    lost_ = PQstatus(connection_) != CONNECTION_OK;
    if (PQstatus(connection_) != CONNECTION_OK) {
      failure = {ErrorCode::Io,
                 "lost the connection to PostgreSQL at " + target_ + ": " + last_error()};
      return false;
    }
  }
  const PGTransactionStatusType status = PQtransactionStatus(connection_);
  if (status == PQTRANS_INTRANS || status == PQTRANS_INERROR) rollback();
  return true;
}

PgResult PostgresConnection::exec(const char* what, const char* sql,
                                  std::initializer_list<std::string> params, Failure& failure) {
  std::vector<const char*> values;
  values.reserve(params.size());
  for (const std::string& param : params) values.push_back(param.c_str());
  PgResult result(PQexecParams(connection_, sql, static_cast<int>(values.size()), nullptr,
                               values.data(), nullptr, nullptr, 0));
  if (!check(what, result, failure)) return nullptr;
  return result;
}

bool PostgresConnection::exec_script(const char* what, const char* sql, Failure& failure) {
  const PgResult result(PQexec(connection_, sql));
  return check(what, result, failure);
}

void PostgresConnection::rollback() { PQclear(PQexec(connection_, "ROLLBACK")); }

bool PostgresConnection::check(const char* what, const PgResult& result, Failure& failure) {
  if (result) {
    const ExecStatusType status = PQresultStatus(result.get());
    if (status == PGRES_COMMAND_OK || status == PGRES_TUPLES_OK) return true;
  }
  const char* sqlstate = result ? PQresultErrorField(result.get(), PG_DIAG_SQLSTATE) : nullptr;
  // libpq may report a dead socket (no SQLSTATE) before it marks the connection bad; the
  // server's shutdown codes end the session too. Either way the next call reconnects.
  const std::string_view state = sqlstate != nullptr ? sqlstate : "";
  if (PQstatus(connection_) != CONNECTION_OK || state.empty() || state.starts_with("08") ||
      state == "57P01" || state == "57P02" || state == "57P03") {
    lost_ = true;
    failure = {ErrorCode::Io, "lost the connection to PostgreSQL at " + target_ + " during " +
                                  what + ": " + last_error()};
    return false;
  }
  const char* primary =
      result ? PQresultErrorField(result.get(), PG_DIAG_MESSAGE_PRIMARY) : nullptr;
  std::string message = "postgres: " + std::string(what) + ": ";
  message += primary != nullptr ? one_line(primary) : last_error();
  message += " (SQLSTATE " + std::string(state) + ")";
  failure = {error_code_of_sqlstate(state), redact(std::move(message), secrets_)};
  return false;
}

std::string PostgresConnection::last_error() const {
  return redact(one_line(PQerrorMessage(connection_)), secrets_);
}

}  // namespace csgtile::worker::detail
