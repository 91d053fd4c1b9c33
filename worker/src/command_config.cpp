// `csgtile validate-config FILE` and `csgtile config schema`.

#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "csgtile/config/config.h"
#include "csgtile/worker/errors.h"

namespace csgtile::worker::detail {

std::optional<config::Config> load_run_config(const std::string& file) {
  const auto loaded = config::load_file(file, config::from_process_environment());
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
  cmd->add_option("FILE", *file, "YAML config file")->required();
  cmd->add_flag("--json", *json, "Print the result as one JSON object");
  cmd->callback([&action, file, json] {
    action = [file, json] {
      const auto result = config::load_file(*file, config::from_process_environment());
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
