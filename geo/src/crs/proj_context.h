#pragma once
// PROJ plumbing shared by the CRS builders and the projection engine: one PJ_CONTEXT per
// thread (PROJ objects and contexts are not thread-safe) and an owner for PJ pointers.

#include <proj.h>

#include <string>

namespace csgtile::geo::detail {

/// This thread's PROJ context (logging off), taken on first use from the contexts of threads
/// that ended (or created), given back at thread exit. Thread-locals holding PJ objects must
/// call it before they are constructed, so they are destroyed before it is given back.
PJ_CONTEXT* proj_thread_context();

/// Owns a PJ (proj_destroy on destruction).
struct ProjObject {
  PJ* p = nullptr;
  explicit ProjObject(PJ* q = nullptr) : p(q) {}
  ~ProjObject() {
    if (p != nullptr) proj_destroy(p);
  }
  ProjObject(ProjObject&& o) noexcept : p(o.p) { o.p = nullptr; }
  ProjObject& operator=(ProjObject&& o) noexcept {
    if (this != &o) {
      if (p != nullptr) proj_destroy(p);
      p = o.p;
      o.p = nullptr;
    }
    return *this;
  }
  ProjObject(const ProjObject&) = delete;
  ProjObject& operator=(const ProjObject&) = delete;
  explicit operator bool() const { return p != nullptr; }
};

/// The last error PROJ reported on this thread's context, as text ("" when none).
std::string proj_last_error();

}  // namespace csgtile::geo::detail
