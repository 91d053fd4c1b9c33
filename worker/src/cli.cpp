#include "csgtile/worker/cli.h"

#include <cstdio>
#include <exception>
#include <iostream>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "csgtile/worker/errors.h"
#include "stop_signal.h"

namespace csgtile::worker {

int detail::report_failure(const char* command, const Failure& failure, bool json,
                           nlohmann::ordered_json& out) {
  if (json) {
    out["error"] = std::string(error_info(failure.code).name) + ": " + failure.message;
    std::cout << out.dump(-1, ' ', false, nlohmann::ordered_json::error_handler_t::replace) << "\n";
  } else {
    std::fprintf(stderr, "csgtile %s: %s\n", command, failure.message.c_str());
  }
  return error_info(failure.code).exit_code;
}

int run_cli(int argc, char** argv) {
  // A SIGTERM while a worker starts up must drain it, not kill it: hold the stop signals
  // until `run`/`worker` install their handlers (other commands get the default action back).
  hold_stop_signals();
  CLI::App app{"csgtile: LIDAR tiles to CSG-BRep city models and topology indexes"};
  app.set_version_flag("--version", std::string("csgtile ") + CSGTILE_VERSION);
  app.require_subcommand(1);
  detail::Action action;
  detail::register_validate_config(app, action);
  detail::register_config(app, action);
  detail::register_bool(app, action);
  detail::register_run(app, action);
  detail::register_info(app, action);
  detail::register_synth(app, action);
  detail::register_query(app, action);
  detail::register_assemble(app, action);
  detail::register_inspect(app, action);
  detail::register_status(app, action);
  detail::register_enqueue(app, action);
  detail::register_worker(app, action);
  detail::register_fit(app, action);
  detail::register_tile(app, action);
  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {
    return app.exit(e);  // --help, --version: prints and returns 0
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return error_info(ErrorCode::Usage).exit_code;
  }
  if (app.got_subcommand("run") || app.got_subcommand("worker")) {
    install_stop_signals();
  } else {
    release_stop_signals();
  }
  try {
    return action ? action() : error_info(ErrorCode::Usage).exit_code;
  } catch (const std::exception& e) {
    // Third-party code below us may still throw (allocation failure, say): report, don't crash.
    std::fprintf(stderr, "csgtile: internal error: %s\n", e.what());
    return error_info(ErrorCode::Internal).exit_code;
  }
}

}  // namespace csgtile::worker
