// The LAZ decoder against ../shared/data/laz (README there): each LAZ/COPC file decodes to the
// point records of its LAS reference byte for byte, whatever the thread count and wherever a
// read starts; layered files decode their fitting attributes alone; broken files fail with a
// message naming the file and the chunk, never a crash.

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "csgtile/geo/las.h"
#include "csgtile/geo/point_reader.h"
#include "io/byte_source.h"
#include "io/laz/arithmetic.h"
#include "test_support.h"

namespace csgtile::geo {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

fs::path laz_dir() { return test::shared_dir() / "data" / "laz"; }

#define SKIP_WITHOUT_LAZ_DATA()                                \
  if (!fs::is_directory(laz_dir())) {                          \
    GTEST_SKIP() << "LAZ test data not found at " << laz_dir() \
                 << " (see ../shared/data/laz/README.md)";     \
  }

std::vector<fs::path> laz_files() {
  std::vector<fs::path> files;
  if (!fs::is_directory(laz_dir())) return files;
  for (const auto& e : fs::directory_iterator(laz_dir())) {
    if (e.path().extension() == ".laz") files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

std::vector<std::uint8_t> all_raw(LasReader& reader, std::size_t batch = 7919) {
  std::vector<std::uint8_t> all, part;
  for (;;) {
    auto n = reader.read_raw(part, batch);
    EXPECT_TRUE(n.ok()) << n.error().message;
    if (!n.ok() || n.value() == 0) return all;
    all.insert(all.end(), part.begin(), part.end());
  }
}

std::vector<std::uint8_t> file_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// "records equal" or where the first difference is.
std::string compare_records(const std::vector<std::uint8_t>& got,
                            const std::vector<std::uint8_t>& want, std::size_t record_length) {
  if (got.size() != want.size()) {
    return "sizes differ: " + std::to_string(got.size()) + " vs " + std::to_string(want.size());
  }
  const auto diff = std::mismatch(got.begin(), got.end(), want.begin());
  if (diff.first == got.end()) return "records equal";
  const auto at = static_cast<std::size_t>(diff.first - got.begin());
  return "record " + std::to_string(at / record_length) + " byte " +
         std::to_string(at % record_length) + " differs";
}

TEST(LazReader, EveryFileDecodesToItsLasReferenceByteForByte) {
  SKIP_WITHOUT_LAZ_DATA();
  const auto files = laz_files();
  ASSERT_GE(files.size(), 12u);
  std::size_t checked = 0;
  for (const auto& laz_path : files) {
    SCOPED_TRACE(laz_path.filename().string());
    fs::path las_path = laz_path;
    las_path.replace_extension(".las");
    ASSERT_TRUE(fs::exists(las_path)) << "no reference " << las_path;
    auto laz = LasReader::open(laz_path);
    ASSERT_TRUE(laz.ok()) << laz.error().message;
    auto las = LasReader::open(las_path);
    ASSERT_TRUE(las.ok()) << las.error().message;
    EXPECT_TRUE(laz.value()->compressed());
    EXPECT_FALSE(las.value()->compressed());
    const LasHeader& h = laz.value()->header();
    EXPECT_EQ(h.point_count, las.value()->header().point_count);
    EXPECT_EQ(h.point_format, las.value()->header().point_format);
    ASSERT_EQ(h.record_length, las.value()->header().record_length);
    EXPECT_EQ(laz.value()->evlrs().size(), las.value()->evlrs().size());
    const auto want = all_raw(*las.value());
    const auto got = all_raw(*laz.value());
    EXPECT_EQ(compare_records(got, want, h.record_length), "records equal");
    ++checked;
  }
  EXPECT_EQ(checked, files.size());
}

TEST(LazReader, PointsMatchTheReferenceThroughTheCommonReader) {
  SKIP_WITHOUT_LAZ_DATA();
  for (const auto& laz_path : laz_files()) {
    SCOPED_TRACE(laz_path.filename().string());
    fs::path las_path = laz_path;
    las_path.replace_extension(".las");
    auto laz = open_point_file(laz_path);
    ASSERT_TRUE(laz.ok()) << laz.error().message;
    auto las = open_point_file(las_path);
    ASSERT_TRUE(las.ok()) << las.error().message;
    EXPECT_THAT(laz.value()->info().description, HasSubstr("LAZ"));
    PointBatch a, b;
    std::uint64_t total = 0;
    for (;;) {
      auto na = laz.value()->read(a, 5000);
      auto nb = las.value()->read(b, 5000);
      ASSERT_TRUE(na.ok()) << na.error().message;
      ASSERT_TRUE(nb.ok()) << nb.error().message;
      ASSERT_EQ(na.value(), nb.value());
      if (na.value() == 0) break;
      for (std::size_t i = 0; i < na.value(); ++i) {
        ASSERT_EQ(a.points[i].x, b.points[i].x) << "point " << total + i;
        ASSERT_EQ(a.points[i].y, b.points[i].y);
        ASSERT_EQ(a.points[i].z, b.points[i].z);
        ASSERT_EQ(a.points[i].classification, b.points[i].classification);
        ASSERT_EQ(a.points[i].return_number, b.points[i].return_number);
      }
      EXPECT_EQ(a.extra_bytes, b.extra_bytes);
      total += na.value();
    }
    EXPECT_TRUE(laz.value()->at_end());
  }
}

TEST(LazReader, SameBytesOnOneThreadAndOnAll) {
  SKIP_WITHOUT_LAZ_DATA();
  const fs::path path = laz_dir() / "ahn3_cropped_2.laz";  // five chunks
  if (!fs::exists(path)) GTEST_SKIP() << path << " is absent";
  std::vector<std::uint8_t> one, all;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    auto r = LasReader::open(path);
    ASSERT_TRUE(r.ok()) << r.error().message;
    one = all_raw(*r.value(), 1 << 20);
  }
  {
    auto r = LasReader::open(path);
    ASSERT_TRUE(r.ok()) << r.error().message;
    all = all_raw(*r.value(), 1 << 20);
  }
  EXPECT_EQ(one.size(), 208432u * 28u);
  EXPECT_TRUE(one == all);
}

TEST(LazReader, SeekIntoAChunkReadsTheSameRecordsAsTheReference) {
  SKIP_WITHOUT_LAZ_DATA();
  for (const char* stem : {"ahn3_cropped_2", "simple-laszip-compressor-version-1.2r0",
                           "1.2-with-color.copc", "las_with_several_extra_byte_bloc-chunk0"}) {
    SCOPED_TRACE(stem);
    auto laz = LasReader::open(laz_dir() / (std::string(stem) + ".laz"));
    auto las = LasReader::open(laz_dir() / (std::string(stem) + ".las"));
    ASSERT_TRUE(laz.ok()) << laz.error().message;
    ASSERT_TRUE(las.ok()) << las.error().message;
    const std::uint64_t count = las.value()->readable_points();
    const std::size_t length = las.value()->header().record_length;
    // Forward into the middle of a chunk, then back to an earlier point.
    for (const std::uint64_t at : {count / 2 + 7, count / 3, count - 1, std::uint64_t{0}}) {
      ASSERT_TRUE(laz.value()->seek(at).ok());
      ASSERT_TRUE(las.value()->seek(at).ok());
      std::vector<std::uint8_t> a, b;
      ASSERT_TRUE(laz.value()->read_raw(a, 1000).ok());
      ASSERT_TRUE(las.value()->read_raw(b, 1000).ok());
      EXPECT_EQ(compare_records(a, b, length), "records equal") << "from point " << at;
    }
  }
}

TEST(LazReader, FittingAttributesAloneOfALayeredFile) {
  SKIP_WITHOUT_LAZ_DATA();
  PointReadOptions options;
  options.all_attributes = false;
  for (const char* stem :
       {"las_with_several_extra_byte_bloc-chunk0", "1.2-with-color.copc", "1_4_w_evlr"}) {
    SCOPED_TRACE(stem);
    auto laz = LasReader::open(laz_dir() / (std::string(stem) + ".laz"), options);
    auto las = LasReader::open(laz_dir() / (std::string(stem) + ".las"));
    ASSERT_TRUE(laz.ok()) << laz.error().message;
    ASSERT_TRUE(las.ok()) << las.error().message;
    PointBatch a, b;
    ASSERT_TRUE(laz.value()->read(a, 1 << 20).ok());
    ASSERT_TRUE(las.value()->read(b, 1 << 20).ok());
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
      ASSERT_EQ(a.points[i].x, b.points[i].x) << "point " << i;
      ASSERT_EQ(a.points[i].y, b.points[i].y);
      ASSERT_EQ(a.points[i].z, b.points[i].z);
      ASSERT_EQ(a.points[i].classification, b.points[i].classification);
      ASSERT_EQ(a.points[i].return_number, b.points[i].return_number);
      ASSERT_EQ(a.points[i].number_of_returns, b.points[i].number_of_returns);
    }
  }
}

// Opens `bytes` as a LAZ in memory and reads everything: the result, never a crash.
kernel::Status open_and_read(const std::string& name, const std::vector<std::uint8_t>& bytes) {
  auto r = LasReader::open_memory(name, bytes);
  if (!r.ok()) return r.error();
  PointBatch batch;
  for (;;) {
    auto n = r.value()->read(batch, 4096);
    if (!n.ok()) return n.error();
    if (n.value() == 0) return {};
  }
}

TEST(LazReader, TruncatedFilesFailNamingTheFileAndWhatIsMissing) {
  SKIP_WITHOUT_LAZ_DATA();
  const auto bytes = file_bytes(laz_dir() / "ahn3_cropped_2.laz");
  ASSERT_GT(bytes.size(), 100000u);
  // Cut inside the last chunk: the chunk table (at the end) is gone.
  std::vector<std::uint8_t> cut(bytes.begin(), bytes.begin() + bytes.size() * 9 / 10);
  auto st = open_and_read("cut.laz", cut);
  ASSERT_FALSE(st.ok());
  EXPECT_EQ(st.error().code, kernel::ErrorCode::CorruptData);
  EXPECT_THAT(st.error().message, HasSubstr("cut.laz"));
  EXPECT_THAT(st.error().message, HasSubstr("chunk table"));
}

TEST(LazReader, ACorruptChunkTableIsNamed) {
  SKIP_WITHOUT_LAZ_DATA();
  auto bytes = file_bytes(laz_dir() / "ahn3_cropped_2.laz");
  ASSERT_GT(bytes.size(), 100000u);
  // The table's offset sits at the start of the point data; point it into the points.
  auto las = LasReader::open_memory("probe.laz", bytes);
  ASSERT_TRUE(las.ok());
  const std::uint32_t data = las.value()->header().offset_to_point_data;
  std::int64_t table = 0;
  std::memcpy(&table, bytes.data() + data, 8);
  // 1. A table version that is not 0.
  auto bad = bytes;
  bad[static_cast<std::size_t>(table)] = 7;
  auto st = open_and_read("version.laz", bad);
  ASSERT_FALSE(st.ok());
  EXPECT_THAT(st.error().message, HasSubstr("chunk table"));
  EXPECT_THAT(st.error().message, HasSubstr("version 7"));
  // 2. A chunk count the points cannot fill.
  bad = bytes;
  const std::uint32_t chunks = 4000000;
  std::memcpy(bad.data() + table + 4, &chunks, 4);
  st = open_and_read("count.laz", bad);
  ASSERT_FALSE(st.ok());
  EXPECT_THAT(st.error().message, HasSubstr("4000000 chunks"));
  // 3. An offset past the end of the file.
  bad = bytes;
  const std::int64_t far = 1LL << 40;
  std::memcpy(bad.data() + data, &far, 8);
  st = open_and_read("offset.laz", bad);
  ASSERT_FALSE(st.ok());
  EXPECT_THAT(st.error().message, HasSubstr("outside the point data"));
}

TEST(LazReader, GarbledChunksFailOrDecodeWithoutCrashing) {
  SKIP_WITHOUT_LAZ_DATA();
  // Every file, with bytes of its point data overwritten at a few places: the reader must
  // end, with an error naming a chunk or with points, and never read outside its buffers
  // (the sanitizer build runs this too).
  std::size_t errors = 0, runs = 0;
  for (const auto& path : laz_files()) {
    const auto bytes = file_bytes(path);
    auto probe = LasReader::open_memory("probe", bytes);
    ASSERT_TRUE(probe.ok()) << probe.error().message;
    const std::size_t data = probe.value()->header().offset_to_point_data;
    if (bytes.size() <= data + 64) continue;
    for (int trial = 0; trial < 6; ++trial) {
      auto bad = bytes;
      const std::size_t span = bytes.size() - data - 16;
      const std::size_t at = data + 12 + (span * static_cast<std::size_t>(trial + 1)) / 7;
      for (std::size_t k = 0; k < 8 && at + k < bad.size(); ++k) bad[at + k] ^= 0xA5;
      const auto st = open_and_read(path.filename().string(), bad);
      ++runs;
      if (!st.ok()) {
        ++errors;
        EXPECT_THAT(st.error().message, HasSubstr(path.filename().string()));
      }
    }
  }
  EXPECT_GT(runs, 0u);
  RecordProperty("garbled_runs", static_cast<int>(runs));
  RecordProperty("garbled_errors", static_cast<int>(errors));
}

TEST(LazReader, ABadLaszipVlrIsRefusedByName) {
  SKIP_WITHOUT_LAZ_DATA();
  const auto bytes = file_bytes(laz_dir() / "point10.laz");
  auto probe = LasReader::open_memory("probe", bytes);
  ASSERT_TRUE(probe.ok()) << probe.error().message;
  std::uint64_t payload = 0;
  for (const auto& r : probe.value()->vlrs()) {
    if (r.user_id == "laszip encoded") payload = r.payload_offset;
  }
  ASSERT_NE(payload, 0u);
  auto bad = bytes;
  bad[payload] = 9;  // compressor 9
  auto st = open_and_read("compressor.laz", bad);
  ASSERT_FALSE(st.ok());
  EXPECT_EQ(st.error().code, kernel::ErrorCode::Unsupported);
  EXPECT_THAT(st.error().message, HasSubstr("compressor 9"));
  bad = bytes;
  bad[payload + 34 + 2] = 21;  // POINT10 of 21 bytes
  st = open_and_read("item.laz", bad);
  ASSERT_FALSE(st.ok());
  EXPECT_THAT(st.error().message, HasSubstr("POINT10 v2 (21 bytes)"));
}

// Found by the fuzzer (CI, laz_reader_fuzz_smoke): a layered chunk (formats 6-10) whose xy
// layer is claimed empty while the chunk holds more points. The xy layer is always decoded, so
// its decoder read through a null stream (SEGV). Now it reads its own empty stream past its end
// and the chunk fails by name. All layer sizes zero, and each one alone zero, likewise end
// without a crash.
TEST(LazReader, ALayeredChunkWithAnEmptyXyLayerFailsByName) {
  SKIP_WITHOUT_LAZ_DATA();
  std::size_t layered = 0;
  for (const auto& path : laz_files()) {
    const auto bytes = file_bytes(path);
    auto probe = LasReader::open_memory("probe", bytes);
    ASSERT_TRUE(probe.ok()) << probe.error().message;
    const auto& header = probe.value()->header();
    if (header.point_format < 6 || header.point_count < 2) continue;
    ++layered;
    SCOPED_TRACE(path.filename().string());
    // Chunked layout: the chunk table's offset (8 bytes), the first point raw, the chunk's
    // point count (4 bytes), then the layer sizes, the xy layer's first.
    const std::size_t sizes = header.offset_to_point_data + 8 + header.record_length + 4;
    ASSERT_LT(sizes + 36, bytes.size());
    auto bad = bytes;
    std::memset(bad.data() + sizes, 0, 4);
    auto st = open_and_read("empty-xy.laz", bad);
    ASSERT_FALSE(st.ok());
    EXPECT_EQ(st.error().code, kernel::ErrorCode::CorruptData);
    EXPECT_THAT(st.error().message, HasSubstr("empty-xy.laz"));
    EXPECT_THAT(st.error().message, HasSubstr("chunk 1"));
    for (std::size_t layer = 0; layer < 9; ++layer) {
      bad = bytes;
      std::memset(bad.data() + sizes + 4 * layer, 0, 4);
      (void)open_and_read("one-empty.laz", bad);  // ends, with points or an error
    }
    bad = bytes;
    std::memset(bad.data() + sizes, 0, 36);
    EXPECT_FALSE(open_and_read("all-empty.laz", bad).ok());
  }
  EXPECT_GT(layered, 0u) << "no layered LAZ among the test files";
}

// Layers are taken from a chunk read through a small window (a chunk too large to hold):
// each layer keeps its bytes though the window is refilled under it.
TEST(LazByteStream, LayersTakenAcrossRefilledWindowsKeepTheirBytes) {
  std::vector<std::uint8_t> bytes(100);
  for (std::size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<std::uint8_t>(i * 7 + 1);
  auto source = detail::memory_source("chunk", bytes);
  detail::laz::ByteStream chunk(*source, 10, 80, 16);  // windows of 16 bytes
  (void)chunk.get();                                   // byte 10
  detail::laz::ByteStream a = chunk.take(30);          // bytes 11-40, across three windows
  detail::laz::ByteStream b = chunk.take(5);           // bytes 41-45
  detail::laz::ByteStream c = chunk.take(60);          // 44 bytes left: 16 past the end
  for (std::size_t i = 11; i <= 40; ++i) ASSERT_EQ(a.get(), bytes[i]) << i;
  for (std::size_t i = 41; i <= 45; ++i) ASSERT_EQ(b.get(), bytes[i]) << i;
  for (std::size_t i = 46; i < 90; ++i) ASSERT_EQ(c.get(), bytes[i]) << i;
  EXPECT_EQ(a.overrun() + b.overrun() + c.overrun(), 0u);
  EXPECT_EQ(chunk.overrun(), 16u);
  EXPECT_EQ(c.get(), 0);  // past its own end: zero, counted
  EXPECT_EQ(c.overrun(), 1u);
}

}  // namespace
}  // namespace csgtile::geo
