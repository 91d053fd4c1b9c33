// Kernel benchmarks. Run: build/tests/bench/kernel_bench --benchmark_format=json
//   BM_BuildPrimitives     — building primitives (items/s), all seven types in turn;
//   BM_AncestorIndex       — edge→faces index of a compound of boxes; the argument is the
//                            number of sub-shapes, so items/s at 1e5 and 1e6 shows the scaling;
//   BM_ChildMap            — the same model's edge child map, for comparison;
//   BM_NativeWrite/Read    — native format throughput (bytes/s), against BM_CopyBaseline,
//                            a memcpy of the same bytes (the ratio is what we report).

#include <benchmark/benchmark.h>

#include <cstring>
#include <numbers>

#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/native_format.h"
#include "csgtile/kernel/primitives.h"

namespace {

using namespace csgtile::kernel;

PrimitiveSpec spec_of(int i) {
  PrimitiveSpec s;
  s.type = static_cast<PrimitiveType>(i % kPrimitiveTypeCount);
  s.size = Vec3(1 + i % 3, 2, 3);
  s.radius = 2;
  s.radius2 = 1;
  s.height = 3;
  s.profile = {{1, 0}, {3, 0}, {2, 2}, {1, 2}};
  if (s.type == PrimitiveType::Extrusion)
    s.profile = {{0, 0}, {4, 0}, {4, 1}, {1, 1}, {1, 4}, {0, 4}};
  s.placement = Location::translation(Vec3(i % 100, (i / 100) % 100, i / 10000));
  return s;
}

void BM_BuildPrimitives(benchmark::State& state) {
  int i = 0;
  for (auto _ : state) {
    auto s = build_primitive(spec_of(i++));
    benchmark::DoNotOptimize(s);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_BuildPrimitives);

// A compound of distinct boxes with about `subshapes` distinct sub-shapes (a box has 34:
// 1 solid, 1 shell, 6 faces, 6 wires, 12 edges, 8 vertices).
Shape boxes_model(std::int64_t subshapes) {
  std::vector<Shape> boxes;
  for (std::int64_t i = 0; i < subshapes / 34; ++i) boxes.push_back(make_box(1, 1, 1).value());
  return ShapeFactory::compound(std::move(boxes)).value();
}

void BM_AncestorIndex(benchmark::State& state) {
  const Shape model = boxes_model(state.range(0));
  for (auto _ : state) {
    AncestorIndex index(model, ShapeKind::Edge, ShapeKind::Face);
    benchmark::DoNotOptimize(index.size());
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_AncestorIndex)->Arg(100'000)->Arg(1'000'000)->Unit(benchmark::kMillisecond);

void BM_ChildMap(benchmark::State& state) {
  const Shape model = boxes_model(state.range(0));
  for (auto _ : state) {
    ShapeIndex map = map_child_shapes(model, ShapeKind::Edge);
    benchmark::DoNotOptimize(map.size());
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_ChildMap)->Arg(100'000)->Arg(1'000'000)->Unit(benchmark::kMillisecond);

Shape mixed_model() {
  std::vector<Shape> solids;
  for (int i = 0; i < 2000; ++i) solids.push_back(build_primitive(spec_of(i)).value());
  return ShapeFactory::compound(std::move(solids)).value();
}

void BM_NativeWrite(benchmark::State& state) {
  const Shape model = mixed_model();
  std::size_t bytes = 0;
  for (auto _ : state) {
    std::string out = write_native(model);
    bytes = out.size();
    benchmark::DoNotOptimize(out);
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * bytes));
}
BENCHMARK(BM_NativeWrite)->Unit(benchmark::kMillisecond);

void BM_NativeRead(benchmark::State& state) {
  const std::string data = write_native(mixed_model());
  for (auto _ : state) {
    auto shape = read_native(data);
    benchmark::DoNotOptimize(shape);
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * data.size()));
}
BENCHMARK(BM_NativeRead)->Unit(benchmark::kMillisecond);

void BM_CopyBaseline(benchmark::State& state) {
  const std::string data = write_native(mixed_model());
  std::string copy(data.size(), '\0');
  for (auto _ : state) {
    std::memcpy(copy.data(), data.data(), data.size());
    benchmark::DoNotOptimize(copy.data());
    benchmark::ClobberMemory();
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * data.size()));
}
BENCHMARK(BM_CopyBaseline)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
