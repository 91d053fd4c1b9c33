// Hostile and broken LAS headers: every field that drives a read or an allocation is checked
// against the data present, and each lie gives an error naming the file, the field and the
// values — before anything is allocated from it. Also: reading stays within bounded memory.

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "csgtile/geo/las.h"
#include "test_support.h"

namespace csgtile::geo {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

using Bytes = std::vector<std::uint8_t>;

// Temporary directories of this suite.
struct TempDir : test::TempDir {
  TempDir() : test::TempDir("csgtile_geo_hostile_") {}
};

Bytes file_bytes(const fs::path& path) {
  const std::string text = test::read_file(path);
  return Bytes(text.begin(), text.end());
}

// A valid LAS file: `points` points of `format` in version 1.`minor`, optionally with a VLR
// and an EVLR, as bytes.
Bytes valid_las(int minor, int format, std::size_t points, bool records = false) {
  TempDir dir;
  const fs::path path = dir / "valid.las";
  LasWriteOptions options;
  options.version_minor = static_cast<std::uint8_t>(minor);
  options.point_format = static_cast<std::uint8_t>(format);
  if (records) {
    LasRecord r;
    r.user_id = "test";
    r.record_id = 1;
    r.data = Bytes(100, 7);
    options.vlrs.push_back(r);
    if (minor >= 4) options.evlrs.push_back(r);
  }
  PointBatch batch;
  for (std::size_t i = 0; i < points; ++i) {
    Point p;
    p.x = static_cast<double>(i);
    p.y = 2.0 * static_cast<double>(i);
    p.z = 1.0;
    p.return_number = p.number_of_returns = 1;
    batch.append(p);
  }
  EXPECT_TRUE(write_las(path, options, batch).ok());
  return file_bytes(path);
}

template <class T>
void poke(Bytes& bytes, std::size_t at, T value) {
  std::memcpy(bytes.data() + at, &value, sizeof(T));  // the test host is little-endian
}

template <class T>
T peek(const Bytes& bytes, std::size_t at) {
  T value;
  std::memcpy(&value, bytes.data() + at, sizeof(T));
  return value;
}

kernel::Error open_error(const Bytes& bytes, const PointReadOptions& options = {}) {
  auto reader = LasReader::open_memory("hostile.las", bytes, options);
  EXPECT_FALSE(reader.ok()) << "the file was accepted";
  return reader.ok() ? kernel::Error{kernel::ErrorCode::InvalidArgument, "accepted"}
                     : reader.error();
}

constexpr std::size_t kHeaderSize = 94, kOffsetToPoints = 96, kVlrCount = 100, kPointFormat = 104,
                      kRecordLength = 105, kLegacyCount = 107, kScaleX = 131, kEvlrOffset = 235,
                      kEvlrCount = 243, kPointCount = 247;

TEST(LasHostile, HugeLegacyPointCountIsATruncationNamingBothCounts) {
  Bytes las = valid_las(2, 3, 10);
  poke<std::uint32_t>(las, kLegacyCount, 0xFFFFFFFFu);
  const auto error = open_error(las);
  EXPECT_EQ(error.code, kernel::ErrorCode::CorruptData);
  EXPECT_THAT(error.message, HasSubstr("hostile.las"));
  EXPECT_THAT(error.message, HasSubstr("point count is 4294967295 records of 34 bytes"));
  EXPECT_THAT(error.message, HasSubstr("10 complete records"));
}

TEST(LasHostile, Huge64BitPointCountDoesNotOverflow) {
  Bytes las = valid_las(4, 6, 10);
  poke<std::uint64_t>(las, kPointCount, 0x8000000000000001ull);
  const auto error = open_error(las);
  EXPECT_THAT(error.message, HasSubstr("point count is 9223372036854775809"));
  EXPECT_THAT(error.message, HasSubstr("10 complete records"));
}

TEST(LasHostile, OffsetToPointDataPastTheEnd) {
  Bytes las = valid_las(2, 1, 3);
  poke<std::uint32_t>(las, kOffsetToPoints, 4000000000u);
  const auto error = open_error(las);
  EXPECT_THAT(error.message,
              HasSubstr("offset to point data 4000000000 passes the end of the file (" +
                        std::to_string(las.size()) + " bytes)"));
}

TEST(LasHostile, OffsetToPointDataInsideTheHeader) {
  Bytes las = valid_las(2, 1, 3);
  poke<std::uint32_t>(las, kOffsetToPoints, 100u);
  EXPECT_THAT(open_error(las).message,
              HasSubstr("offset to point data 100 lies inside the header (header size 227)"));
}

TEST(LasHostile, HeaderSizePastTheEndOrTooSmall) {
  Bytes las = valid_las(2, 1, 3);
  poke<std::uint16_t>(las, kHeaderSize, 60000);
  EXPECT_THAT(open_error(las).message, HasSubstr("header size 60000 passes the end of the file"));
  poke<std::uint16_t>(las, kHeaderSize, 100);
  EXPECT_THAT(open_error(las).message, HasSubstr("header size 100 is smaller than the 227"));
}

TEST(LasHostile, VlrCountLargerThanTheSpaceBeforeThePoints) {
  Bytes las = valid_las(2, 1, 3, true);
  poke<std::uint32_t>(las, kVlrCount, 1000000u);
  EXPECT_THAT(open_error(las).message,
              HasSubstr("VLR count 1000000 needs at least 54000000 bytes, but only 154 lie "
                        "between the header (227 bytes) and the point data (offset 381)"));
}

TEST(LasHostile, VlrLengthPastTheEndOfTheFile) {
  Bytes las = valid_las(2, 1, 3, true);
  poke<std::uint16_t>(las, 227 + 20, 65535);
  const auto error = open_error(las);
  EXPECT_THAT(error.message, HasSubstr("VLR 1 of 1 (user id \"test\", record id 1): length 65535"));
  EXPECT_THAT(error.message, HasSubstr("past the end of the file"));
}

TEST(LasHostile, VlrLengthIntoThePointData) {
  Bytes las = valid_las(2, 1, 300, true);
  poke<std::uint16_t>(las, 227 + 20, 200);
  EXPECT_THAT(
      open_error(las).message,
      HasSubstr("length 200 ends at byte 481, past the start of the point data (offset 381)"));
}

TEST(LasHostile, RecordLengthSmallerThanTheFormat) {
  Bytes las = valid_las(4, 6, 3);
  poke<std::uint16_t>(las, kRecordLength, 10);
  const auto error = open_error(las);
  EXPECT_EQ(error.code, kernel::ErrorCode::CorruptData);
  EXPECT_THAT(error.message,
              HasSubstr("point record length 10 is smaller than point format 6's minimum of 30"));
}

TEST(LasHostile, EvlrOffsetPastTheEndOrBeforeThePoints) {
  Bytes las = valid_las(4, 6, 3, true);
  const auto evlr_offset = peek<std::uint64_t>(las, kEvlrOffset);
  ASSERT_GT(evlr_offset, 0u);
  poke<std::uint64_t>(las, kEvlrOffset, 1ull << 40);
  EXPECT_THAT(open_error(las).message,
              HasSubstr("start of first EVLR 1099511627776 passes the end of the file"));
  poke<std::uint64_t>(las, kEvlrOffset, 300);
  EXPECT_THAT(open_error(las).message, HasSubstr("lies before the point data"));
  // Inside the point records: the points would run into the EVLR.
  poke<std::uint64_t>(las, kEvlrOffset, evlr_offset - 10);
  EXPECT_THAT(open_error(las).message, HasSubstr("and the first EVLR (byte"));
}

TEST(LasHostile, EvlrCountAndLengthPastTheEnd) {
  Bytes las = valid_las(4, 6, 3, true);
  poke<std::uint32_t>(las, kEvlrCount, 0xFFFFFFFFu);
  EXPECT_THAT(open_error(las).message, HasSubstr("EVLR count 4294967295 needs at least"));
  poke<std::uint32_t>(las, kEvlrCount, 1);
  const auto evlr_offset = peek<std::uint64_t>(las, kEvlrOffset);
  poke<std::uint64_t>(las, evlr_offset + 20, 1ull << 62);
  EXPECT_THAT(open_error(las).message,
              HasSubstr("EVLR 1 of 1 (user id \"test\", record id 1): length 4611686018427387904 "
                        "passes the end of the file"));
}

TEST(LasHostile, CompressedWithoutAUsableLaszipVlrIsRefusedByName) {
  // The compression bit without the VLR that says how.
  Bytes las = valid_las(2, 3, 3);
  poke<std::uint8_t>(las, kPointFormat, 3 | 0x80);
  auto error = open_error(las);
  EXPECT_EQ(error.code, kernel::ErrorCode::CorruptData);
  EXPECT_THAT(error.message, HasSubstr("LAZ-compressed"));
  EXPECT_THAT(error.message, HasSubstr("no laszip VLR"));

  // A laszip VLR whose payload is not one.
  Bytes tagged = valid_las(2, 3, 3, true);
  std::memset(tagged.data() + 227 + 2, 0, 16);
  std::memcpy(tagged.data() + 227 + 2, "laszip encoded", 14);
  poke<std::uint16_t>(tagged, 227 + 18, 22204);
  error = open_error(tagged);
  EXPECT_TRUE(error.code == kernel::ErrorCode::CorruptData ||
              error.code == kernel::ErrorCode::Unsupported);
  EXPECT_THAT(error.message, HasSubstr("laszip VLR"));
}

TEST(LasHostile, VersionsAndFormatsThatDoNotExist) {
  Bytes las = valid_las(2, 1, 3);
  poke<std::uint8_t>(las, 25, 9);
  auto error = open_error(las);
  EXPECT_EQ(error.code, kernel::ErrorCode::UnsupportedVersion);
  EXPECT_THAT(error.message, HasSubstr("LAS version 1.9 is not supported"));
  poke<std::uint8_t>(las, 25, 2);
  poke<std::uint8_t>(las, kPointFormat, 42);
  error = open_error(las);
  EXPECT_EQ(error.code, kernel::ErrorCode::Unsupported);
  EXPECT_THAT(error.message, HasSubstr("point data format 42 is not defined"));
}

TEST(LasHostile, NotLasTooShortOrEmpty) {
  Bytes las = valid_las(2, 1, 3);
  las[0] = 'X';
  EXPECT_THAT(open_error(las).message, HasSubstr("not a LAS file"));
  EXPECT_THAT(open_error(Bytes{}).message, HasSubstr("not a LAS file"));
  Bytes stub = valid_las(2, 1, 3);
  stub.resize(100);
  EXPECT_THAT(open_error(stub).message, HasSubstr("smaller than the smallest LAS header"));
}

TEST(LasHostile, ZeroScaleIsRefused) {
  Bytes las = valid_las(2, 1, 3);
  poke<double>(las, kScaleX, 0.0);
  EXPECT_THAT(open_error(las).message, HasSubstr("scale/offset of x"));
}

TEST(LasHostile, OneByteShortIsTruncatedByDefaultAndReadableOnRequest) {
  Bytes las = valid_las(2, 3, 5);
  las.pop_back();
  EXPECT_THAT(open_error(las).message, HasSubstr("point count is 5 records of 34 bytes, but only "
                                                 "169 bytes"));
  PointReadOptions lenient;
  lenient.accept_truncated = true;
  auto reader = LasReader::open_memory("short.las", las, lenient);
  ASSERT_TRUE(reader.ok()) << reader.error().message;
  PointBatch batch;
  EXPECT_EQ(reader.value()->read(batch, 100).value(), 4u);
  ASSERT_FALSE(reader.value()->warnings().empty());
  EXPECT_THAT(reader.value()->warnings()[0], HasSubstr("4 complete records; reading those"));
}

TEST(LasHostile, BrokenGeoKeysAndExtraDescriptorsAreWarningsNotCrashes) {
  TempDir dir;
  LasWriteOptions options;
  options.point_format = 1;
  options.version_minor = 2;
  GeoKey key;
  key.id = kGeoKeyProjectedCsType;
  key.value_offset = 32632;
  GeoKey dangling;
  dangling.id = 3078;
  dangling.doubles = {1.0};
  options.geo_keys = {key, dangling};
  ExtraDimension d;
  d.name = "wide";
  d.type = ExtraType::F64;
  options.extra.record_size = 8;
  options.extra.dimensions = {d};
  PointBatch batch;
  batch.layout = std::make_shared<ExtraLayout>(options.extra);
  batch.append(Point{});
  ASSERT_TRUE(write_las(dir / "keys.las", options, batch).ok());
  Bytes las = file_bytes(dir / "keys.las");
  // Find the VLRs: extra bytes (54 + 192) come first, then the key directory, then doubles.
  const std::size_t extra_vlr = 227;
  const std::size_t keys_vlr = extra_vlr + 54 + 192;
  ASSERT_EQ(peek<std::uint16_t>(las, keys_vlr + 18), 34735);
  poke<std::uint16_t>(las, keys_vlr + 54 + 6, 50);         // NumberOfKeys: 50, 2 fit
  poke<std::uint16_t>(las, keys_vlr + 54 + 8 + 8 + 6, 9);  // key 2 double index 9 of 1
  poke<std::uint8_t>(las, extra_vlr + 54 + 2, 30);         // three doubles: 24 bytes, 8 present
  auto reader = LasReader::open_memory("keys.las", las);
  ASSERT_TRUE(reader.ok()) << reader.error().message;
  const auto& warnings = reader.value()->warnings();
  auto warned = [&](const std::string& text) {
    return std::any_of(warnings.begin(), warnings.end(),
                       [&](const std::string& w) { return w.find(text) != std::string::npos; });
  };
  EXPECT_TRUE(warned("declares 50 keys but its record (24 bytes) holds only 2"));
  EXPECT_TRUE(warned("GeoKey 3078: double parameters [9, 10) pass the 1 values"));
  EXPECT_TRUE(warned("descriptor 1 (\"wide\", 24 bytes at offset 0) does not fit the 8 extra"));
  EXPECT_EQ(reader.value()->crs().projected_cs, 32632);
  PointBatch out;
  EXPECT_EQ(reader.value()->read(out, 10).value(), 1u);
}

TEST(LasHostile, EveryTruncationOfAValidFileFailsCleanly) {
  // Cutting a file anywhere never crashes: it opens (the cut is in data it does not need)
  // or fails with an error naming the file.
  const Bytes las = valid_las(4, 7, 20, true);
  for (std::size_t size = 0; size < las.size(); size += 7) {
    const Bytes cut(las.begin(), las.begin() + static_cast<std::ptrdiff_t>(size));
    auto reader = LasReader::open_memory("cut.las", cut);
    if (!reader.ok()) {
      EXPECT_THAT(reader.error().message, HasSubstr("cut.las: ")) << size;
      continue;
    }
    PointBatch batch;
    while (true) {
      auto n = reader.value()->read(batch, 3);
      if (!n.ok() || n.value() == 0) break;
    }
  }
}

// Resident set size in bytes (Linux).
std::size_t resident_bytes() {
  std::ifstream statm("/proc/self/statm");
  std::size_t pages = 0, resident = 0;
  statm >> pages >> resident;
  return resident * static_cast<std::size_t>(::sysconf(_SC_PAGESIZE));
}

TEST(LasMemory, ReadingInBatchesDoesNotGrowWithTheFile) {
  TempDir dir;
  const fs::path path = dir / "large.las";
  constexpr std::size_t kPoints = 2'000'000;  // 60 MB of format-6 records
  {
    LasWriteOptions options;
    auto writer = LasWriter::create(path, options);
    ASSERT_TRUE(writer.ok()) << writer.error().message;
    PointBatch batch;
    for (std::size_t done = 0; done < kPoints; done += batch.size()) {
      batch.clear();
      for (std::size_t i = 0; i < 100'000; ++i) {
        Point p;
        p.x = static_cast<double>((done + i) % 100000) * 0.01;
        p.y = static_cast<double>((done + i) / 100000);
        batch.append(p);
      }
      ASSERT_TRUE(writer.value()->write(batch).ok());
    }
    ASSERT_TRUE(writer.value()->close().ok());
  }
  ASSERT_EQ(fs::file_size(path), 375 + kPoints * 30);
  auto reader = LasReader::open(path);
  ASSERT_TRUE(reader.ok()) << reader.error().message;
  PointBatch batch;
  batch.points.reserve(65536);
  const std::size_t before = resident_bytes();
  std::size_t peak = before, total = 0;
  for (;;) {
    auto n = reader.value()->read(batch, 65536);
    ASSERT_TRUE(n.ok()) << n.error().message;
    if (n.value() == 0) break;
    total += n.value();
    peak = std::max(peak, resident_bytes());
  }
  EXPECT_EQ(total, kPoints);
  // One batch (65536 × 72 B = 4.7 MB) plus a 1 MiB chunk: far below the file's 60 MB.
  RecordProperty("resident_growth_kib", static_cast<int>((peak - before) / 1024));
  EXPECT_LT(peak - before, std::size_t{16} << 20)
      << "resident memory grew by " << (peak - before) / 1024 << " KiB reading a "
      << fs::file_size(path) / (1 << 20) << " MiB file";
}

}  // namespace
}  // namespace csgtile::geo
