// The PostgreSQL connection's pure parts: which errors retry, and passwords kept out of
// messages even when the connection string does not parse. No server needed.

#include <gtest/gtest.h>

#include "csgtile/worker/queue.h"
#include "queue/postgres_connection.h"

namespace csgtile::worker {
namespace {

using detail::error_code_of_sqlstate;

TEST(PostgresErrors, SqlstateClassesMapToRetryableOrNot) {
  EXPECT_EQ(error_code_of_sqlstate("08006"), ErrorCode::Io);             // connection failure
  EXPECT_EQ(error_code_of_sqlstate("57P01"), ErrorCode::Io);             // admin shutdown
  EXPECT_EQ(error_code_of_sqlstate("40001"), ErrorCode::Io);             // serialization failure
  EXPECT_EQ(error_code_of_sqlstate("53100"), ErrorCode::Io);             // disk full
  EXPECT_EQ(error_code_of_sqlstate("25006"), ErrorCode::Io);             // read-only (a standby)
  EXPECT_EQ(error_code_of_sqlstate("28P01"), ErrorCode::ConfigInvalid);  // bad password
  EXPECT_EQ(error_code_of_sqlstate("42501"), ErrorCode::ConfigInvalid);  // no privilege
  EXPECT_EQ(error_code_of_sqlstate("22021"), ErrorCode::InputInvalid);   // bad encoding
  EXPECT_EQ(error_code_of_sqlstate("42P07"), ErrorCode::Internal);       // duplicate table
  EXPECT_TRUE(error_info(error_code_of_sqlstate("08006")).retryable);
}

TEST(PostgresSecrets, PasswordsAreFoundInEveryForm) {
  using V = std::vector<std::string>;
  EXPECT_EQ(detail::passwords_in("host=h password=hunter2 user=u"), V{"hunter2"});
  EXPECT_EQ(detail::passwords_in("password = 'a b\\'c'"), V{"a b'c"});
  EXPECT_EQ(detail::passwords_in("postgresql://u:hunter2@h:5/db"), V{"hunter2"});
  EXPECT_EQ(detail::passwords_in("postgres://u:p%zz@h/db?password=two&sslmode=x"),
            (V{"two", "p%zz"}));
  EXPECT_EQ(detail::passwords_in("host=h user=password_admin"), V{});
  EXPECT_EQ(detail::redact("x hunter2 y hunter2", {"", "hunter2"}), "x *** y ***");
}

TEST(PostgresSecrets, DescribedTargetHasNoCredentials) {
  EXPECT_EQ(detail::describe_postgres_target("postgresql://u:hunter2@db.example:6543/jobs"),
            "db.example:6543/jobs");
  EXPECT_EQ(detail::describe_postgres_target("host=10.0.0.5 dbname=jobs password=hunter2"),
            "10.0.0.5:5432/jobs");
  EXPECT_EQ(detail::describe_postgres_target("not a conninfo"), "");
}

struct BadConnection {
  const char* name;
  std::string conninfo;
  ErrorCode code;
  const char* message_has;
};

class PostgresBadConnection : public ::testing::TestWithParam<BadConnection> {};

TEST_P(PostgresBadConnection, IsANamedErrorWithoutThePassword) {
  Failure f;
  EXPECT_FALSE(open_postgres_queue(GetParam().conninfo, {}, f));
  EXPECT_EQ(f.code, GetParam().code) << f.message;
  EXPECT_NE(f.message.find(GetParam().message_has), std::string::npos) << f.message;
  EXPECT_EQ(f.message.find("hunter2"), std::string::npos) << f.message;
  EXPECT_EQ(f.message.find("zzter"), std::string::npos) << f.message;
}

// Nothing listens on port 1 of the loopback interface.
INSTANTIATE_TEST_SUITE_P(
    Cases, PostgresBadConnection,
    ::testing::Values(
        BadConnection{"RefusedKeywordValue",
                      "host=127.0.0.1 port=1 dbname=jobs user=u password=hunter2", ErrorCode::Io,
                      "cannot connect to PostgreSQL at 127.0.0.1:1/jobs"},
        BadConnection{"RefusedUri", "postgresql://u:hunter2@127.0.0.1:1/jobs", ErrorCode::Io,
                      "Connection refused"},
        BadConnection{"MissingEquals", "host=127.0.0.1 port password=hunter2",
                      ErrorCode::ConfigInvalid, "invalid PostgreSQL connection string"},
        BadConnection{"UnknownKeyword", "hostname=h password=hunter2", ErrorCode::ConfigInvalid,
                      "invalid connection option \"hostname\""},
        BadConnection{"BadPercentEscapeInPassword", "postgresql://u:hun%zzter2@h/db",
                      ErrorCode::ConfigInvalid, "invalid percent-encoded token"}),
    [](const ::testing::TestParamInfo<BadConnection>& param) { return param.param.name; });

}  // namespace
}  // namespace csgtile::worker
