#pragma once
// Small RAII wrappers over SQLite for the topology index writer and reader: a connection that
// closes itself and prepared statements that finalize themselves. Errors are Failures (Io) with
// SQLite's message.

#include <sqlite3.h>

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "csgtile/worker/errors.h"

namespace csgtile::worker::detail {

class SqliteDb {
 public:
  SqliteDb() = default;
  ~SqliteDb() { close(); }
  SqliteDb(const SqliteDb&) = delete;
  SqliteDb& operator=(const SqliteDb&) = delete;

  /// Opens `path` with sqlite3_open_v2 `flags`. Error: Io with SQLite's message.
  Failure open(const std::string& path, int flags) {
    close();
    path_ = path;
    if (sqlite3_open_v2(path.c_str(), &db_, flags, nullptr) != SQLITE_OK) {
      Failure st = failure("cannot open");
      close();
      return st;
    }
    sqlite3_extended_result_codes(db_, 1);
    return {};
  }
  /// Closes; returns false when SQLite refused (unfinalised statements: a bug).
  bool close() {
    if (db_ == nullptr) return true;
    const bool ok = sqlite3_close(db_) == SQLITE_OK;
    db_ = nullptr;
    return ok;
  }
  sqlite3* get() const { return db_; }

  /// Runs statements without results.
  Failure exec(const std::string& sql) {
    char* message = nullptr;
    if (sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &message) != SQLITE_OK) {
      std::string text = message != nullptr ? message : sqlite3_errmsg(db_);
      sqlite3_free(message);
      return {ErrorCode::Io, path_ + ": " + text + " (in: " + sql.substr(0, 80) + ")"};
    }
    return {};
  }

  Failure failure(const std::string& what) const {
    return {ErrorCode::Io,
            what + " " + path_ + ": " + (db_ != nullptr ? sqlite3_errmsg(db_) : "out of memory")};
  }
  const std::string& path() const { return path_; }

 private:
  sqlite3* db_ = nullptr;
  std::string path_;
};

class SqliteStatement {
 public:
  SqliteStatement(const SqliteDb& db, std::string_view sql) : db_(&db) {
    rc_ = sqlite3_prepare_v2(db.get(), sql.data(), static_cast<int>(sql.size()), &stmt_, nullptr);
  }
  ~SqliteStatement() { sqlite3_finalize(stmt_); }
  SqliteStatement(const SqliteStatement&) = delete;
  SqliteStatement& operator=(const SqliteStatement&) = delete;

  bool ok() const { return rc_ == SQLITE_OK && stmt_ != nullptr; }
  Failure status() const {
    return ok() ? Failure{} : db_->failure("cannot prepare a statement on");
  }

  SqliteStatement& bind(int i, std::int64_t v) {
    sqlite3_bind_int64(stmt_, i, v);
    return *this;
  }
  SqliteStatement& bind(int i, double v) {
    sqlite3_bind_double(stmt_, i, v);
    return *this;
  }
  SqliteStatement& bind(int i, std::string_view v) {
    sqlite3_bind_text(stmt_, i, v.data(), static_cast<int>(v.size()), SQLITE_TRANSIENT);
    return *this;
  }
  SqliteStatement& bind_blob(int i, const std::string& v) {
    sqlite3_bind_blob(stmt_, i, v.data(), static_cast<int>(v.size()), SQLITE_TRANSIENT);
    return *this;
  }
  SqliteStatement& bind_null(int i) {
    sqlite3_bind_null(stmt_, i);
    return *this;
  }
  /// NULL when empty.
  SqliteStatement& bind_text_or_null(int i, std::string_view v) {
    return v.empty() ? bind_null(i) : bind(i, v);
  }
  template <class T>
  SqliteStatement& bind(int i, const std::optional<T>& v) {
    return v ? bind(i, *v) : bind_null(i);
  }

  /// SQLITE_ROW, SQLITE_DONE or an error code.
  int step() { return sqlite3_step(stmt_); }
  /// Steps a statement without result rows, then resets it for the next bindings.
  Failure run() {
    const int rc = sqlite3_step(stmt_);
    sqlite3_reset(stmt_);
    sqlite3_clear_bindings(stmt_);
    if (rc != SQLITE_DONE) return db_->failure("cannot write");
    return {};
  }

  int columns() const { return sqlite3_column_count(stmt_); }
  bool is_null(int c) const { return sqlite3_column_type(stmt_, c) == SQLITE_NULL; }
  std::int64_t integer(int c) const { return sqlite3_column_int64(stmt_, c); }
  double real(int c) const { return sqlite3_column_double(stmt_, c); }
  std::string text(int c) const {
    const unsigned char* t = sqlite3_column_text(stmt_, c);
    return t == nullptr ? std::string()
                        : std::string(reinterpret_cast<const char*>(t),
                                      static_cast<std::size_t>(sqlite3_column_bytes(stmt_, c)));
  }
  std::optional<double> optional_real(int c) const {
    return is_null(c) ? std::nullopt : std::optional<double>(real(c));
  }
  sqlite3_stmt* get() const { return stmt_; }

 private:
  const SqliteDb* db_;
  sqlite3_stmt* stmt_ = nullptr;
  int rc_ = SQLITE_ERROR;
};

}  // namespace csgtile::worker::detail
