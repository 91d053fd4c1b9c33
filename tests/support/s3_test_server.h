#pragma once
/// \file
/// @20minutes/s3rver for tests (it checks AWS SigV4 signatures), started on 127.0.0.1
/// through tests/support/s3_server.cjs, and scoped environment variables for its
/// credentials (S3RVER / S3RVER). Header-only: the package's default location is the test
/// target's CSGTILE_S3RVER_DIR definition, which the environment's CSGTILE_S3RVER_DIR
/// overrides.

#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>

#include "background_process.h"
#include "test_commands.h"

namespace csgtile::test {

/// True when CSGTILE_REQUIRE_S3RVER=1: a missing s3rver then fails the tests that need it
/// instead of skipping them.
inline bool s3rver_required() {
  const char* env = std::getenv("CSGTILE_REQUIRE_S3RVER");
  return env != nullptr && std::string(env) == "1";
}

/// Starts s3rver serving `bucket`, its objects kept as files under `data_dir` (created).
/// Returns null with `why` set when the package is not installed: the caller skips (or
/// fails, when s3rver_required()). Otherwise the process, whose running() the caller
/// asserts (a server that does not start is a failure) and whose first_line() is its port.
inline std::unique_ptr<BackgroundProcess> start_s3rver(const std::filesystem::path& data_dir,
                                                       const std::string& bucket,
                                                       std::string& why) {
  const char* env = std::getenv("CSGTILE_S3RVER_DIR");
#ifdef CSGTILE_S3RVER_DIR
  const std::filesystem::path module = env != nullptr ? env : CSGTILE_S3RVER_DIR;
#else
  const std::filesystem::path module = env != nullptr ? env : "";
#endif
  if (!std::filesystem::exists(module / "package.json")) {
    why = "@20minutes/s3rver not found at '" + module.string() +
          "' (deploy/run-tests.sh installs it into build/npm)";
    return nullptr;
  }
  std::filesystem::create_directories(data_dir);
  auto server = std::make_unique<BackgroundProcess>(
      "exec node " +
      quoted(std::filesystem::path(CSGTILE_SOURCE_DIR) / "tests/support/s3_server.cjs") + " " +
      quoted(module) + " " + quoted(data_dir) + " " + bucket);
  return server;
}

/// Sets environment variables for its lifetime and restores the previous values after.
class ScopedEnv {
 public:
  explicit ScopedEnv(const std::map<std::string, std::string>& values) {
    for (const auto& [name, value] : values) {
      const char* old = std::getenv(name.c_str());
      saved_[name] = old ? std::optional<std::string>(old) : std::nullopt;
      setenv(name.c_str(), value.c_str(), 1);
    }
  }
  ~ScopedEnv() {
    for (const auto& [name, value] : saved_) {
      if (value)
        setenv(name.c_str(), value->c_str(), 1);
      else
        unsetenv(name.c_str());
    }
  }
  ScopedEnv(const ScopedEnv&) = delete;
  ScopedEnv& operator=(const ScopedEnv&) = delete;

 private:
  std::map<std::string, std::optional<std::string>> saved_;
};

}  // namespace csgtile::test
