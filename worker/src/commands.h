#pragma once
// Subcommand registration: each command file adds its CLI11 subcommand and sets `run`.

#include <CLI/CLI.hpp>
#include <functional>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>

#include "checks/run_checks.h"
#include "csgtile/config/config.h"
#include "csgtile/worker/errors.h"

namespace csgtile::worker::detail {

/// Options shared by every subcommand.
struct GlobalOptions {
  bool json = false;
};

/// Loads a run config with its CSGTILE_* overrides for a command; on problems prints each
/// (file:line: key: message) to stderr and returns nullopt (exit with config_invalid).
/// Loads a config (and CSGTILE_* overrides) and checks it against the world
/// (checks/run_checks.h); prints every problem with key and line and returns nullopt on any.
std::optional<config::Config> load_run_config(const std::string& file, RunChecks what);

/// How a command reports its failure: with --json, `out` (what it had gathered) with "error":
/// "<code name>: <message>", one line on stdout; otherwise "csgtile <command>: <message>" on
/// stderr. Returns the exit code of the failure's code.
int report_failure(const char* command, const Failure& failure, bool json,
                   nlohmann::ordered_json& out);

/// A registered subcommand's action, returning the exit code.
using Action = std::function<int()>;

void register_validate_config(CLI::App& app, Action& action);
void register_config(CLI::App& app, Action& action);
void register_bool(CLI::App& app, Action& action);
void register_run(CLI::App& app, Action& action);
void register_info(CLI::App& app, Action& action);
void register_synth(CLI::App& app, Action& action);
void register_query(CLI::App& app, Action& action);
void register_assemble(CLI::App& app, Action& action);
void register_inspect(CLI::App& app, Action& action);
void register_status(CLI::App& app, Action& action);
void register_enqueue(CLI::App& app, Action& action);
void register_worker(CLI::App& app, Action& action);
void register_fit(CLI::App& app, Action& action);
void register_tile(CLI::App& app, Action& action);

}  // namespace csgtile::worker::detail
