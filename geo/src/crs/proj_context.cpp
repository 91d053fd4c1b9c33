// One PROJ context per thread.

#include "crs/proj_context.h"

namespace csgtile::geo::detail {

namespace {

struct Context {
  PJ_CONTEXT* ctx = proj_context_create();
  Context() { proj_log_level(ctx, PJ_LOG_NONE); }
  ~Context() { proj_context_destroy(ctx); }
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
