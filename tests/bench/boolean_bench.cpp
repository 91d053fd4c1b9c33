// Boolean benchmark: n-ary fuse of a synthetic city block (tests/support/random_city.h's
// city_block: boxes and columns on a grid, about 30% overlapping a neighbour) for n = 10,
// 100, 1000 (and 5000 with --big), and of the timber gate of `csgtile synth` (81 columns,
// 148 beams), against the pairwise fold of the
// same primitives in the same process (up to --fold-max), plus the volumes (equal for both
// methods). Prints one JSON object; "native_fnv1a" is a 64-bit FNV-1a hash of the n-ary
// result's native bytes (write_native), so that two builds can be shown to give the same
// results (not CRC-32C: the bytes end with their own CRC, whose residue is a constant).
// Run: build/tests/bench/boolean_bench [--big] [--fold-max N] [--only gate|N]
//
// Before/after a change (one script, one machine state; the figures are noisy, compare
// ratios): keep the old binary (cp build/tests/bench/boolean_bench /tmp/boolean_bench.before),
// rebuild, then run both in turn, e.g.
//   for b in /tmp/boolean_bench.before build/tests/bench/boolean_bench; do $b --fold-max 0; done
// Equal volumes, face counts and native_fnv1a: the change did not alter any result.

#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>

#include "csgtile/geo/synth.h"
#include "csgtile/kernel/boolean.h"
#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/mass_properties.h"
#include "csgtile/kernel/native_format.h"
#include "csgtile/kernel/primitives.h"
#include "random_city.h"

using namespace csgtile::kernel;

namespace {

unsigned long long fnv1a(const std::string& bytes) {
  unsigned long long h = 14695981039346656037ull;
  for (const unsigned char c : bytes) h = (h ^ c) * 1099511628211ull;
  return h;
}

long peak_rss_kb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss;
}

}  // namespace

int main(int argc, char** argv) {
  bool big = false;
  int fold_max = 1000;
  int only = -1;  // one scene: 0 the gate, else a city-block size
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--big")) big = true;
    if (!std::strcmp(argv[i], "--fold-max") && i + 1 < argc) fold_max = std::atoi(argv[++i]);
    if (!std::strcmp(argv[i], "--only") && i + 1 < argc) {
      ++i;
      only = !std::strcmp(argv[i], "gate") ? 0 : std::atoi(argv[i]);
    }
  }
  std::vector<int> sizes{10, 100, 1000};
  if (big) sizes.push_back(5000);
  sizes.push_back(0);  // 0: the gate
  if (only >= 0) sizes = {only};
  std::printf("{\"benchmark\": \"city_block_fuse\", \"runs\": [\n");
  bool first = true;
  for (const int size : sizes) {
    int n = size;
    const bool is_gate = size == 0;
    std::vector<Shape> prims;
    if (!is_gate) {
      for (const auto& spec : csgtile::test::city_block(n, 42))
        prims.push_back(build_primitive(spec).value());
    } else {
      auto gate = csgtile::geo::make_synth_scene("gate", 1);
      if (!gate.ok()) {
        std::fprintf(stderr, "gate: %s\n", gate.error().message.c_str());
        return 1;
      }
      for (const auto& p : gate.value().scene.primitives)
        prims.push_back(build_primitive(p.spec).value());
      n = static_cast<int>(prims.size());
    }
    auto t0 = std::chrono::steady_clock::now();
    auto nary = boolean_fuse_all(prims);
    const double nary_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (!nary.ok()) {
      std::fprintf(stderr, "n=%d: %s\n", n, nary.error().message.c_str());
      return 1;
    }
    const auto counts = count_shapes(nary.value());
    double fold_s = -1, fold_volume = -1;
    if (n <= fold_max) {
      t0 = std::chrono::steady_clock::now();
      auto fold = boolean_fold(prims, BooleanOp::Fuse);
      fold_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      if (fold.ok()) fold_volume = mass_properties(fold.value()).volume;
    }
    const double peak_mb = peak_rss_kb() / 1024.0;  // before the checksum's own allocations
    const unsigned long long hash = fnv1a(write_native(nary.value()));
    std::printf(
        "%s  {\"scene\": \"%s\", \"n\": %d, \"nary_seconds\": %.4f, \"fold_seconds\": %.4f, "
        "\"fold_over_nary\": %.2f, "
        "\"solids\": %zu, \"faces\": %zu, \"volume\": %.17g, \"fold_volume\": %.6f, "
        "\"peak_rss_mb\": %.1f, "
        "\"native_fnv1a\": \"%016llx\"}",
        first ? "" : ",\n", is_gate ? "gate" : "city_block", n, nary_s, fold_s,
        fold_s > 0 ? fold_s / nary_s : -1.0, counts[static_cast<int>(ShapeKind::Solid)],
        counts[static_cast<int>(ShapeKind::Face)], mass_properties(nary.value()).volume,
        fold_volume, peak_mb, hash);
    std::fflush(stdout);
    first = false;
  }
  std::printf("\n]}\n");
  return 0;
}
