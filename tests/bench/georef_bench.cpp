// Georeferencing throughput. Run: build/tests/bench/georef_bench --benchmark_format=json
//
// 5 M points of a 1 km tile go through Georeferencer::to_local (the exact per-point path:
// inverse projection → geodetic → [Helmert] → ENU) for three CRS families:
//   BM_ProjectedToLocal/utm   — EPSG:32631 (PROJ's tmerc in batches + LocalCartesian)
//   BM_ProjectedToLocal/rd    — EPSG:28992 (PROJ's sterea in batches + Helmert in ECEF)
//   BM_ProjectedToLocal/lccft — EPSG:2263  (PROJ's lcc, US survey feet)
//   BM_ProjectedToLocal/krovak — EPSG:5514 (PROJ's krovak) + Helmert
//   BM_ProjectedToLocal/dhdn   — EPSG:31467 with PROJ's BETA2007 grid shift per point
// Every projection is PROJ's since issue #19; the GeographicLib engines it replaced measured
// 1.79 M (utm), 1.44 M (rd, with our own oblique stereographic) and 1.71 M points/s (lccft)
// here (commit cda5f37's build).
// against BM_AffineBaseline, the same points through a plain 3×4 affine transform in the same
// process. Each georeferencing record carries `affine_points_per_second` (the baseline, timed
// in the same process just before) and `ratio_to_affine` (georef rate / affine rate): the
// figure to report. BM_TileMappingToLocal/<family> takes the same points through a
// TileMapping fitted over the tile (verified within 1e-7 m of the exact path) and reports its
// ratio to the exact path and to the affine baseline. Single thread; to_local is const and
// thread-safe, so it scales per core.

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <random>
#include <vector>

#include "csgtile/geo/crs.h"
#include "csgtile/geo/georeference.h"
#include "csgtile/geo/tile_mapping.h"

namespace {

using csgtile::geo::Crs;
using csgtile::geo::Georeferencer;
using csgtile::kernel::Vec3;

constexpr std::size_t kPoints = 5'000'000;

struct Family {
  int epsg;
  Vec3 origin;  // tile centre in CRS units
};

Family family(int index) {
  switch (index) {
    case 0:
      return {32631, Vec3(640000, 5700000, 20)};
    case 1:
      return {28992, Vec3(85000, 446000, 0)};
    case 2:
      return {2263, Vec3(988000, 210000, 30)};
    case 3:
      return {5514, Vec3(-743000, -1043000, 250)};
    default:
      return {31467, Vec3(3500000, 5400000, 300)};
  }
}

std::vector<Vec3> tile_points(const Family& f, double unit) {
  std::mt19937_64 rng(20240601);
  std::uniform_real_distribution<double> d(-500 / unit, 500 / unit), h(-10 / unit, 60 / unit);
  std::vector<Vec3> points(kPoints);
  for (Vec3& p : points) p = f.origin + Vec3(d(rng), d(rng), h(rng));
  return points;
}

// The baseline: the same points through a fixed affine map (what an approximate
// "projected → local" similarity would cost). Returns points per second, best of three.
double affine_rate(const std::vector<Vec3>& in, std::vector<Vec3>& out) {
  Eigen::Matrix<double, 3, 4> m;
  m << 0.9996, -0.0012, 0.0, -640000.0,  //
      0.0012, 0.9996, 0.0, -5700000.0,   //
      0.0, 0.0, 1.0, -20.0;
  double best = 0;
  for (int round = 0; round < 3; ++round) {
    const auto start = std::chrono::steady_clock::now();
    for (std::size_t i = 0; i < in.size(); ++i) out[i] = m.leftCols<3>() * in[i] + m.col(3);
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    best = std::max(best, static_cast<double>(in.size()) / seconds);
  }
  return best;
}

// Times `mapper.to_local(points, out)` over the benchmark's iterations; records the items
// processed and returns points per second (0 after reporting an error).
template <class Mapper>
double time_bulk(benchmark::State& state, const Mapper& mapper, const std::vector<Vec3>& points,
                 std::vector<Vec3>& out) {
  double seconds = 0;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    auto status = mapper.to_local(points, out);
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (!status.ok()) {
      state.SkipWithError(status.error().message.c_str());
      return 0;
    }
    benchmark::DoNotOptimize(out.data());
  }
  const double processed =
      static_cast<double>(state.iterations()) * static_cast<double>(points.size());
  state.SetItemsProcessed(static_cast<std::int64_t>(processed));
  return processed / seconds;
}

