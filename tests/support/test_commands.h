#pragma once
/// \file
/// Running external tools (validators, GDAL, node) from tests.

#include <filesystem>
#include <string>

namespace csgtile::test {

struct CommandResult {
  int exit_code = -1;  ///< -1 when the command could not run or did not exit normally
  std::string out;     ///< standard output (and standard error when merged)
};

/// Runs `command` through the shell; standard error is merged into `out` or discarded.
CommandResult run_command(const std::string& command, bool merge_stderr = true);

/// `p` in single quotes for the shell (paths without quotes of their own).
std::string quoted(const std::filesystem::path& p);

}  // namespace csgtile::test
