// LAS read (+ georeference) throughput. Synthesises a LAS 1.4 point-format-7 file of N points
// (default 5 M, 36 bytes each, UTM 31N with its WKT), then measures in this one process:
//   baseline — a plain sequential read() loop over the same file (1 MiB chunks),
//   reader   — LasReader decoding every point in batches of 65536, and
//   georef   — the same, plus the file's CRS resolved from its WKT and every point taken into
//              the tile's east-north-up frame (Georeferencer::to_local, exact per point),
//   mapped   — as georef through a TileMapping fitted over the header bounds (within 1e-7 m
//              of the exact path: the bulk path point clouds take),
// each the best of three passes (`--passes`) over the warm page cache, and prints one JSON
// object: points/s, MB/s, the ratios to the baseline, the resident-memory growth while reading,
// and peak RSS (compare the peak for 5 M and 50 M points: it must not grow with the file).
//
// Usage: las_read_bench [POINTS] [FILE] [--passes K]
//        (FILE defaults to a temporary file, removed after; an existing FILE is read as is)

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include "csgtile/geo/georeference.h"
#include "csgtile/geo/las.h"
#include "csgtile/geo/tile_mapping.h"

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// A field of /proc/self/status in MiB ("VmRSS", "VmHWM").
double status_mib(const char* field) {
  std::ifstream status("/proc/self/status");
  std::string key;
  while (status >> key) {
    if (key == std::string(field) + ":") {
      double kib = 0;
      status >> kib;
      return kib / 1024.0;
    }
    std::getline(status, key);
  }
  return 0;
}

bool synthesise(const fs::path& path, std::size_t count) {
  csgtile::geo::LasWriteOptions options;
  options.point_format = 7;
  options.scale = {0.001, 0.001, 0.001};
  options.offset = {650000.0, 5400000.0, 0.0};
  if (auto crs = csgtile::geo::crs_from_epsg(32631); crs.ok()) {
    options.wkt = csgtile::geo::crs_to_wkt1(crs.value());
  }
  auto writer = csgtile::geo::LasWriter::create(path, options);
  if (!writer.ok()) {
    std::fprintf(stderr, "%s\n", writer.error().message.c_str());
    return false;
  }
  csgtile::geo::PointBatch batch;
  std::uint64_t state = 88172645463325252ull;  // xorshift: fixed, fast, no <random> needed
  auto next = [&] {
    state ^= state << 13;
    state ^= state >> 7;
    state ^= state << 17;
    return state;
  };
  for (std::size_t done = 0; done < count;) {
    batch.clear();
    const std::size_t n = std::min<std::size_t>(100000, count - done);
    for (std::size_t i = 0; i < n; ++i) {
      csgtile::geo::Point p;
      p.x = 650000.0 + static_cast<double>(next() % 1000000) * 0.001;
      p.y = 5400000.0 + static_cast<double>(next() % 1000000) * 0.001;
      p.z = static_cast<double>(next() % 50000) * 0.001;
      p.intensity = static_cast<std::uint16_t>(next());
      p.return_number = 1;
      p.number_of_returns = 1;
      p.classification = static_cast<std::uint8_t>(next() % 7);
      p.gps_time = static_cast<double>(done + i) * 1e-5;
      p.red = p.green = p.blue = static_cast<std::uint16_t>(next());
      batch.append(p);
    }
    if (auto st = writer.value()->write(batch); !st.ok()) {
      std::fprintf(stderr, "%s\n", st.error().message.c_str());
      return false;
    }
    done += n;
  }
  return writer.value()->close().ok();
}

double baseline_pass(const fs::path& path, std::uint64_t& checksum) {
  const auto start = Clock::now();
  const int fd = ::open(path.c_str(), O_RDONLY);
  if (fd < 0) return -1;
  std::vector<unsigned char> buffer(1 << 20);
  for (;;) {
    const ssize_t n = ::read(fd, buffer.data(), buffer.size());
    if (n <= 0) break;
    for (ssize_t i = 0; i < n; i += 4096) checksum += buffer[static_cast<std::size_t>(i)];
  }
  ::close(fd);
  return seconds_since(start);
}

double reader_pass(const fs::path& path, double& sum, std::uint64_t& points, double& growth) {
  const auto start = Clock::now();
  auto reader = csgtile::geo::LasReader::open(path);
  if (!reader.ok()) {
    std::fprintf(stderr, "%s\n", reader.error().message.c_str());
    return -1;
  }
  csgtile::geo::PointBatch batch;
  const double before = status_mib("VmRSS");
  double peak = before;
  points = 0;
  for (;;) {
    auto n = reader.value()->read(batch, 65536);
    if (!n.ok() || n.value() == 0) break;
    for (const auto& p : batch.points) sum += p.x + p.gps_time;
    points += n.value();
    if ((points >> 16) % 16 == 0) peak = std::max(peak, status_mib("VmRSS"));
  }
  growth = std::max(growth, peak - before);
  return seconds_since(start);
}

