// `csgtile run CONFIG`: a whole run on the embedded SQLite queue.

#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "csgtile/worker/run.h"
#include "ops/worker_endpoint.h"
#include "stop_signal.h"

namespace csgtile::worker::detail {

void register_run(CLI::App& app, Action& action) {
  auto* cmd = app.add_subcommand("run",
                                 "Run a whole job on the embedded SQLite queue: one job per "
                                 "input, outputs under run.output");
  auto file = std::make_shared<std::string>();
  auto json = std::make_shared<bool>(false);
  cmd->add_option("CONFIG", *file, "YAML config file")->required();
  cmd->add_flag("--json", *json, "Print the run summary as one JSON object");
  auto listen = std::make_shared<std::string>();
  auto* listen_option = cmd->add_option(
      "--metrics-listen", *listen,
      "Serve /healthz, /readyz and /metrics on ADDR:PORT (e.g. 127.0.0.1:9464; \"off\" disables); "
      "overrides metrics.listen");
  auto index = std::make_shared<long long>(-1);
  auto* index_option = cmd->add_option(
      "--index", *index,
      "Run only input N (0-based) of run.inputs, without a shared queue: the run is named "
      "<run.name>-<N> and its private SQLite queue lives in the temporary directory (for a "
      "Kubernetes Indexed Job: --index $JOB_COMPLETION_INDEX)");
  cmd->callback([&action, file, json, listen, listen_option, index, index_option] {
    action = [file, json, listen, listen_option, index, index_option] {
      auto loaded = load_run_config(*file, RunChecks::CrsAndInputs);
      if (!loaded) return error_info(ErrorCode::ConfigInvalid).exit_code;
      if (index_option->count() > 0) {
        const auto n = static_cast<long long>(loaded->run.inputs.size());
        if (*index < 0 || *index >= n) {
          std::cerr << "csgtile run: --index " << *index << " is outside run.inputs (" << n
                    << " input(s): 0.." << n - 1 << ")\n";
          return error_info(ErrorCode::Usage).exit_code;
        }
        config::Config& c = *loaded;
        c.run.inputs = {c.run.inputs[static_cast<std::size_t>(*index)]};
        c.run.name += "-" + std::to_string(*index);
        c.queue.backend = config::QueueBackend::Sqlite;
        c.queue.sqlite_path =
            (std::filesystem::temp_directory_path() / ("csgtile-" + c.run.name + ".sqlite"))
                .string();
      }
      const config::Config& cfg = *loaded;
      Logger log(cfg.log.level, cfg.log.format);
      RunSummary summary;
      install_stop_signals();
      Failure started;
      const auto endpoint = ops::start_worker_endpoint(
          cfg, listen_option->count() > 0 ? std::optional<std::string>(*listen) : std::nullopt, log,
          started);
      if (!started.ok()) {
        log.error("run", started.message, {{"error", error_info(started.code).name}});
        return error_info(started.code).exit_code;
      }
      // A job released at shutdown ends the process inside the run: say so first.
      const auto on_forced_exit = [&](const std::string& job, bool released) {
        if (*json) {
          std::cout << nlohmann::ordered_json{{"run", cfg.run.name},
                                              {"stopped", true},
                                              {"job", job},
                                              {"released", released}}
                           .dump()
                    << "\n";
        } else {
          std::cout << "run " << cfg.run.name << " stopped; job " << job
                    << (released ? " released to the queue"
                                 : " not released (its lease will expire)")
                    << "; run again to resume\n";
        }
      };
      const Failure failure = run_embedded(cfg, log, summary, on_forced_exit);
      if (!failure.ok()) {
        log.error("run", failure.message, {{"error", error_info(failure.code).name}});
        return error_info(failure.code).exit_code;
      }
      if (summary.stopped) {
        if (*json) {
          nlohmann::ordered_json out{{"run", cfg.run.name},
                                     {"stopped", true},
                                     {"done", summary.counts.done},
                                     {"unfinished", summary.counts.unfinished()}};
          if (!summary.released_job.empty()) {
            out["job"] = summary.released_job;
            out["released"] = summary.released;
          }
          std::cout << out.dump() << "\n";
        } else {
          std::cout << "run " << cfg.run.name << " stopped: " << summary.counts.done
                    << " job(s) done, " << summary.counts.unfinished() << " left in the queue";
          if (!summary.released_job.empty()) {
            std::cout << " (job " << summary.released_job
                      << (summary.released ? " cancelled and released" : " cancelled") << ")";
          }
          std::cout << "; run again to resume\n";
        }
        return 0;
      }
      if (*json) {
        nlohmann::ordered_json out;
        out["run"] = cfg.run.name;
        out["done"] = summary.counts.done;
        out["dead"] = summary.counts.dead;
        out["manifest"] = summary.manifest.string();
        std::cout << out.dump() << "\n";
      } else {
        std::cout << "run " << cfg.run.name << ": " << summary.counts.done << " job(s) done, "
                  << summary.counts.dead << " dead\n";
        for (const DeadJob& d : summary.dead)
          std::cout << "  dead " << d.key << ": " << d.last_error << "\n";
        std::cout << "results: " << summary.run_dir.string()
                  << " (manifest: " << summary.manifest.string() << ")\n";
      }
      return summary.counts.dead > 0 ? error_info(ErrorCode::JobsFailed).exit_code : 0;
    };
  });
}

}  // namespace csgtile::worker::detail
