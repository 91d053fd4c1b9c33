// Assembly benchmark: synthetic cities (tests/support/random_city.h: blocks of box and
// L-extrusion buildings with wings, roofs and columns, about a third of the primitives in
// contact) of 1k, 10k and 100k primitives, assembled (a) in full, (b) without the OpenVDB
// culling and (c) without any broad phase (every pair a candidate; up to --all-pairs-max).
// Each run is a forked child, so its peak memory is its own. Prints one JSON object: per
// run the statistics of csgtile::assembly (pairs per stage, objects, seconds per phase),
// peak RSS, and the time scaling exponent of the full runs.
// Run: build/tests/bench/assemble_bench [--max N] [--all-pairs-max N] [--threads T]
//      [--sizes N,N,...] (instead of 1k, 10k, 100k; tests/bench/memory_bench.py takes 5k)

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "child_run.h"
#include "csgtile/assembly/assembly.h"
#include "random_city.h"

using namespace csgtile;

namespace {

struct Run {
  int n = 0;
  std::string mode;
  assembly::AssemblyStats stats;
  double volume = 0;
  long peak_kb = 0;
  bool ok = false;
};

struct Payload {
  assembly::AssemblyStats stats;
  double volume;
  int ok;
};

// Runs one configuration in a forked child (tests/support/child_run.h): its peak memory is
// its own.
Run run_child(int n, const std::string& mode, int threads) {
  Run r;
  r.n = n;
  r.mode = mode;
  const auto run = test::run_in_child<Payload>([&] {
    std::vector<assembly::AssemblyPrimitive> prims;
    const auto specs = test::random_city(n, 42);
    for (std::size_t i = 0; i < specs.size(); ++i)
      prims.push_back({specs[i], "p" + std::to_string(i)});
    assembly::AssemblyOptions o;
    o.threads = threads;
    o.voxel_culling = mode != "no_culling";
    o.broad_phase = mode != "no_broad_phase";
    auto a = assembly::assemble(prims, o);
    Payload p{};
    p.ok = a.ok() ? 1 : 0;
    if (a.ok()) {
      p.stats = a->stats;
      for (const auto& obj : a->objects) p.volume += obj.volume;
    }
    return p;
  });
  r.peak_kb = run.peak_kb;
  if (run.result) {
    r.stats = run.result->stats;
    r.volume = run.result->volume;
    r.ok = run.result->ok == 1;
  }
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  int max_n = 100000, all_pairs_max = 2000, threads = 0;
  std::vector<int> sizes = {1000, 10000, 100000};
  for (int i = 1; i + 1 < argc; ++i) {
    if (!std::strcmp(argv[i], "--max"))
      max_n = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--all-pairs-max"))
      all_pairs_max = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--threads"))
      threads = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--sizes")) {
      sizes.clear();
      for (const char* p = argv[++i]; *p != '\0';) {
        char* end = nullptr;
        const long n = std::strtol(p, &end, 10);
        if (end == p || n <= 0) {
          std::fprintf(stderr, "--sizes: a comma-separated list of positive counts\n");
          return 2;
        }
        sizes.push_back(static_cast<int>(n));
        p = *end == ',' ? end + 1 : end;
      }
    }
  }
  std::vector<Run> runs;
  for (int n : sizes) {
    if (n > max_n) break;
    runs.push_back(run_child(n, "full", threads));
    runs.push_back(run_child(n, "no_culling", threads));
    if (n <= all_pairs_max) runs.push_back(run_child(n, "no_broad_phase", threads));
    std::fprintf(stderr, "n=%d done\n", n);
  }
  std::printf("{\"benchmark\": \"assemble_city\", \"runs\": [\n");
  for (std::size_t k = 0; k < runs.size(); ++k) {
    const Run& r = runs[k];
    const auto& s = r.stats;
    std::printf(
        "  {\"n\": %d, \"mode\": \"%s\", \"ok\": %s, \"seconds\": %.3f, \"peak_rss_mb\": %.1f, "
        "\"candidate_pairs\": %lld, \"culled_pairs\": %lld, \"exact_tests\": %lld, "
        "\"interacting_pairs\": %lld, \"exact_per_interacting\": %.3f, \"objects\": %lld, "
        "\"objects_failed\": %lld, \"volume\": %.6f, \"phase_seconds\": {\"build\": %.3f, "
        "\"broad\": %.3f, \"voxel\": %.3f, \"exact\": %.3f, \"fuse\": %.3f}}%s\n",
        r.n, r.mode.c_str(), r.ok ? "true" : "false", s.seconds_total, r.peak_kb / 1024.0,
        s.candidate_pairs, s.culled_pairs, s.exact_tests, s.interacting_pairs,
        s.interacting_pairs > 0
            ? static_cast<double>(s.exact_tests) / static_cast<double>(s.interacting_pairs)
            : 0.0,
        s.objects, s.objects_failed, r.volume, s.seconds_build, s.seconds_broad, s.seconds_voxel,
        s.seconds_exact, s.seconds_fuse, k + 1 < runs.size() ? "," : "");
  }
  // Scaling exponent of the full runs: t ∝ n^k between the smallest and largest n.
  double k = 0;
  const Run* first = nullptr;
  const Run* last = nullptr;
  for (const Run& r : runs) {
    if (r.mode != "full") continue;
    if (!first) first = &r;
    last = &r;
  }
  if (first && last && last->n > first->n) {
    k = std::log(last->stats.seconds_total / first->stats.seconds_total) /
        std::log(static_cast<double>(last->n) / first->n);
  }
  std::printf("], \"scaling_exponent_full\": %.3f}\n", k);
  return 0;
}
