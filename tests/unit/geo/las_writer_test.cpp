// LAS round trips: synthesised points in every point format of every version they exist in
// (1.0-1.4, formats 0-10), with typed extra bytes and CRS records, written by LasWriter and
// read back by LasReader field by field.

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "csgtile/geo/las.h"
#include "test_support.h"

namespace csgtile::geo {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

// A file in a per-process scratch directory, removed when the test ends.
class TempFile {
 public:
  explicit TempFile(const std::string& name) {
    const fs::path dir =
        fs::temp_directory_path() / ("csgtile_geo_las_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    path_ = dir / name;
  }
  ~TempFile() {
    std::error_code ignored;
    fs::remove(path_, ignored);
    fs::remove(path_.parent_path(), ignored);  // only once empty: other files may still live
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

constexpr std::array<double, 3> kScale{0.001, 0.01, 0.0005};
constexpr std::array<double, 3> kOffset{650000.0, 5400000.0, -20.0};

// Extra bytes of every kind the Extra Bytes VLR can describe, with a gap of undocumented
// bytes in the middle (written as a data-type-0 descriptor) and two trailing undescribed.
ExtraLayout test_layout() {
  ExtraLayout layout;
  auto add = [&](const char* name, ExtraType type, int elements, std::size_t offset) {
    ExtraDimension d;
    d.name = name;
    d.description = std::string("test ") + name;
    d.type = type;
    d.elements = elements;
    d.byte_offset = offset;
    layout.dimensions.push_back(d);
  };
  add("u8", ExtraType::U8, 1, 0);
  add("height", ExtraType::I16, 1, 1);
  layout.dimensions.back().scale = 0.05;
  layout.dimensions.back().offset = 100.0;
  add("colour3", ExtraType::U16, 3, 3);
  add("big", ExtraType::I64, 1, 9);
  // 17..19: undocumented gap
  add("value", ExtraType::F64, 1, 20);
  layout.dimensions.back().no_data = -9999.0;
  layout.dimensions.back().minimum = -1.0;
  layout.dimensions.back().maximum = 1.0;
  add("pair", ExtraType::F32, 2, 28);
  layout.record_size = 38;  // 36..37 undescribed
  return layout;
}

// Deterministic points valid for `format`, on the scale grid so that they survive exactly.
PointBatch synth_points(int format, std::size_t count, const ExtraLayout* layout,
                        std::uint32_t seed) {
  std::mt19937_64 random(seed);
  auto uniform = [&](int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(random); };
  PointBatch batch;
  if (layout != nullptr) batch.layout = std::make_shared<ExtraLayout>(*layout);
  const bool extended = format >= 6;
  for (std::size_t i = 0; i < count; ++i) {
    Point p;
    p.x = uniform(-2000000, 2000000) * kScale[0] + kOffset[0];
    p.y = uniform(-2000000, 2000000) * kScale[1] + kOffset[1];
    p.z = uniform(-200000, 200000) * kScale[2] + kOffset[2];
    p.intensity = static_cast<std::uint16_t>(uniform(0, 65535));
    p.number_of_returns = static_cast<std::uint8_t>(uniform(1, extended ? 15 : 7));
    p.return_number = static_cast<std::uint8_t>(uniform(1, p.number_of_returns));
    p.classification = static_cast<std::uint8_t>(uniform(0, extended ? 255 : 31));
    p.classification_flags = static_cast<std::uint8_t>(uniform(0, extended ? 15 : 7));
    p.scanner_channel = static_cast<std::uint8_t>(extended ? uniform(0, 3) : 0);
    p.scan_direction = uniform(0, 1) == 1;
    p.edge_of_flight_line = uniform(0, 1) == 1;
    p.scan_angle = extended ? static_cast<float>(uniform(-30000, 30000) * 0.006)
                            : static_cast<float>(uniform(-90, 90));
    p.user_data = static_cast<std::uint8_t>(uniform(0, 255));
    p.point_source_id = static_cast<std::uint16_t>(uniform(0, 65535));
    if (format == 1 || format >= 3) p.gps_time = uniform(0, 1 << 30) * 1e-6 + 1e8;
    if (format == 2 || format == 3 || format == 5 || format == 7 || format == 8 || format == 10) {
      p.red = static_cast<std::uint16_t>(uniform(0, 65535));
      p.green = static_cast<std::uint16_t>(uniform(0, 65535));
      p.blue = static_cast<std::uint16_t>(uniform(0, 65535));
    }
    if (format == 8 || format == 10) p.nir = static_cast<std::uint16_t>(uniform(0, 65535));
    std::vector<std::uint8_t> extra(layout != nullptr ? layout->record_size : 0);
    for (auto& b : extra) b = static_cast<std::uint8_t>(uniform(0, 255));
    batch.append(p, extra);
  }
  return batch;
}

void expect_same_point(const Point& a, const Point& b, int format) {
  EXPECT_EQ(a.x, b.x);
  EXPECT_EQ(a.y, b.y);
  EXPECT_EQ(a.z, b.z);
  EXPECT_EQ(a.intensity, b.intensity);
  EXPECT_EQ(a.return_number, b.return_number);
  EXPECT_EQ(a.number_of_returns, b.number_of_returns);
  EXPECT_EQ(a.classification, b.classification);
  EXPECT_EQ(a.classification_flags, b.classification_flags);
  EXPECT_EQ(a.scanner_channel, b.scanner_channel);
  EXPECT_EQ(a.scan_direction, b.scan_direction);
  EXPECT_EQ(a.edge_of_flight_line, b.edge_of_flight_line);
  EXPECT_NEAR(a.scan_angle, b.scan_angle, format >= 6 ? 1e-3 : 0.0);
  EXPECT_EQ(a.user_data, b.user_data);
  EXPECT_EQ(a.point_source_id, b.point_source_id);
  EXPECT_EQ(a.gps_time, b.gps_time);
  EXPECT_EQ(a.red, b.red);
  EXPECT_EQ(a.green, b.green);
  EXPECT_EQ(a.blue, b.blue);
  EXPECT_EQ(a.nir, b.nir);
}

struct VersionFormat {
  int minor;
  int format;
};

std::vector<VersionFormat> every_version_and_format() {
  std::vector<VersionFormat> out;
  for (int minor = 0; minor <= 4; ++minor) {
    const int last = minor <= 1 ? 1 : minor == 2 ? 3 : minor == 3 ? 5 : 10;
    for (int format = 0; format <= last; ++format) out.push_back({minor, format});
  }
  return out;
}

class LasRoundTrip : public ::testing::TestWithParam<VersionFormat> {};

TEST_P(LasRoundTrip, EveryFieldAndExtraByteSurvives) {
  const auto [minor, format] = GetParam();
  TempFile file("roundtrip_1" + std::to_string(minor) + "_" + std::to_string(format) + ".las");
  LasWriteOptions options;
  options.version_minor = static_cast<std::uint8_t>(minor);
  options.point_format = static_cast<std::uint8_t>(format);
  options.scale = kScale;
  options.offset = kOffset;
  options.extra = test_layout();
  const PointBatch written = synth_points(format, 1001, &options.extra, 17u * minor + format);
  {
    auto writer = LasWriter::create(file.path(), options);
    ASSERT_TRUE(writer.ok()) << writer.error().message;
    // Two writes: the writer streams.
    PointBatch first = written, second = written;
    first.points.resize(600);
    first.extra_bytes.resize(600 * 38);
    second.points.erase(second.points.begin(), second.points.begin() + 600);
    second.extra_bytes.erase(second.extra_bytes.begin(), second.extra_bytes.begin() + 600 * 38);
    ASSERT_TRUE(writer.value()->write(first).ok());
    ASSERT_TRUE(writer.value()->write(second).ok());
    ASSERT_TRUE(writer.value()->close().ok());
    EXPECT_EQ(writer.value()->points_written(), 1001u);
  }

  auto reader = LasReader::open(file.path());
  ASSERT_TRUE(reader.ok()) << reader.error().message;
  LasReader& las = *reader.value();
  const LasHeader& h = las.header();
  EXPECT_EQ(h.version_major, 1);
  EXPECT_EQ(h.version_minor, minor);
  EXPECT_EQ(h.point_format, format);
  EXPECT_EQ(h.record_length, las_point_format_length(format) + 38);
  EXPECT_EQ(h.extra_bytes_per_point(), 38);
  EXPECT_EQ(h.point_count, 1001u);
  EXPECT_EQ(h.header_size, minor <= 2 ? 227 : minor == 3 ? 235 : 375);
  EXPECT_EQ(h.scale, kScale);
  EXPECT_EQ(h.offset, kOffset);
  EXPECT_EQ(h.legacy_point_count, format < 6 ? 1001u : 0u);
  EXPECT_TRUE(las.warnings().empty()) << las.warnings().front();

  // Extra bytes descriptors, gap included.
  ASSERT_NE(las.info().extra, nullptr);
  const ExtraLayout& layout = *las.info().extra;
  EXPECT_EQ(layout.record_size, 38u);
  std::vector<std::string> names;
  for (const auto& d : layout.dimensions) names.push_back(d.name);
  EXPECT_THAT(names, ::testing::ElementsAre("u8", "height", "colour3", "big", "unused 17", "value",
                                            "pair"));
  EXPECT_EQ(layout.find("height")->scale, 0.05);
  EXPECT_EQ(layout.find("height")->offset, 100.0);
  EXPECT_EQ(layout.find("value")->no_data, -9999.0);
  EXPECT_EQ(layout.find("value")->maximum, 1.0);
  EXPECT_EQ(layout.find("pair")->elements, 2);
  EXPECT_EQ(layout.find("colour3")->description, "test colour3");
  EXPECT_EQ(layout.undescribed_bytes(), 2u);

  PointBatch batch;
  std::vector<Point> points;
  std::vector<std::uint8_t> extra;
  while (las.read(batch, 333).value() > 0) {
    points.insert(points.end(), batch.points.begin(), batch.points.end());
    extra.insert(extra.end(), batch.extra_bytes.begin(), batch.extra_bytes.end());
  }
  ASSERT_EQ(points.size(), written.points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    SCOPED_TRACE("point " + std::to_string(i));
    expect_same_point(points[i], written.points[i], format);
    if (HasFailure()) break;
  }
  EXPECT_EQ(extra, written.extra_bytes);

  // Header bounds and returns are those of the points.
  Bounds3 expected;
  std::array<std::uint64_t, 15> by_return{};
  for (const auto& p : written.points) {
    expected.add(p.x, p.y, p.z);
    ++by_return[p.return_number - 1];
  }
  EXPECT_EQ(h.min, expected.min);
  EXPECT_EQ(h.max, expected.max);
  for (int r = 0; r < (minor >= 4 ? 15 : 5); ++r) {
    EXPECT_EQ(h.points_by_return[r], by_return[r]) << "return " << r + 1;
  }
  EXPECT_FALSE(std::any_of(las.warnings().begin(), las.warnings().end(), [](const std::string& w) {
    return w.find("outside") != std::string::npos;
  }));
}

std::string version_format_name(const ::testing::TestParamInfo<VersionFormat>& info) {
  return "v1" + std::to_string(info.param.minor) + "_format" + std::to_string(info.param.format);
}

INSTANTIATE_TEST_SUITE_P(EveryVersionAndFormat, LasRoundTrip,
                         ::testing::ValuesIn(every_version_and_format()), version_format_name);

TEST(LasWriter, Las10PutsThePointDataStartSignatureAfterTheVlrs) {
  TempFile file("signature.las");
  LasWriteOptions options;
  options.version_minor = 0;
  options.point_format = 1;
  options.scale = kScale;
  options.offset = kOffset;
  const auto status = write_las(file.path(), options, synth_points(1, 3, nullptr, 1));
  ASSERT_TRUE(status.ok()) << status.error().message;
  const std::string bytes = test::read_file(file.path());
  auto reader = LasReader::open(file.path());
  ASSERT_TRUE(reader.ok()) << reader.error().message;
  const auto offset = reader.value()->header().offset_to_point_data;
  ASSERT_EQ(offset, 229u);
  EXPECT_EQ(static_cast<unsigned char>(bytes[227]), 0xDD);
  EXPECT_EQ(static_cast<unsigned char>(bytes[228]), 0xCC);
}

TEST(LasWriter, CrsRecordsVlrsAndEvlrsRoundTrip) {
  TempFile file("crs.las");
  LasWriteOptions options;
  options.version_minor = 4;
  options.point_format = 6;
  options.scale = kScale;
  options.offset = kOffset;
  options.wkt = "PROJCS[\"ETRS89 / UTM zone 32N\",AUTHORITY[\"EPSG\",\"25832\"]]";
  options.wkt_in_evlr = true;
  GeoKey model;
  model.id = kGeoKeyModelType;
  model.value_offset = 1;
  GeoKey projected;
  projected.id = kGeoKeyProjectedCsType;
  projected.value_offset = 25832;
  GeoKey citation;
  citation.id = kGeoKeyCitation;
  citation.location = 34737;
  citation.ascii = "ETRS89 / UTM 32N";
  GeoKey parallel;
  parallel.id = 3078;
  parallel.doubles = {52.5};
  options.geo_keys = {model, citation, projected, parallel};
  LasRecord custom;
  custom.user_id = "csgtile";
  custom.record_id = 7;
  custom.description = "a custom record";
  custom.data = std::vector<std::uint8_t>{1, 2, 3};
  options.vlrs = {custom};
  custom.record_id = 8;
  custom.data = std::vector<std::uint8_t>(70000, 9);  // longer than a VLR could hold
  options.evlrs = {custom};
  const auto status = write_las(file.path(), options, synth_points(6, 10, nullptr, 2));
  ASSERT_TRUE(status.ok()) << status.error().message;

  auto reader = LasReader::open(file.path());
  ASSERT_TRUE(reader.ok()) << reader.error().message;
  const LasReader& las = *reader.value();
  const LasCrsRecords& crs = las.crs();
  EXPECT_EQ(crs.wkt, options.wkt);
  EXPECT_TRUE(crs.wkt_from_evlr);
  EXPECT_TRUE(crs.wkt_flag);
  EXPECT_EQ(crs.projected_cs, 25832);
  EXPECT_EQ(crs.model_type, 1);
  ASSERT_NE(crs.find(kGeoKeyCitation), nullptr);
  EXPECT_EQ(crs.find(kGeoKeyCitation)->ascii, "ETRS89 / UTM 32N");
  ASSERT_NE(crs.find(3078), nullptr);
  EXPECT_EQ(crs.find(3078)->doubles, std::vector<double>{52.5});
  EXPECT_TRUE(crs.warnings.empty()) << crs.warnings.front();
  ASSERT_EQ(las.evlrs().size(), 2u);
  EXPECT_EQ(las.evlrs()[1].length, 70000u);
  EXPECT_EQ(las.evlrs()[1].data->size(), 70000u);
  const auto custom_vlr = std::find_if(las.vlrs().begin(), las.vlrs().end(),
                                       [](const LasRecord& r) { return r.user_id == "csgtile"; });
  ASSERT_NE(custom_vlr, las.vlrs().end());
  EXPECT_EQ(custom_vlr->description, "a custom record");
  EXPECT_EQ(*custom_vlr->data, (std::vector<std::uint8_t>{1, 2, 3}));
}

TEST(LasWriter, IdenticalInputsGiveIdenticalFiles) {
  TempFile a("same_a.las"), b("same_b.las");
  LasWriteOptions options;
  options.scale = kScale;
  options.offset = kOffset;
  options.extra = test_layout();
  const PointBatch points = synth_points(6, 100, &options.extra, 5);
  ASSERT_TRUE(write_las(a.path(), options, points).ok());
  ASSERT_TRUE(write_las(b.path(), options, points).ok());
  EXPECT_EQ(test::read_file(a.path()), test::read_file(b.path()));
}

TEST(LasWriter, RefusesWhatTheFormatCannotHold) {
  TempFile file("refused.las");
  LasWriteOptions options;
  options.version_minor = 2;
  options.point_format = 6;
  auto writer = LasWriter::create(file.path(), options);
  ASSERT_FALSE(writer.ok());
  EXPECT_EQ(writer.error().code, kernel::ErrorCode::InvalidArgument);
  EXPECT_THAT(writer.error().message, HasSubstr("point format 6 needs LAS 1.4"));

  options.point_format = 1;
  options.evlrs.push_back(LasRecord{});
  writer = LasWriter::create(file.path(), options);
  ASSERT_FALSE(writer.ok());
  EXPECT_THAT(writer.error().message, HasSubstr("EVLRs need LAS 1.4"));

  options.evlrs.clear();
  writer = LasWriter::create(file.path(), options);
  ASSERT_TRUE(writer.ok());
  PointBatch far;
  Point p;
  p.x = 1e12;  // 1e15 steps of a millimetre: past int32
  far.append(p);
  auto status = writer.value()->write(far);
  ASSERT_FALSE(status.ok());
  EXPECT_THAT(status.error().message, HasSubstr("does not fit a 32-bit integer"));

  PointBatch classy;
  p.x = 0;
  p.classification = 40;
  classy.append(p);
  status = writer.value()->write(classy);
  ASSERT_FALSE(status.ok());
  EXPECT_THAT(status.error().message, HasSubstr("classes 0-31"));
}

TEST(LasWriter, AnEmptyFileReadsAsNoPoints) {
  TempFile file("empty.las");
  ASSERT_TRUE(write_las(file.path(), LasWriteOptions{}, PointBatch{}).ok());
  auto reader = LasReader::open(file.path());
  ASSERT_TRUE(reader.ok()) << reader.error().message;
  PointBatch batch;
  EXPECT_EQ(reader.value()->read(batch, 10).value(), 0u);
  EXPECT_TRUE(reader.value()->at_end());
  EXPECT_TRUE(reader.value()->warnings().empty());
}

}  // namespace
}  // namespace csgtile::geo
