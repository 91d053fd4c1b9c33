#include "stop_signal.h"

#include <atomic>
#include <pthread.h>

#include <csignal>

namespace csgtile::worker {

namespace {

// A lock-free atomic rather than volatile sig_atomic_t: besides the handler and the main
// thread, the ops endpoint's threads read it (readiness), and only atomics are race-free there.
std::atomic<int> g_stop{0};
static_assert(std::atomic<int>::is_always_lock_free, "signal handlers need lock-free atomics");

extern "C" void on_stop_signal(int signal) {
  if (g_stop.load() != 0) std::signal(signal, SIG_DFL);  // asked twice: the next one is not caught
  g_stop.store(1);
}

}  // namespace

void install_stop_signals() {
  struct sigaction action {};
  action.sa_handler = on_stop_signal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = 0;  // no SA_RESTART: a sleep in the claim loop ends early
  sigaction(SIGTERM, &action, nullptr);
  sigaction(SIGINT, &action, nullptr);
  release_stop_signals();
}

namespace {
sigset_t stop_set() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGINT);
  return set;
}
}  // namespace

void hold_stop_signals() {
  const sigset_t set = stop_set();
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
}

void release_stop_signals() {
  const sigset_t set = stop_set();
  pthread_sigmask(SIG_UNBLOCK, &set, nullptr);
}

bool stop_requested() { return g_stop.load() != 0; }

}  // namespace csgtile::worker
