// `csgtile enqueue CONFIG` and `csgtile worker CONFIG [--exit-when-idle]`: the two halves of
// `csgtile run` for queue-driven clusters. Any number of workers (processes, machines) share
// the config's queue; when one finds the queue finished it publishes the run (index,
// CityJSONSeq, 3D Tiles, manifest) — deterministic bytes, so several publishing is harmless.

#include <chrono>
#include <iostream>
#include <nlohmann/json.hpp>
#include <thread>

#include "commands.h"
#include "csgtile/worker/run.h"
#include "ops/worker_endpoint.h"
#include "stop_signal.h"

namespace csgtile::worker::detail {

void register_enqueue(CLI::App& app, Action& action) {
  auto* cmd = app.add_subcommand("enqueue",
                                 "Add a run's jobs (one per input) to the config's queue; "
                                 "jobs already there are left as they are");
  auto file = std::make_shared<std::string>();
  auto json = std::make_shared<bool>(false);
  cmd->add_option("CONFIG", *file, "YAML config file")->required();
  cmd->add_flag("--json", *json, "Print one JSON object");
  cmd->callback([&action, file, json] {
    action = [file, json] {
      const auto cfg = load_run_config(*file, RunChecks::CrsAndInputs);
      if (!cfg) return error_info(ErrorCode::ConfigInvalid).exit_code;
      Logger log(cfg->log.level, cfg->log.format);
      Failure failure;
      auto queue = open_queue(*cfg, failure);
      std::size_t added = 0;
      if (queue) failure = enqueue_run(*cfg, *queue, log, added);
      if (!queue || !failure.ok()) {
        log.error("enqueue", failure.message, {{"error", error_info(failure.code).name}});
        return error_info(failure.code).exit_code;
      }
      if (*json) {
        std::cout << nlohmann::ordered_json{{"run", cfg->run.name},
                                            {"added", added},
                                            {"inputs", cfg->run.inputs.size()}}
                         .dump()
                  << "\n";
      } else {
        std::cout << "run " << cfg->run.name << ": " << added << " job(s) added ("
                  << cfg->run.inputs.size() - added << " already queued)\n";
      }
      return 0;
    };
  });
}

void register_worker(CLI::App& app, Action& action) {
  auto* cmd =
      app.add_subcommand("worker",
                         "Work the config's queue: claim, run and complete jobs until "
                         "SIGTERM (or, with --exit-when-idle, until the queue is finished); "
                         "publish the run when the queue is finished");
  auto file = std::make_shared<std::string>();
  auto json = std::make_shared<bool>(false);
  auto idle = std::make_shared<bool>(false);
  cmd->add_option("CONFIG", *file, "YAML config file")->required();
  cmd->add_flag("--exit-when-idle", *idle,
                "Exit once no job is unfinished (after publishing the run)");
  cmd->add_flag("--json", *json, "Print one JSON summary object at exit");
  auto listen = std::make_shared<std::string>();
  auto* listen_option = cmd->add_option(
      "--metrics-listen", *listen,
      "Serve /healthz, /readyz and /metrics on ADDR:PORT (e.g. 127.0.0.1:9464; \"off\" disables); "
      "overrides metrics.listen");
  cmd->callback([&action, file, json, idle, listen, listen_option] {
    action = [file, json, idle, listen, listen_option] {
      const auto loaded = load_run_config(*file, RunChecks::CrsOnly);
      if (!loaded) return error_info(ErrorCode::ConfigInvalid).exit_code;
      const config::Config& cfg = *loaded;
      Logger log(cfg.log.level, cfg.log.format);
      install_stop_signals();
      Failure failure;
      // Before the queue: a bad address or a port in use fails at once, not after a claim.
      const auto endpoint = ops::start_worker_endpoint(
          cfg, listen_option->count() > 0 ? std::optional<std::string>(*listen) : std::nullopt, log,
          failure);
      if (!failure.ok()) {
        log.error("worker", failure.message, {{"error", error_info(failure.code).name}});
        return error_info(failure.code).exit_code;
      }
      auto queue = open_queue(cfg, failure);
      if (!queue) {
        log.error("worker", failure.message, {{"error", error_info(failure.code).name}});
        return error_info(failure.code).exit_code;
      }
      WorkOptions options;
      options.exit_when_idle = true;  // work_queue returns whenever the queue is finished
      WorkSummary work;
      RunSummary summary;
      bool published = false;
      // A job released at shutdown ends the process in work_queue: say so first.
      options.on_forced_exit = [&](const std::string& job, bool released) {
        if (*json) {
          std::cout << nlohmann::ordered_json{{"run", cfg.run.name},
                                              {"stopped", true},
                                              {"published", published},
                                              {"job", job},
                                              {"released", released}}
                           .dump()
                    << "\n";
        } else {
          std::cout << "worker stopped: run " << cfg.run.name << "; job " << job
                    << (released ? " released to the queue"
                                 : " not released (its lease will expire)")
                    << " at the end of the grace period\n";
        }
      };
      // The queue finished: publish (again only after more work), then exit or wait for more.
      while (true) {
        failure = work_queue(cfg, *queue, log, options, work);
        if (!failure.ok() || work.stopped) break;
        if (!published || work.jobs > 0) {
          failure = publish_run(cfg, *queue, log, summary);
          if (!failure.ok()) break;
          published = true;
          work.jobs = 0;
        }
        if (*idle) break;
        std::this_thread::sleep_for(std::chrono::seconds(1));
      }
      if (!failure.ok()) {
        log.error("worker", failure.message, {{"error", error_info(failure.code).name}});
        return error_info(failure.code).exit_code;
      }
      const QueueCounts c = queue->counts(failure);
      if (*json) {
        nlohmann::ordered_json out{{"run", cfg.run.name},    {"stopped", work.stopped},
                                   {"published", published}, {"done", c.done},
                                   {"dead", c.dead},         {"unfinished", c.unfinished()}};
        if (published) out["manifest"] = summary.manifest.string();
        if (!work.released_job.empty()) {
          out["job"] = work.released_job;
          out["released"] = work.released;
        }
        std::cout << out.dump() << "\n";
      } else {
        std::cout << "worker " << (work.stopped ? "stopped" : "finished") << ": run "
                  << cfg.run.name << " " << c.done << " done, " << c.dead << " dead, "
                  << c.unfinished() << " unfinished"
                  << (published ? "; published " + summary.manifest.string() : std::string());
        if (!work.released_job.empty()) {
          std::cout << "; job " << work.released_job
                    << (work.released ? " cancelled and released to the queue"
                                      : " cancelled, not released (its lease will expire)");
        }
        std::cout << "\n";
      }
      return 0;
    };
  });
}

}  // namespace csgtile::worker::detail
