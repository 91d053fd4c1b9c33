// One PROJ context per thread, reused by the threads that come after it.

#include "crs/proj_context.h"

#include <mutex>
#include <vector>

namespace csgtile::geo::detail {

namespace {

// A new context opens PROJ's database again and starts with empty caches (about 15 ms on
// this project's machines), and the worker runs each job on a thread of its own. So a
// thread's context goes back to this pool when the thread ends, and the next thread takes
// it: one thread at a time uses each context, as PROJ requires.
class ContextPool {
 public:
  ContextPool() = default;
  ContextPool(const ContextPool&) = delete;
  ContextPool& operator=(const ContextPool&) = delete;
  ~ContextPool() {
    for (PJ_CONTEXT* ctx : free_) proj_context_destroy(ctx);
  }

  PJ_CONTEXT* take() {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      if (!free_.empty()) {
        PJ_CONTEXT* ctx = free_.back();
        free_.pop_back();
        return ctx;
      }
    }
    PJ_CONTEXT* ctx = proj_context_create();
    proj_log_level(ctx, PJ_LOG_NONE);
    return ctx;
  }

  void give(PJ_CONTEXT* ctx) {
    const std::lock_guard<std::mutex> lock(mutex_);
    free_.push_back(ctx);
  }

 private:
  std::mutex mutex_;
  std::vector<PJ_CONTEXT*> free_;
};

ContextPool& pool() {
  static ContextPool p;  // constructed before any thread's Context, so destroyed after them
  return p;
}

struct Context {
  PJ_CONTEXT* ctx = pool().take();
  Context() = default;
  ~Context() { pool().give(ctx); }
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;
};

}  // namespace

PJ_CONTEXT* proj_thread_context() {
  thread_local Context c;
  return c.ctx;
}

std::string proj_last_error() {
  PJ_CONTEXT* ctx = proj_thread_context();
  const int code = proj_context_errno(ctx);
  if (code == 0) return std::string();
  const char* text = proj_context_errno_string(ctx, code);
  return text != nullptr ? text : "PROJ error " + std::to_string(code);
}

}  // namespace csgtile::geo::detail
