// Projections computed by PROJ: one PJ per thread and engine, transforms in batches.

#include "crs/proj_engine.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "crs/crs_internal.h"
#include "crs/proj_context.h"

namespace csgtile::geo::detail {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The PJs of this thread, by engine id (ids are never reused, so an entry can never be taken
// for another engine's). Least recently used first out; a few engines are alive at a time.
class ThreadCache {
 public:
  PJ* find(std::uint64_t id) {
    for (std::size_t i = 0; i < entries_.size(); ++i) {
      if (entries_[i].first == id) {
        if (i + 1 != entries_.size())
          std::rotate(entries_.begin() + i, entries_.begin() + i + 1, entries_.end());
        return entries_.back().second.p;
      }
    }
    return nullptr;
  }
  PJ* insert(std::uint64_t id, ProjObject pj) {
    if (entries_.size() >= kCapacity) entries_.erase(entries_.begin());
    entries_.emplace_back(id, std::move(pj));
    return entries_.back().second.p;
  }

 private:
  static constexpr std::size_t kCapacity = 16;
  std::vector<std::pair<std::uint64_t, ProjObject>> entries_;
};

ThreadCache& thread_cache() {
  // The thread's context first: thread-locals end in reverse order, so the cache's objects
  // are destroyed before their context goes back to the pool for another thread.
  (void)proj_thread_context();
  thread_local ThreadCache cache;
  return cache;
}

std::uint64_t next_engine_id() {
  static std::atomic<std::uint64_t> next{1};
  return next.fetch_add(1, std::memory_order_relaxed);
}

// A PJ for the string on this thread's context, or null with PROJ's reason in `why`.
ProjObject create_any(const std::string& definition, std::string* why) {
  ProjObject pj(proj_create(proj_thread_context(), definition.c_str()));
  if (!pj && why != nullptr) *why = proj_last_error();
  return pj;
}

// As create_any, and checks that it is a projection (geodetic in, metres out).
ProjObject create(const std::string& definition, std::string* why) {
  ProjObject pj(proj_create(proj_thread_context(), definition.c_str()));
  if (!pj) {
    if (why != nullptr) *why = proj_last_error();
    return pj;
  }
  const PJ_TYPE type = proj_get_type(pj.p);
  const bool operation = type == PJ_TYPE_CONVERSION || type == PJ_TYPE_TRANSFORMATION ||
                         type == PJ_TYPE_CONCATENATED_OPERATION ||
                         type == PJ_TYPE_OTHER_COORDINATE_OPERATION;
  if (!operation || proj_angular_input(pj.p, PJ_FWD) == 0 ||
      proj_angular_output(pj.p, PJ_FWD) != 0) {
    if (why != nullptr) *why = "not a projection from geodetic coordinates to metres";
    return ProjObject();
  }
  return pj;
}

// One PJ per thread for a definition, built on first use (ids are never reused).
class ThreadPj {
 public:
  // `projection`: the PJ must be a projection (geodetic in, metres out), as checked once.
  ThreadPj(std::string definition, bool projection)
      : definition_(std::move(definition)), id_(next_engine_id()), projection_(projection) {}
  PJ* get() const {
    ThreadCache& cache = thread_cache();
    if (PJ* found = cache.find(id_)) return found;
    std::string why;
    ProjObject made = projection_ ? create(definition_, &why) : create_any(definition_, &why);
    if (!made) throw DomainError("PROJ refused '" + definition_ + "' on this thread: " + why);
    return cache.insert(id_, std::move(made));
  }

 private:
  std::string definition_;
  std::uint64_t id_;
  bool projection_;
};

// PROJ's reason for the last failure on `p` (its error number, then reset), or `fallback`.
std::string pj_reason(PJ* p, const char* fallback) {
  const int code = proj_errno(p);
  proj_errno_reset(p);
  const char* text = code != 0 ? proj_context_errno_string(proj_thread_context(), code) : nullptr;
  return text != nullptr ? text : fallback;
}

class ProjEngine final : public ProjectionEngine {
 public:
  explicit ProjEngine(std::string definition) : pj_(std::move(definition), true) {}

  void forward(double lat, double lon, double& easting, double& northing) const override {
    PJ_COORD c = proj_coord(lon * kDegree, lat * kDegree, 0.0, 0.0);
    PJ_COORD r = proj_trans(pj(), PJ_FWD, c);
    if (!std::isfinite(r.xy.x) || !std::isfinite(r.xy.y) || r.xy.x == HUGE_VAL) {
      throw DomainError("latitude " + format_number(lat) + ", longitude " + format_number(lon) +
                        " cannot be projected by PROJ (" + reason() + ")");
    }
    easting = r.xy.x;
    northing = r.xy.y;
  }

  void reverse(double easting, double northing, double& lat, double& lon) const override {
    PJ_COORD c = proj_coord(easting, northing, 0.0, 0.0);
    PJ_COORD r = proj_trans(pj(), PJ_INV, c);
    if (!std::isfinite(r.lp.lam) || !std::isfinite(r.lp.phi) || r.lp.lam == HUGE_VAL) {
      throw DomainError("easting " + format_number(easting) + ", northing " +
                        format_number(northing) + " has no geodetic coordinates in PROJ (" +
                        reason() + ")");
    }
    lat = r.lp.phi / kDegree;
    lon = r.lp.lam / kDegree;
  }

  void reverse_many(double* x, double* y, std::size_t count) const override {
    if (count == 0) return;
    PJ* p = pj();
    proj_errno_reset(p);
    proj_trans_generic(p, PJ_INV, x, sizeof(double), count, y, sizeof(double), count, nullptr, 0, 0,
                       nullptr, 0, 0);
    for (std::size_t i = 0; i < count; ++i) {
      if (!std::isfinite(x[i]) || !std::isfinite(y[i]) || x[i] == HUGE_VAL) {
        x[i] = y[i] = kNaN;
        continue;
      }
      const double lon = x[i] / kDegree;
      x[i] = y[i] / kDegree;  // latitude
      y[i] = lon;
    }
  }

 private:
  PJ* pj() const { return pj_.get(); }
  std::string reason() const { return pj_reason(pj(), "outside the projection's domain"); }

  ThreadPj pj_;
};

class ProjGeodeticTransform final : public GeodeticTransform {
 public:
  explicit ProjGeodeticTransform(std::string pipeline) : pj_(std::move(pipeline), false) {}
  void forward(double& lat, double& lon, double& h) const override { run(PJ_FWD, lat, lon, h); }
  void inverse(double& lat, double& lon, double& h) const override { run(PJ_INV, lat, lon, h); }

 private:
  void run(PJ_DIRECTION direction, double& lat, double& lon, double& h) const {
    PJ* p = pj_.get();
    PJ_COORD c = proj_coord(lon, lat, h, 0.0);
    PJ_COORD r = proj_trans(p, direction, c);
    if (!std::isfinite(r.lpzt.lam) || !std::isfinite(r.lpzt.phi) || r.lpzt.lam == HUGE_VAL) {
      throw DomainError("latitude " + format_number(lat) + ", longitude " + format_number(lon) +
                        ": PROJ's datum transformation fails there (" +
                        pj_reason(p, "outside its area or grid") + ")");
    }
    lon = r.lpzt.lam;
    lat = r.lpzt.phi;
    h = std::isfinite(r.lpzt.z) ? r.lpzt.z : h;
  }
  ThreadPj pj_;
};

}  // namespace

kernel::Result<std::shared_ptr<const GeodeticTransform>> make_geodetic_transform(
    const std::string& pipeline) {
  std::string why;
  ProjObject pj = create_any(pipeline, &why);
  if (!pj) {
    return kernel::Error{kernel::ErrorCode::InvalidArgument,
                         "PROJ refuses the datum transformation '" + pipeline + "': " + why};
  }
  return std::shared_ptr<const GeodeticTransform>(new ProjGeodeticTransform(pipeline));
}

kernel::Result<std::unique_ptr<ProjectionEngine>> make_proj_engine(const std::string& proj_string) {
  std::string why;
  if (!create(proj_string, &why)) {
    return kernel::Error{kernel::ErrorCode::InvalidArgument,
                         "PROJ refuses the projection '" + proj_string + "': " + why};
  }
  return std::unique_ptr<ProjectionEngine>(new ProjEngine(proj_string));
}

}  // namespace csgtile::geo::detail