const char* family_label(std::int64_t index) {
  static const char* labels[] = {"utm EPSG:32631", "rd EPSG:28992", "lccft EPSG:2263",
                                 "krovak EPSG:5514", "dhdn EPSG:31467 (BETA2007 grid)"};
  return labels[std::clamp<std::int64_t>(index, 0, 4)];
}

Crs family_crs(int index) { return csgtile::geo::crs_from_epsg(family(index).epsg).value(); }

void BM_AffineBaseline(benchmark::State& state) {
  const Family f = family(0);
  const auto points = tile_points(f, 1.0);
  std::vector<Vec3> out(points.size());
  Eigen::Matrix<double, 3, 4> m;
  m << 0.9996, -0.0012, 0.0, -640000.0, 0.0012, 0.9996, 0.0, -5700000.0, 0.0, 0.0, 1.0, -20.0;
  for (auto _ : state) {
    for (std::size_t i = 0; i < points.size(); ++i) out[i] = m.leftCols<3>() * points[i] + m.col(3);
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * points.size()));
}
BENCHMARK(BM_AffineBaseline)->Unit(benchmark::kMillisecond)->Iterations(3);

void BM_ProjectedToLocal(benchmark::State& state) {
  const Family f = family(static_cast<int>(state.range(0)));
  const Crs crs = family_crs(static_cast<int>(state.range(0)));
  auto georef = Georeferencer::create_at(crs, f.origin);
  if (!georef.ok()) {
    state.SkipWithError(georef.error().message.c_str());
    return;
  }
  const auto points = tile_points(f, crs.linear_unit.metres);
  std::vector<Vec3> out(points.size());
  const double baseline = affine_rate(points, out);
  const double rate = time_bulk(state, georef.value(), points, out);
  if (rate <= 0) return;
  state.counters["affine_points_per_second"] = baseline;
  state.counters["ratio_to_affine"] = rate / baseline;
  state.SetLabel(family_label(state.range(0)));
}
BENCHMARK(BM_ProjectedToLocal)
    ->Arg(0)
    ->Arg(1)
    ->Arg(2)
    ->Arg(3)
    ->Arg(4)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(2);

// The same points through TileMapping fitted over the tile (1e-7 m bound): the bulk path a
// point cloud takes. `ratio_to_exact` is measured against the exact path in this benchmark.
void BM_TileMappingToLocal(benchmark::State& state) {
  const Family f = family(static_cast<int>(state.range(0)));
  const Crs crs = csgtile::geo::crs_from_epsg(f.epsg).value();
  auto georef = Georeferencer::create_at(crs, f.origin);
  if (!georef.ok()) {
    state.SkipWithError(georef.error().message.c_str());
    return;
  }
  const auto points = tile_points(f, crs.linear_unit.metres);
  csgtile::kernel::BoundingBox box;
  for (const Vec3& p : points) box.add(p);
  const auto fit_start = std::chrono::steady_clock::now();
  auto mapping = csgtile::geo::TileMapping::fit(georef.value(), box);
  const double fit_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - fit_start).count();
  if (!mapping.ok()) {
    state.SkipWithError(mapping.error().message.c_str());
    return;
  }
  std::vector<Vec3> out(points.size());
  const double baseline = affine_rate(points, out);
  const std::size_t sample = points.size() / 10;  // exact path on a tenth, for the ratio
  const auto exact_start = std::chrono::steady_clock::now();
  (void)georef.value().to_local(std::span(points).first(sample), std::span(out).first(sample));
  const double exact_rate =
      static_cast<double>(sample) /
      std::chrono::duration<double>(std::chrono::steady_clock::now() - exact_start).count();
  const double rate = time_bulk(state, mapping.value(), points, out);
  if (rate <= 0) return;
  state.counters["affine_points_per_second"] = baseline;
  state.counters["ratio_to_affine"] = rate / baseline;
  state.counters["ratio_to_exact"] = rate / exact_rate;
  state.counters["degree"] = mapping.value().degree();
  state.counters["verified_error_nm"] = mapping.value().verified_error_m() * 1e9;
  state.counters["fit_ms"] = fit_seconds * 1e3;
  state.SetLabel(family_label(state.range(0)));
}
BENCHMARK(BM_TileMappingToLocal)
    ->Arg(0)
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(3);

}  // namespace

BENCHMARK_MAIN();
