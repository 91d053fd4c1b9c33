// libFuzzer target for the point-cloud readers (CSGTILE_FUZZ=ON, clang): the LAS header, VLR,
// EVLR, extra-bytes, GeoTIFF-key and point parsers, and — for inputs that are not LAS — the
// PLY, PCD (with LZF) and XYZ readers picked by their magic bytes.
//
// Besides "no crash, no sanitizer report", an accepted LAS input must keep the reader's
// promises: batches never exceed their bound, extra bytes match the layout, the number of
// points read equals readable_points(), and reading again after seek(0) in other batch sizes
// gives the same points.
//
// Built a second time with CSGTILE_LAS_SEED_GENERATOR defined, the same file is a program that
// writes a seed corpus (ctest runs it before the fuzzer): small files of ../shared/data when
// present, and synthesised LAS 1.0-1.4 files, a PLY and a PCD in any case.

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "csgtile/geo/las.h"
#include "csgtile/geo/point_reader.h"

using namespace csgtile::geo;

#ifndef CSGTILE_LAS_SEED_GENERATOR

namespace {

void check(bool condition, const char* what) {
  if (!condition) {
    std::fprintf(stderr, "broken reader promise: %s\n", what);
    __builtin_trap();
  }
}

// Reads everything in batches of `max`, checking the batch invariants; returns the x values
// (bit patterns) of up to the first 256 points, and the count.
std::uint64_t drain(PointReader& reader, std::size_t max, std::vector<double>* first) {
  PointBatch batch;
  std::uint64_t total = 0;
  for (int guard = 0; guard < 1000000; ++guard) {
    auto n = reader.read(batch, max);
    if (!n.ok()) return total;
    if (n.value() == 0) return total;
    check(n.value() <= max && n.value() == batch.size(), "batch larger than asked");
    check(batch.extra_bytes.size() == batch.size() * batch.extra_record_size(),
          "extra bytes do not match the layout");
    if (batch.layout) {
      for (const auto& d : batch.layout->dimensions) {
        for (int e = 0; e < d.elements && e < 3; ++e) {
          (void)batch.extra_value(0, d.name, e);
          (void)batch.extra_raw(batch.size() - 1, d.name, e);
        }
      }
    }
    for (const Point& p : batch.points) {
      if (first != nullptr && first->size() < 256) first->push_back(p.x);
    }
    total += n.value();
  }
  return total;
}

void fuzz_las(std::span<const std::uint8_t> bytes, bool accept_truncated) {
  PointReadOptions options;
  options.accept_truncated = accept_truncated;
  options.skip_non_finite = false;  // keep every record so that the counts must match
  auto reader = LasReader::open_memory("fuzz.las", bytes, options);
  if (!reader.ok()) return;
  LasReader& las = *reader.value();
  (void)las.crs().find(kGeoKeyProjectedCsType);
  std::vector<double> first, again;
  const std::uint64_t total = drain(las, 37, &first);
  if (!las.at_end()) return;  // a read error (e.g. I/O) ends the run; nothing to compare
  check(total == las.readable_points(), "points read differ from readable_points()");
  check(las.seek(0).ok(), "seek(0) refused");
  // A second pass in other batch sizes must give the same points.
  auto second = LasReader::open_memory("fuzz.las", bytes, options);
  check(second.ok(), "a file that opened once failed to open again");
  const std::uint64_t total_again = drain(*second.value(), 1000, &again);
  check(total_again == total, "point count depends on the batch size");
  check(std::equal(first.begin(), first.end(), again.begin(), again.end(),
                   [](double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }),
        "points depend on the batch size");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::uint8_t> bytes(data, size);
  fuzz_las(bytes, false);
  fuzz_las(bytes, true);
  // Not LAS: the name's extension makes text fall to the XYZ reader; PLY and PCD are
  // recognised by their first bytes.
  if (size < 4 || std::memcmp(data, "LASF", 4) != 0) {
    auto reader = open_point_memory("fuzz.xyz", bytes);
    if (reader.ok()) drain(*reader.value(), 64, nullptr);
  }
  return 0;
}

#else

namespace fs = std::filesystem;

// Synthesised seeds: LAS in each version with a format of that version, extra bytes, CRS
// records and (1.4) an EVLR; a PLY and a PCD.
void write_synthesised(const fs::path& dir) {
  const int formats[] = {1, 1, 3, 5, 10};
  for (int minor = 0; minor <= 4; ++minor) {
    LasWriteOptions options;
    options.version_minor = static_cast<std::uint8_t>(minor);
    options.point_format = static_cast<std::uint8_t>(formats[minor]);
    ExtraDimension height;
    height.name = "height";
    height.type = ExtraType::I16;
    height.scale = 0.01;
    ExtraDimension pair;
    pair.name = "pair";
    pair.type = ExtraType::F32;
    pair.elements = 2;
    pair.byte_offset = 2;
    options.extra.record_size = 11;
    options.extra.dimensions = {height, pair};
    GeoKey projected;
    projected.id = kGeoKeyProjectedCsType;
    projected.value_offset = 32632;
    GeoKey citation;
    citation.id = kGeoKeyCitation;
    citation.ascii = "WGS 84 / UTM 32N";
    GeoKey parallel;
    parallel.id = 3078;
    parallel.doubles = {45.0};
    options.geo_keys = {projected, citation, parallel};
    if (minor == 4) {
      options.wkt = "PROJCS[\"WGS 84 / UTM zone 32N\"]";
      LasRecord r;
      r.user_id = "seed";
      r.record_id = 1;
      r.data = std::vector<std::uint8_t>{1, 2, 3, 4};
      options.evlrs.push_back(r);
    }
    PointBatch batch;
    batch.layout = std::make_shared<ExtraLayout>(options.extra);
    for (int i = 0; i < 12; ++i) {
      Point p;
      p.x = i * 1.5;
      p.y = -i * 0.25;
      p.z = i;
      p.return_number = 1;
      p.number_of_returns = 2;
      p.classification = static_cast<std::uint8_t>(i % 8);
      p.gps_time = 1000.0 + i;
      std::uint8_t extra[11] = {static_cast<std::uint8_t>(i), 0, 0, 0, 0x80, 0x3F};
      batch.append(p, extra);
    }
    const auto status =
        write_las(dir / ("synth_v1" + std::to_string(minor) + ".las"), options, batch);
    if (!status.ok()) std::fprintf(stderr, "seed: %s\n", status.error().message.c_str());
  }
  std::ofstream(dir / "synth.ply", std::ios::binary)
      << "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
         "property float z\nproperty uchar red\nend_header\n1 2 3 4\n5 6 7 8\n";
  std::ofstream(dir / "synth.pcd", std::ios::binary)
      << "VERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\nWIDTH 2\n"
         "HEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n1 2 3 4.2108e+06\n4 5 6 0\n";
}

// Usage: las_reader_fuzz_seeds SEED_DIR [SHARED_DATA_DIR]
int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s SEED_DIR [SHARED_DATA_DIR]\n", argv[0]);
    return 64;
  }
  const fs::path dir = argv[1];
  std::error_code error;
  fs::create_directories(dir, error);
  if (error) {
    std::fprintf(stderr, "cannot create %s: %s\n", dir.c_str(), error.message().c_str());
    return 74;
  }
  write_synthesised(dir);
  std::size_t copied = 0;
  if (argc > 2 && fs::is_directory(argv[2])) {
    // Small real files only: the fuzzer mutates best what it can read quickly.
    for (const auto& entry : fs::recursive_directory_iterator(argv[2])) {
      const std::string ext = entry.path().extension().string();
      if (!entry.is_regular_file() || entry.file_size() > 64 * 1024) continue;
      if (ext != ".las" && ext != ".laz" && ext != ".pcd" && ext != ".ply") continue;
      const std::string name = "shared_" + entry.path().parent_path().filename().string() + "_" +
                               entry.path().filename().string();
      fs::copy_file(entry.path(), dir / name, fs::copy_options::overwrite_existing, error);
      if (!error) ++copied;
    }
  }
  std::printf("seeds in %s: synthesised 7, copied %zu from the shared data\n", dir.c_str(), copied);
  return 0;
}

#endif
