// LAZ decode throughput. For each LAZ file given (default: the AHN3 Delft tile and the
// point-format-8 file of ../shared/data/laz) and its LAS reference beside it, measures in this
// one process, each the best of `--passes` passes over the warm page cache:
//   las        — LasReader::read_raw over the uncompressed LAS (the baseline),
//   laz_1      — the same over the LAZ on one TBB thread,
//   laz_all    — the same on all cores (chunks decoded in parallel),
//   laz_fit    — all cores, decoding only what fitting needs (layered files skip layers),
//   points     — LasReader::read (decoded into points) on all cores,
// and prints one JSON object: points/s per case, the ratios to the LAS baseline and the
// parallel speed-up, and peak RSS. For the COPC file of ../shared/data/laz it also reports
// the bytes a region query reads (a quarter of the extent in x and y, and the root level
// alone) over the bytes of a whole read, counted at the byte source.
//
// Usage: laz_decode_bench [FILE.laz ...] [--passes K]

#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "csgtile/geo/las.h"

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double peak_rss_mib() {
  std::ifstream status("/proc/self/status");
  std::string key;
  while (status >> key) {
    if (key == "VmHWM:") {
      double kib = 0;
      status >> kib;
      return kib / 1024.0;
    }
  }
  return 0.0;
}

// Seconds for one whole read of `path` (raw records or points); -1 on error.
double read_once(const fs::path& path, bool points, bool fit_only, std::uint64_t& count) {
  csgtile::geo::PointReadOptions options;
  options.all_attributes = !fit_only;
  const auto start = Clock::now();
  auto opened = csgtile::geo::LasReader::open(path, options);
  if (!opened.ok()) {
    std::fprintf(stderr, "%s\n", opened.error().message.c_str());
    return -1;
  }
  count = 0;
  std::vector<std::uint8_t> raw;
  csgtile::geo::PointBatch batch;
  for (;;) {
    auto n = points ? opened.value()->read(batch, 1 << 16) : opened.value()->read_raw(raw, 1 << 16);
    if (!n.ok()) {
      std::fprintf(stderr, "%s\n", n.error().message.c_str());
      return -1;
    }
    if (n.value() == 0) break;
    count += n.value();
  }
  return std::chrono::duration<double>(Clock::now() - start).count();
}

double best(const fs::path& path, bool points, bool fit_only, int passes, std::uint64_t& count) {
  double b = 1e300;
  for (int i = 0; i < passes; ++i) {
    const double t = read_once(path, points, fit_only, count);
    if (t < 0) std::exit(1);
    b = std::min(b, t);
  }
  return b;
}

// Bytes in memory, counting what is read of them.
class CountingSource final : public csgtile::geo::ByteSource {
 public:
  CountingSource(const std::vector<std::uint8_t>& bytes, std::uint64_t* read)
      : ByteSource("copc"), bytes_(bytes), read_(read) {}
  std::uint64_t size() const override { return bytes_.size(); }
  csgtile::kernel::Status read_at(std::uint64_t offset, std::span<std::uint8_t> out) override {
    if (offset > bytes_.size() || out.size() > bytes_.size() - offset) {
      return csgtile::kernel::Status(csgtile::kernel::ErrorCode::CorruptData, "past the end");
    }
    std::copy_n(bytes_.data() + offset, out.size(), out.data());
    *read_ += out.size();
    return csgtile::kernel::Status();
  }

 private:
  const std::vector<std::uint8_t>& bytes_;
  std::uint64_t* read_;
};

// Points and bytes read for one COPC query (no region: the whole file).
std::pair<std::uint64_t, std::uint64_t> copc_read(const std::vector<std::uint8_t>& bytes,
                                                  const csgtile::geo::PointReadOptions& options) {
  std::uint64_t read = 0, points = 0;
  auto reader =
      csgtile::geo::LasReader::open_source(std::make_unique<CountingSource>(bytes, &read), options);
  if (!reader.ok()) {
    std::fprintf(stderr, "%s\n", reader.error().message.c_str());
    std::exit(1);
  }
  csgtile::geo::PointBatch batch;
  for (;;) {
    auto n = reader.value()->read(batch, 1 << 16);
    if (!n.ok() || n.value() == 0) break;
    points += n.value();
  }
  return {points, read};
}

