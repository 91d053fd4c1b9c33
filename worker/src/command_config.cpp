// `csgtile validate-config FILE` and `csgtile config schema`.

#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "csgtile/config/config.h"
#include "csgtile/worker/errors.h"

namespace csgtile::worker::detail {

namespace {
// The load, with the checks against the world appended when it loaded.
config::LoadResult load_checked(const std::string& file, RunChecks what) {
  auto loaded = config::load_file(file, config::from_process_environment());
  if (loaded.ok()) {
    auto found = check_run_config(loaded, what);
    loaded.problems.insert(loaded.problems.end(), found.begin(), found.end());
  }
  return loaded;
}
}  // namespace

std::optional<config::Config> load_run_config(const std::string& file, RunChecks what) {
  const auto loaded = load_checked(file, what);
  if (!loaded.ok()) {
    for (const auto& p : loaded.problems) std::cerr << config::format_problem(file, p) << "\n";
    return std::nullopt;
  }
  return *loaded.config;
}

void register_validate_config(CLI::App& app, Action& action) {
  auto* cmd = app.add_subcommand("validate-config",
                                 "Check a config file (and CSGTILE_* overrides); list every "
                                 "problem with its key and line");
  auto file = std::make_shared<std::string>();
  auto json = std::make_shared<bool>(false);
  auto no_inputs = std::make_shared<bool>(false);
  cmd->add_option("FILE", *file, "YAML config file")->required();
  cmd->add_flag("--json", *json, "Print the result as one JSON object");
  cmd->add_flag("--no-input-check", *no_inputs,
                "Do not check that local inputs exist (a config written for another machine, "
                "e.g. a pod's)");
  cmd->callback([&action, file, json, no_inputs] {
    action = [file, json, no_inputs] {
      const auto result =
          load_checked(*file, *no_inputs ? RunChecks::CrsOnly : RunChecks::CrsAndInputs);
      if (*json) {
        nlohmann::ordered_json out;
        out["file"] = *file;
        out["valid"] = result.ok();
        out["problems"] = nlohmann::json::array();
        for (const auto& p : result.problems) {
          out["problems"].push_back({{"path", p.path}, {"line", p.line}, {"message", p.message}});
        }
        if (result.ok()) out["config"] = nlohmann::json::parse(config::to_json(*result.config));
        std::cout << out.dump() << "\n";
      } else if (result.ok()) {
        std::cout << *file << ": valid\n";
      } else {
        for (const auto& p : result.problems) {
          std::cerr << config::format_problem(*file, p) << "\n";
        }
        std::cerr << *file << ": " << result.problems.size() << " problem(s)\n";
      }
      return result.ok() ? 0 : error_info(ErrorCode::ConfigInvalid).exit_code;
    };
  });
}

void register_config(CLI::App& app, Action& action) {
  auto* cmd = app.add_subcommand("config", "Configuration reference");
  cmd->require_subcommand(1);
  auto* schema = cmd->add_subcommand("schema", "Print the config's JSON Schema (draft-07)");
  schema->callback([&action] {
    action = [] {
      std::cout << config::schema_json();
      if (!config::schema_json().empty() && config::schema_json().back() != '\n') std::cout << "\n";
      return 0;
    };
  });
}

}  // namespace csgtile::worker::detail
