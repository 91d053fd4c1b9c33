#include "stop_signal.h"

#include <pthread.h>
#include <time.h>

#include <atomic>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <iostream>

namespace csgtile::worker {

namespace {

// A lock-free atomic rather than volatile sig_atomic_t: besides the handler and the main
// thread, the ops endpoint's threads read it (readiness), and only atomics are race-free there.
std::atomic<int> g_stop{0};
static_assert(std::atomic<int>::is_always_lock_free, "signal handlers need lock-free atomics");
// CLOCK_MONOTONIC nanoseconds of the first signal (std::chrono::steady_clock's clock on Linux;
// clock_gettime is async-signal-safe, steady_clock::now() is not promised to be).
std::atomic<std::int64_t> g_stop_ns{0};
static_assert(std::atomic<std::int64_t>::is_always_lock_free,
              "signal handlers need lock-free atomics");

extern "C" void on_stop_signal(int signal) {
  if (g_stop.load() != 0) {
    std::signal(signal, SIG_DFL);  // asked twice: the next one is not caught
  } else {
    timespec now{};
    clock_gettime(CLOCK_MONOTONIC, &now);
    g_stop_ns.store(static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec);
  }
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

std::optional<std::chrono::steady_clock::time_point> stop_requested_at() {
  if (g_stop.load() == 0) return std::nullopt;
  const std::int64_t ns = g_stop_ns.load();
  // The handler stores the time before the flag; 0 only if the clock itself failed.
  if (ns == 0) return std::chrono::steady_clock::now();
  return std::chrono::steady_clock::time_point(std::chrono::nanoseconds(ns));
}

void exit_leaving_threads(int status) {
  std::cout.flush();
  std::cerr.flush();
  std::fflush(nullptr);
  std::_Exit(status);
}

}  // namespace csgtile::worker
