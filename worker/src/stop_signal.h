#pragma once
// Graceful stop: SIGTERM (Kubernetes, systemd) and SIGINT (Ctrl-C) ask the worker to stop
// claiming jobs; the job running then finishes and the process exits 0. The queue keeps
// everything else, so running the same command again resumes.

namespace csgtile::worker {

/// Blocks SIGTERM and SIGINT in the calling thread (the first thing the command line does), so
/// that a stop asked for while a worker starts up waits for the handlers instead of killing it.
void hold_stop_signals();
/// Unblocks them: a signal held meanwhile is delivered now, with the default action unless
/// install_stop_signals() ran (commands other than run and worker).
void release_stop_signals();

/// Installs the handlers (idempotent), then releases held signals. A second signal of either kind restores the default
/// action, so a third one ends the process at once.
void install_stop_signals();

/// Whether a stop was asked for since install_stop_signals().
bool stop_requested();

}  // namespace csgtile::worker
