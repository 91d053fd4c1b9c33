// libFuzzer target for the LAZ decoder (CSGTILE_FUZZ=ON, clang), the LAS fuzzer's sibling:
// the laszip VLR, the chunk table, the arithmetic decoder and every item decoder, fed with
// mutated LAZ and COPC files.
//
// Besides "no crash, no hang, no sanitizer report", an accepted LAZ input must keep the
// decoder's promises: the records read equal readable_points(); a read that starts at a seek
// gives the same records as a read from the start (chunks and streams restart cleanly); and
// decoding only the fitting attributes gives the same coordinates, returns and classes; and
// for a COPC file, a region query (its hierarchy read and checked) never gives a point that a
// whole read does not give inside that region.
//
// Built a second time with CSGTILE_LAZ_SEED_GENERATOR defined, the same file is a program
// that copies the seed corpus: the LAZ and COPC files of ../shared/data up to 256 KiB.

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "csgtile/geo/las.h"
#include "csgtile/geo/point_reader.h"

using namespace csgtile::geo;

#ifndef CSGTILE_LAZ_SEED_GENERATOR

namespace {

void check(bool condition, const char* what) {
  if (!condition) {
    std::fprintf(stderr, "broken LAZ decoder promise: %s\n", what);
    __builtin_trap();
  }
}

// All raw records, or false on a read error.
bool raw_all(LasReader& reader, std::vector<std::uint8_t>& all, std::size_t batch) {
  std::vector<std::uint8_t> part;
  for (int guard = 0; guard < 1000000; ++guard) {
    auto n = reader.read_raw(part, batch);
    if (!n.ok()) return false;
    if (n.value() == 0) return true;
    all.insert(all.end(), part.begin(), part.end());
  }
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::uint8_t> bytes(data, size);
  auto reader = LasReader::open_memory("fuzz.laz", bytes);
  if (!reader.ok() || !reader.value()->compressed()) return 0;
  LasReader& laz = *reader.value();
  // Cap the work: a header may declare far more points than a small input holds.
  if (laz.readable_points() > 2000000) return 0;
  std::vector<std::uint8_t> all;
  if (!raw_all(laz, all, 4099)) return 0;
  const std::size_t length = laz.header().record_length;
  check(all.size() == laz.readable_points() * length, "records read differ from the count");
  const std::uint64_t count = laz.readable_points();
  if (count > 2) {
    const std::uint64_t at = count / 2 + 1;
    check(laz.seek(at).ok(), "seek refused");
    std::vector<std::uint8_t> tail;
    check(raw_all(laz, tail, 1000), "a read after a seek failed where the first succeeded");
    check(tail.size() == (count - at) * length &&
              std::equal(tail.begin(), tail.end(),
                         all.begin() + static_cast<std::ptrdiff_t>(at * length)),
          "records after a seek differ");
  }
  PointReadOptions fit;
  fit.all_attributes = false;
  auto partial = LasReader::open_memory("fuzz.laz", bytes, fit);
  check(partial.ok(), "opened with all attributes but not with the fitting ones");
  PointBatch a;
  auto full = LasReader::open_memory("fuzz.laz", bytes);
  PointBatch b;
  for (int guard = 0; guard < 1000000; ++guard) {
    auto na = partial.value()->read(a, 4096);
    auto nb = full.value()->read(b, 4096);
    check(na.ok() == nb.ok(), "a partial decode fails where the full one does not");
    if (!na.ok() || na.value() == 0) break;
    check(na.value() == nb.value(), "batch sizes differ");
    for (std::size_t i = 0; i < na.value(); ++i) {
      check(std::memcmp(&a.points[i].x, &b.points[i].x, sizeof(double)) == 0 &&
                std::memcmp(&a.points[i].z, &b.points[i].z, sizeof(double)) == 0 &&
                a.points[i].classification == b.points[i].classification &&
                a.points[i].return_number == b.points[i].return_number,
            "fitting attributes differ between a partial and a full decode");
    }
  }
  if (laz.copc() && laz.header().min[0] <= laz.header().max[0]) {
    // A COPC region query: the lower-left quarter of the header's extent.
    PointReadOptions query;
    Bounds3 box;
    const auto& h = laz.header();
    box.min = {h.min[0], h.min[1], -1e300};
    box.max = {0.5 * (h.min[0] + h.max[0]), 0.5 * (h.min[1] + h.max[1]), 1e300};
    query.region = box;
    auto region = LasReader::open_memory("fuzz.copc.laz", bytes, query);
    if (region.ok()) {
      std::vector<std::array<double, 3>> inside, got;
      auto whole = LasReader::open_memory("fuzz.copc.laz", bytes);
      PointBatch batch;
      bool whole_ok = whole.ok();
      for (int guard = 0; whole_ok && guard < 1000000; ++guard) {
        auto n = whole.value()->read(batch, 4096);
        if (!n.ok()) whole_ok = false;
        if (!n.ok() || n.value() == 0) break;
        for (const Point& p : batch.points) {
          if (box.contains(p.x, p.y, p.z, {0, 0, 0})) inside.push_back({p.x, p.y, p.z});
        }
      }
      bool region_ok = true;
      for (int guard = 0; guard < 1000000; ++guard) {
        auto n = region.value()->read(batch, 4096);
        if (!n.ok()) region_ok = false;
        if (!n.ok() || n.value() == 0) break;
        for (const Point& p : batch.points) got.push_back({p.x, p.y, p.z});
      }
      if (whole_ok && region_ok) {
        std::sort(inside.begin(), inside.end());
        std::sort(got.begin(), got.end());
        check(std::includes(inside.begin(), inside.end(), got.begin(), got.end()),
              "a COPC region query gives a point a whole read does not");
      }
    }
  }
  return 0;
}

#else

namespace fs = std::filesystem;

// Usage: laz_reader_fuzz_seeds SEED_DIR SHARED_DATA_DIR
int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s SEED_DIR SHARED_DATA_DIR\n", argv[0]);
    return 64;
  }
  const fs::path dir = argv[1];
  std::error_code error;
  fs::create_directories(dir, error);
  if (error) {
    std::fprintf(stderr, "cannot create %s: %s\n", dir.c_str(), error.message().c_str());
    return 74;
  }
  std::size_t copied = 0;
  if (fs::is_directory(argv[2])) {
    for (const auto& entry : fs::recursive_directory_iterator(argv[2])) {
      if (!entry.is_regular_file() || entry.file_size() > 256 * 1024) continue;
      if (entry.path().extension() != ".laz") continue;
      const std::string name =
          entry.path().parent_path().filename().string() + "_" + entry.path().filename().string();
      fs::copy_file(entry.path(), dir / name, fs::copy_options::overwrite_existing, error);
      if (!error) ++copied;
    }
  }
  if (copied == 0) {
    // Without the shared data there is nothing LAZ to start from; the smoke run then
    // fuzzes from an empty corpus (still bounded), and says so.
    std::printf("no LAZ seeds: %s has no .laz files\n", argv[2]);
  }
  std::printf("seeds in %s: copied %zu LAZ files from the shared data\n", dir.c_str(), copied);
  return 0;
}

#endif
