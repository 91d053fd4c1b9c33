// `csgtile status CONFIG [--json]`: the state of a run's queue (SQLite or PostgreSQL, as the
// config says): jobs per state, dead jobs with their last error, and progress. Read-only: an
// embedded queue that does not exist yet is reported, not created.

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>

#include "city/city_jobs.h"
#include "commands.h"
#include "csgtile/config/config.h"
#include "csgtile/worker/queue.h"

namespace csgtile::worker::detail {

void register_status(CLI::App& app, Action& action) {
  auto* cmd = app.add_subcommand("status",
                                 "Show a run's queue: jobs per state, dead jobs with "
                                 "their reasons, progress");
  auto file = std::make_shared<std::string>();
  auto json = std::make_shared<bool>(false);
  cmd->add_option("CONFIG", *file, "YAML config file")->required();
  cmd->add_flag("--json", *json, "Print one JSON object");
  cmd->callback([&action, file, json] {
    action = [file, json] {
      const auto loaded = load_run_config(*file, RunChecks::CrsOnly);
      if (!loaded) return error_info(ErrorCode::ConfigInvalid).exit_code;
      const config::Config& cfg = *loaded;
      const std::string where = describe_queue(cfg);
      if (cfg.queue.backend == config::QueueBackend::Sqlite && !std::filesystem::exists(where)) {
        std::cerr << "csgtile status: no queue at " << where << " (nothing enqueued yet)\n";
        return error_info(ErrorCode::InputInvalid).exit_code;
      }
      Failure failure;
      auto queue = open_queue(cfg, failure);
      QueueCounts c;
      std::vector<DeadJob> dead;
      if (queue) c = queue->counts(failure);
      if (queue && failure.ok()) dead = queue->dead_jobs(failure);
      if (!queue || !failure.ok()) {
        std::cerr << "csgtile status: " << failure.message << "\n";
        return error_info(failure.code).exit_code;
      }
      const std::int64_t total = c.queued + c.running + c.done + c.retry + c.dead;
      // A city run's progress through its graph (fit per tile → assemble per cell → index).
      std::optional<city::CityProgress> city;
      if (std::any_of(cfg.run.inputs.begin(), cfg.run.inputs.end(), city::is_tile_input)) {
        city.emplace();
        if (Failure f = city::city_progress(cfg, *queue, *city); !f.ok()) {
          std::cerr << "csgtile status: " << f.message << "\n";
          return error_info(f.code).exit_code;
        }
      }
      if (*json) {
        nlohmann::ordered_json out;
        out["run"] = cfg.run.name;
        out["queue"] = where;
        out["jobs"] = {{"queued", c.queued}, {"running", c.running}, {"retry", c.retry},
                       {"done", c.done},     {"dead", c.dead},       {"total", total}};
        out["finished"] = c.unfinished() == 0;
        if (city) {
          out["city"] = {{"tiles", city->tiles},           {"fits_done", city->fits_done},
                         {"fits_dead", city->fits_dead},   {"cells", city->cells},
                         {"cells_done", city->cells_done}, {"cells_dead", city->cells_dead},
                         {"indexed", city->indexed},       {"index_dead", city->index_dead}};
        }
        out["dead"] = nlohmann::ordered_json::array();
        for (const DeadJob& d : dead) {
          out["dead"].push_back(
              {{"key", d.key}, {"attempts", d.attempts}, {"error", d.last_error}});
        }
        std::cout << out.dump() << "\n";
      } else {
        std::cout << "run " << cfg.run.name << " (" << where << "): " << c.done + c.dead << " of "
                  << total << " job(s) finished — queued " << c.queued << ", running " << c.running
                  << ", retry " << c.retry << ", done " << c.done << ", dead " << c.dead << "\n";
        if (city) {
          std::cout << "  fit       " << city->fits_done << " of " << city->tiles
                    << " tile(s) done, " << city->fits_dead << " dead\n";
          std::cout << "  assemble  ";
          if (city->fits_done + city->fits_dead < city->tiles) {
            std::cout << "waiting for the fits\n";
          } else {
            std::cout << city->cells_done << " of " << city->cells << " cell(s) done, "
                      << city->cells_dead << " dead\n";
          }
          std::cout << "  index     "
                    << (city->indexed      ? "done"
                        : city->index_dead ? "dead"
                                           : "not yet")
                    << "\n";
        }
        for (const DeadJob& d : dead) {
          std::cout << "  dead " << d.key << " after " << d.attempts
                    << " attempt(s): " << d.last_error << "\n";
        }
      }
      return 0;
    };
  });
}

}  // namespace csgtile::worker::detail