void report_copc(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  const std::vector<std::uint8_t> bytes{std::istreambuf_iterator<char>(in),
                                        std::istreambuf_iterator<char>()};
  auto header = csgtile::geo::LasReader::open(path);
  if (!header.ok()) return;
  const auto& h = header.value()->header();
  const auto [all_points, all_bytes] = copc_read(bytes, {});
  csgtile::geo::PointReadOptions quarter;
  csgtile::geo::Bounds3 box;
  box.min = {h.min[0], h.min[1], -1e300};
  box.max = {0.5 * (h.min[0] + h.max[0]), 0.5 * (h.min[1] + h.max[1]), 1e300};
  quarter.region = box;
  const auto [q_points, q_bytes] = copc_read(bytes, quarter);
  csgtile::geo::PointReadOptions root;
  root.copc_max_depth = 0;
  const auto [r_points, r_bytes] = copc_read(bytes, root);
  std::printf(
      ", \"copc\": {\"file\": \"%s\", \"file_bytes\": %zu, \"whole\": {\"points\": %llu, "
      "\"bytes_read\": %llu}, \"quarter_region\": {\"points\": %llu, \"bytes_read\": %llu, "
      "\"bytes_over_whole\": %.3f}, \"root_level\": {\"points\": %llu, \"bytes_read\": %llu, "
      "\"bytes_over_whole\": %.3f}}",
      path.filename().c_str(), bytes.size(), static_cast<unsigned long long>(all_points),
      static_cast<unsigned long long>(all_bytes), static_cast<unsigned long long>(q_points),
      static_cast<unsigned long long>(q_bytes),
      static_cast<double>(q_bytes) / static_cast<double>(all_bytes),
      static_cast<unsigned long long>(r_points), static_cast<unsigned long long>(r_bytes),
      static_cast<double>(r_bytes) / static_cast<double>(all_bytes));
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<fs::path> files;
  int passes = 5;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--passes" && i + 1 < argc) {
      passes = std::max(1, std::atoi(argv[++i]));
    } else {
      files.emplace_back(a);
    }
  }
  if (files.empty()) {
    const fs::path dir = fs::path(CSGTILE_SHARED_DIR) / "data" / "laz";
    files = {dir / "ahn3_cropped_2.laz", dir / "las_with_several_extra_byte_bloc-chunk0.laz"};
  }
  const int cores = tbb::this_task_arena::max_concurrency();
  std::printf("{\"cores\": %d, \"passes\": %d, \"files\": [", cores, passes);
  for (std::size_t f = 0; f < files.size(); ++f) {
    fs::path las = files[f];
    las.replace_extension(".las");
    if (!fs::exists(files[f]) || !fs::exists(las)) {
      std::fprintf(stderr, "skipped: %s or its LAS reference is absent\n", files[f].c_str());
      continue;
    }
    std::uint64_t n = 0;
    const double t_las = best(las, false, false, passes, n);
    double t_one = 0;
    {
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
      t_one = best(files[f], false, false, passes, n);
    }
    const double t_all = best(files[f], false, false, passes, n);
    const double t_fit = best(files[f], false, true, passes, n);
    const double t_points = best(files[f], true, false, passes, n);
    const double pts = static_cast<double>(n);
    std::printf(
        "%s{\"file\": \"%s\", \"points\": %llu, \"las_points_per_s\": %.0f, "
        "\"laz_1_thread_points_per_s\": %.0f, \"laz_all_cores_points_per_s\": %.0f, "
        "\"laz_fit_fields_points_per_s\": %.0f, \"laz_to_points_points_per_s\": %.0f, "
        "\"laz_1_thread_over_las\": %.3f, \"laz_all_over_las\": %.3f, \"parallel_speedup\": %.2f}",
        f == 0 ? "" : ", ", files[f].filename().c_str(), static_cast<unsigned long long>(n),
        pts / t_las, pts / t_one, pts / t_all, pts / t_fit, pts / t_points, t_las / t_one,
        t_las / t_all, t_one / t_all);
  }
  std::printf("]");
  const fs::path copc = fs::path(CSGTILE_SHARED_DIR) / "data" / "laz" / "1.2-with-color.copc.laz";
  if (fs::exists(copc)) report_copc(copc);
  std::printf(", \"peak_rss_mib\": %.1f}\n", peak_rss_mib());
  return 0;
}