// As reader_pass, and every batch taken into the tile frame centred on the header bounds:
// through the exact path, or (`mapped`) through a TileMapping fitted over the header bounds.
double georef_pass(const fs::path& path, double& sum, double& growth, bool mapped) {
  const auto start = Clock::now();
  auto reader = csgtile::geo::LasReader::open(path);
  if (!reader.ok()) {
    std::fprintf(stderr, "%s\n", reader.error().message.c_str());
    return -1;
  }
  auto crs = csgtile::geo::las_file_crs(reader.value()->crs());
  if (!crs.ok()) {
    std::fprintf(stderr, "%s\n", crs.error().message.c_str());
    return -1;
  }
  const auto& h = reader.value()->header();
  const csgtile::kernel::Vec3 centre(0.5 * (h.min[0] + h.max[0]), 0.5 * (h.min[1] + h.max[1]),
                                     h.min[2]);
  auto geo = csgtile::geo::Georeferencer::create_at(crs.value(), centre);
  if (!geo.ok()) {
    std::fprintf(stderr, "%s\n", geo.error().message.c_str());
    return -1;
  }
  csgtile::kernel::BoundingBox box;
  box.add(csgtile::kernel::Vec3(h.min[0], h.min[1], h.min[2]));
  box.add(csgtile::kernel::Vec3(h.max[0], h.max[1], h.max[2]));
  std::optional<csgtile::geo::TileMapping> mapping;
  if (mapped) {
    auto fitted = csgtile::geo::TileMapping::fit(geo.value(), box);
    if (!fitted.ok()) {
      std::fprintf(stderr, "%s\n", fitted.error().message.c_str());
      return -1;
    }
    mapping = std::move(fitted).value();
  }
  csgtile::geo::PointBatch batch;
  std::vector<csgtile::kernel::Vec3> in, out;
  const double before = status_mib("VmRSS");
  double peak = before;
  std::uint64_t points = 0;
  for (;;) {
    auto n = reader.value()->read(batch, 65536);
    if (!n.ok() || n.value() == 0) break;
    in.resize(batch.points.size());
    out.resize(batch.points.size());
    for (std::size_t i = 0; i < batch.points.size(); ++i) {
      in[i] = csgtile::kernel::Vec3(batch.points[i].x, batch.points[i].y, batch.points[i].z);
    }
    if (!(mapping ? mapping->to_local(in, out) : geo.value().to_local(in, out)).ok()) return -1;
    for (const auto& p : out) sum += p.x();
    points += n.value();
    if ((points >> 16) % 16 == 0) peak = std::max(peak, status_mib("VmRSS"));
  }
  growth = std::max(growth, peak - before);
  return seconds_since(start);
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args;
  int passes = 3;
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]) == "--passes" && i + 1 < argc) {
      passes = std::max(1, std::atoi(argv[++i]));
    } else {
      args.emplace_back(argv[i]);
    }
  }
  const std::size_t count = !args.empty() ? std::strtoull(args[0].c_str(), nullptr, 10) : 5'000'000;
  const bool temporary = args.size() < 2;
  const fs::path path = temporary ? fs::temp_directory_path() /
                                        ("csgtile_las_bench_" + std::to_string(::getpid()) + ".las")
                                  : fs::path(args[1]);
  if (!fs::exists(path) && !synthesise(path, count)) return 1;
  const double bytes = static_cast<double>(fs::file_size(path));

  double best_baseline = 1e300, best_reader = 1e300, best_georef = 1e300, best_mapped = 1e300;
  double sum = 0, growth = 0;
  std::uint64_t checksum = 0, points = 0;
  for (int pass = 0; pass < passes; ++pass) {
    best_baseline = std::min(best_baseline, baseline_pass(path, checksum));
    best_reader = std::min(best_reader, reader_pass(path, sum, points, growth));
    best_georef = std::min(best_georef, georef_pass(path, sum, growth, false));
    best_mapped = std::min(best_mapped, georef_pass(path, sum, growth, true));
  }
  if (temporary) fs::remove(path);
  const double mb = bytes / 1e6;
  std::printf(
      "{\"points\": %llu, \"file_bytes\": %.0f, \"record_length\": 36, \"cache\": \"warm\",\n"
      " \"baseline\": {\"seconds\": %.4f, \"mb_per_s\": %.1f},\n"
      " \"las_reader\": {\"seconds\": %.4f, \"points_per_s\": %.4g, \"mb_per_s\": %.1f},\n"
      " \"ratio_to_baseline\": %.3f,\n"
      " \"read_and_georef\": {\"seconds\": %.4f, \"points_per_s\": %.4g, \"mb_per_s\": %.1f},\n"
      " \"georef_ratio_to_baseline\": %.4f, \"georef_ratio_to_reader\": %.3f,\n"
      " \"read_and_tile_mapping\": {\"seconds\": %.4f, \"points_per_s\": %.4g, \"mb_per_s\": "
      "%.1f},\n"
      " \"mapped_ratio_to_baseline\": %.4f, \"mapped_ratio_to_reader\": %.3f,\n"
      " \"read_rss_growth_mib\": %.1f, \"peak_rss_mib\": %.1f,\n"
      " \"checksum\": %.6g}\n",
      static_cast<unsigned long long>(points), bytes, best_baseline, mb / best_baseline,
      best_reader, static_cast<double>(points) / best_reader, mb / best_reader,
      best_baseline / best_reader, best_georef, static_cast<double>(points) / best_georef,
      mb / best_georef, best_baseline / best_georef, best_reader / best_georef, best_mapped,
      static_cast<double>(points) / best_mapped, mb / best_mapped, best_baseline / best_mapped,
      best_reader / best_mapped, growth, status_mib("VmHWM"), sum + static_cast<double>(checksum));
  return 0;
}
