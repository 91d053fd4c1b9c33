#pragma once
// Graceful stop: SIGTERM (Kubernetes, systemd) and SIGINT (Ctrl-C) ask the worker to stop
// claiming jobs; the job running then finishes if it can within queue.grace_seconds of the
// signal, else it is released to the queue, and the process exits 0. The queue keeps
// everything else, so running the same command again resumes.

#include <chrono>
#include <optional>

namespace csgtile::worker {

/// Blocks SIGTERM and SIGINT in the calling thread (the first thing the command line does), so
/// that a stop asked for while a worker starts up waits for the handlers instead of killing it.
void hold_stop_signals();
/// Unblocks them: a signal held meanwhile is delivered now, with the default action unless
/// install_stop_signals() ran (commands other than run and worker).
void release_stop_signals();

/// Installs the handlers (idempotent), then releases held signals. A second signal of either kind
/// restores the default action, so a third one ends the process at once.
void install_stop_signals();

/// Whether a stop was asked for since install_stop_signals().
bool stop_requested();

/// When the first stop signal came (steady clock), or nullopt before one: grace periods are
/// measured from it, not from when the work loop noticed.
std::optional<std::chrono::steady_clock::time_point> stop_requested_at();

/// Ends the process at once with `status`: flushes stdout and stderr, then _Exit, running no
/// destructor and no atexit handler. For a worker that released its job at the end of the
/// grace period while the job's thread still runs: that thread can be neither joined (it may
/// run for a long time) nor outlived by the queue, config and logger it uses, which unwinding
/// would destroy under it. Safe for outputs: they are written to temporary files and renamed,
/// so an abandoned job leaves no partial result (a stray temporary file at worst).
[[noreturn]] void exit_leaving_threads(int status);

}  // namespace csgtile::worker
