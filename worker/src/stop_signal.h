#pragma once
// Graceful stop: SIGTERM (Kubernetes, systemd) and SIGINT (Ctrl-C) ask the worker to stop
// claiming jobs; the job running then finishes and the process exits 0. The queue keeps
// everything else, so running the same command again resumes.

namespace csgtile::worker {

/// Installs the handlers (idempotent). A second signal of either kind restores the default
/// action, so a third one ends the process at once.
void install_stop_signals();

/// Whether a stop was asked for since install_stop_signals().
bool stop_requested();

}  // namespace csgtile::worker
