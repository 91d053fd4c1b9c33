#pragma once
/// \file
/// The csgtile command line. Subcommands register here as their capabilities land.

namespace csgtile::worker {

/// Parses argv, runs the chosen subcommand and returns the process exit code (see the error
/// table in errors.h). Writes results to stdout and logs to stderr; never calls exit().
int run_cli(int argc, char** argv);

}  // namespace csgtile::worker
