// The point readers against the real files of ../shared/data (README there): every LAS, LAZ,
// PCD and PLY file either reads with the header's count and bounds, or fails with the message
// its breakage calls for.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "csgtile/geo/las.h"
#include "csgtile/geo/point_reader.h"
#include "test_support.h"

namespace csgtile::geo {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

fs::path data_dir() { return test::shared_dir() / "data"; }

#define SKIP_WITHOUT_DATA()                                        \
  if (!fs::is_directory(data_dir())) {                             \
    GTEST_SKIP() << "shared test data not found at " << data_dir() \
                 << " (see ../shared/data/README.md)";             \
  }

// Opens `relative` under the data directory, skipping when that one file is absent.
#define OPEN_LAS(var, relative)                                                         \
  SKIP_WITHOUT_DATA();                                                                  \
  if (!fs::exists(data_dir() / (relative))) GTEST_SKIP() << (relative) << " is absent"; \
  auto var##_result = LasReader::open(data_dir() / (relative));                         \
  ASSERT_TRUE(var##_result.ok()) << var##_result.error().message;                       \
  LasReader& var = *var##_result.value();

struct ReadAll {
  std::uint64_t count = 0;
  std::optional<kernel::Error> error;
};

ReadAll read_all(PointReader& reader, std::size_t batch_size = 4096) {
  ReadAll out;
  PointBatch batch;
  for (;;) {
    auto n = reader.read(batch, batch_size);
    if (!n.ok()) {
      out.error = n.error();
      return out;
    }
    if (n.value() == 0) return out;
    out.count += n.value();
  }
}

bool has_warning(const PointReader& reader, const std::string& text) {
  return std::any_of(reader.warnings().begin(), reader.warnings().end(),
                     [&](const std::string& w) { return w.find(text) != std::string::npos; });
}

// Files that are broken or refused on purpose, with what the error must say.
struct Refusal {
  kernel::ErrorCode code;
  std::vector<std::string> message_parts;
};

const std::map<std::string, Refusal>& refusals() {
  static const std::map<std::string, Refusal> kRefusals = {
      {"pdal/1.2-with-color-clipped.las",
       {kernel::ErrorCode::CorruptData, {"truncated", "1065", "1064 complete records"}}},
      {"pdal/permutations_1.2-no-points.las",
       {kernel::ErrorCode::CorruptData, {"truncated", "1065", "0 complete records"}}},
      {"pdal/bad_vlr_count.las",
       {kernel::ErrorCode::CorruptData, {"VLR 3 of 3", "offset 429", "VLR count"}}},
  };
  return kRefusals;
}

// Files whose header bounds are looser than their points (allowed: points lie inside).
bool loose_header_bounds(const std::string& relative) {
  return relative == "liblas/certainty3d-color-utm-feet-navd88.las" ||
         relative == "laszip/5points_14.las";
}

std::vector<std::string> point_files() {
  std::vector<std::string> files;
  if (!fs::is_directory(data_dir())) return files;
  for (const auto& entry : fs::recursive_directory_iterator(data_dir())) {
    const std::string ext = entry.path().extension().string();
    if (entry.is_regular_file() &&
        (ext == ".las" || ext == ".laz" || ext == ".pcd" || ext == ".ply")) {
      files.push_back(fs::relative(entry.path(), data_dir()).generic_string());
    }
  }
  std::sort(files.begin(), files.end());
  return files;
}

TEST(SharedPointFiles, EachReadsWithHeaderCountAndBoundsOrFailsWithItsReason) {
  SKIP_WITHOUT_DATA();
  const auto files = point_files();
  ASSERT_FALSE(files.empty()) << "no point files under " << data_dir();
  std::size_t read = 0, refused = 0;
  for (const auto& relative : files) {
    SCOPED_TRACE(relative);
    auto opened = open_point_file(data_dir() / relative);
    if (auto it = refusals().find(relative); it != refusals().end()) {
      ASSERT_FALSE(opened.ok()) << "expected a refusal";
      EXPECT_EQ(opened.error().code, it->second.code);
      for (const auto& part : it->second.message_parts) {
        EXPECT_THAT(opened.error().message, HasSubstr(part));
      }
      EXPECT_THAT(opened.error().message, HasSubstr(relative));  // names the file
      ++refused;
      continue;
    }
    ASSERT_TRUE(opened.ok()) << opened.error().message;
    PointReader& reader = *opened.value();
    const ReadAll all = read_all(reader);
    ASSERT_FALSE(all.error) << all.error->message;
    EXPECT_TRUE(reader.at_end());
    ASSERT_TRUE(reader.info().point_count.has_value());
    const std::uint64_t declared = *reader.info().point_count;
    // Organised PCD clouds mark holes with NaN: those are dropped and counted in a warning.
    if (all.count != declared) {
      EXPECT_LT(all.count, declared);
      EXPECT_TRUE(has_warning(reader, "NaN or infinite coordinates were dropped"));
    }
    EXPECT_EQ(reader.points_read(), all.count);
    EXPECT_FALSE(has_warning(reader, "outside the header bounds"));
    if (reader.info().bounds && all.count > 0) {
      const Bounds3& header = *reader.info().bounds;
      const Bounds3& scanned = reader.bounds_read();
      const auto& tol = reader.info().bounds_tolerance;
      for (int axis = 0; axis < 3; ++axis) {
        EXPECT_GE(scanned.min[axis], header.min[axis] - tol[axis]) << "axis " << axis;
        EXPECT_LE(scanned.max[axis], header.max[axis] + tol[axis]) << "axis " << axis;
        if (!loose_header_bounds(relative)) {
          EXPECT_NEAR(scanned.min[axis], header.min[axis], tol[axis]) << "axis " << axis;
          EXPECT_NEAR(scanned.max[axis], header.max[axis], tol[axis]) << "axis " << axis;
        }
      }
    }
    ++read;
  }
  EXPECT_EQ(refused, refusals().size()) << "some broken-on-purpose files are missing";
  EXPECT_GT(read, 60u);
}

TEST(SharedPointFiles, TruncatedFileReadsItsCompleteRecordsWhenAskedWithAWarning) {
  SKIP_WITHOUT_DATA();
  PointReadOptions options;
  options.accept_truncated = true;
  auto opened = LasReader::open(data_dir() / "pdal/1.2-with-color-clipped.las", options);
  ASSERT_TRUE(opened.ok()) << opened.error().message;
  EXPECT_EQ(opened.value()->readable_points(), 1064u);
  EXPECT_EQ(read_all(*opened.value()).count, 1064u);
  EXPECT_TRUE(has_warning(*opened.value(), "1064 complete records"));
}

TEST(SharedLas, FirstPointOfFormat3HasEveryFieldRight) {
  OPEN_LAS(las, "pdal/simple.las");
  PointBatch batch;
  ASSERT_TRUE(las.read(batch, 1).ok());
  ASSERT_EQ(batch.size(), 1u);
  const Point& p = batch.points[0];
  EXPECT_DOUBLE_EQ(p.x, 637012.24);
  EXPECT_DOUBLE_EQ(p.y, 849028.31);
  EXPECT_DOUBLE_EQ(p.z, 431.66);
  EXPECT_EQ(p.intensity, 143);
  EXPECT_EQ(p.return_number, 1);
  EXPECT_EQ(p.number_of_returns, 1);
  EXPECT_TRUE(p.scan_direction);
  EXPECT_FALSE(p.edge_of_flight_line);
  EXPECT_EQ(p.classification, 1);
  EXPECT_FLOAT_EQ(p.scan_angle, -9.0F);
  EXPECT_EQ(p.user_data, 132);
  EXPECT_EQ(p.point_source_id, 7326);
  EXPECT_DOUBLE_EQ(p.gps_time, 245380.78254962614);
  EXPECT_EQ(p.red, 68);
  EXPECT_EQ(p.green, 77);
  EXPECT_EQ(p.blue, 88);
}

TEST(SharedLas, Format6FlagsChannelScanAngleAndScaledExtraBytes) {
  OPEN_LAS(las, "laszip/5points_14.las");
  ASSERT_NE(las.info().extra, nullptr);
  const ExtraLayout& layout = *las.info().extra;
  EXPECT_EQ(layout.record_size, 3u);
  ASSERT_EQ(layout.dimensions.size(), 2u);
  EXPECT_EQ(layout.dimensions[0].name, "height above ground");
  EXPECT_EQ(layout.dimensions[0].type, ExtraType::I16);
  EXPECT_EQ(layout.dimensions[0].scale, 0.05);
  EXPECT_EQ(layout.dimensions[1].name, "coverage count");
  EXPECT_EQ(layout.dimensions[1].type, ExtraType::U8);
  EXPECT_EQ(layout.dimensions[1].byte_offset, 2u);

  PointBatch batch;
  ASSERT_TRUE(las.read(batch, 5).ok());
  ASSERT_EQ(batch.size(), 5u);
  const Point& p = batch.points[0];
  EXPECT_EQ(p.return_number, 2);
  EXPECT_EQ(p.number_of_returns, 2);
  EXPECT_EQ(p.classification_flags, kFlagOverlap);
  EXPECT_EQ(p.scanner_channel, 1);
  EXPECT_EQ(p.classification, 2);
  EXPECT_NEAR(p.scan_angle, 21.0, 1e-4);
  EXPECT_DOUBLE_EQ(p.gps_time, 53413162.5604);
  EXPECT_DOUBLE_EQ(batch.extra_value(0, "height above ground").value(), 12.5);
  EXPECT_EQ(std::get<std::int64_t>(batch.extra_raw(0, "height above ground").value()), 250);
  EXPECT_DOUBLE_EQ(batch.extra_value(0, "coverage count").value(), 3.0);
  EXPECT_FALSE(batch.extra_value(0, "no such dimension").has_value());
}

TEST(SharedLas, TypedExtraBytesIncludingDeprecatedArrayTypesAndUndocumentedBytes) {
  OPEN_LAS(las, "pdal/extrabytes.las");
  ASSERT_NE(las.info().extra, nullptr);
  const ExtraLayout& layout = *las.info().extra;
  EXPECT_EQ(layout.record_size, 27u);
  ASSERT_EQ(layout.dimensions.size(), 5u);
  struct Expect {
    const char* name;
    ExtraType type;
    int elements;
    std::size_t offset;
  };
  const Expect expected[] = {{"Colors", ExtraType::U16, 3, 0},
                             {"Reserved", ExtraType::Raw, 7, 6},
                             {"Flags", ExtraType::I8, 2, 13},
                             {"Intensity", ExtraType::U32, 1, 15},
                             {"Time", ExtraType::U64, 1, 19}};
  for (std::size_t i = 0; i < 5; ++i) {
    SCOPED_TRACE(expected[i].name);
    EXPECT_EQ(layout.dimensions[i].name, expected[i].name);
    EXPECT_EQ(layout.dimensions[i].type, expected[i].type);
    EXPECT_EQ(layout.dimensions[i].elements, expected[i].elements);
    EXPECT_EQ(layout.dimensions[i].byte_offset, expected[i].offset);
  }
  EXPECT_EQ(layout.undescribed_bytes(), 0u);
  PointBatch batch;
  ASSERT_TRUE(las.read(batch, 1).ok());
  EXPECT_EQ(batch.extra_value(0, "Colors", 0), 68.0);
  EXPECT_EQ(batch.extra_value(0, "Colors", 1), 77.0);
  EXPECT_EQ(batch.extra_value(0, "Colors", 2), 88.0);
  EXPECT_FALSE(batch.extra_value(0, "Colors", 3).has_value());
  EXPECT_EQ(batch.extra_value(0, "Flags", 1), 1.0);
  EXPECT_EQ(batch.extra_value(0, "Intensity"), 143.0);
  EXPECT_EQ(std::get<std::uint64_t>(batch.extra_raw(0, "Time").value()), 245380u);
  EXPECT_FALSE(batch.extra_value(0, "Reserved").has_value());  // raw bytes have no value
  // The same values as the point's own fields, which this file duplicates.
  EXPECT_EQ(batch.points[0].intensity, 143);
  EXPECT_EQ(batch.points[0].red, 68);
}

TEST(SharedLas, ExtraBytesWithoutDescriptorStayRaw) {
  OPEN_LAS(las, "laspy/unregistered_extra_bytes.las");
  ASSERT_NE(las.info().extra, nullptr);
  EXPECT_EQ(las.info().extra->record_size, 4u);
  EXPECT_TRUE(las.info().extra->dimensions.empty());
  EXPECT_EQ(las.info().extra->undescribed_bytes(), 4u);
  PointBatch batch;
  ASSERT_TRUE(las.read(batch, 10).ok());
  ASSERT_EQ(batch.size(), 4u);
  EXPECT_EQ(batch.extra(3).size(), 4u);
}

TEST(SharedLas, ExtraBytesInA12FileWithRieglDescriptors) {
  OPEN_LAS(las, "pdal/1.2-empty-geotiff-vlrs.las");
  ASSERT_NE(las.info().extra, nullptr);
  const ExtraLayout& layout = *las.info().extra;
  EXPECT_EQ(layout.record_size, 6u);
  ASSERT_EQ(layout.dimensions.size(), 3u);
  EXPECT_EQ(layout.dimensions[0].name, "Amplitude");
  EXPECT_EQ(layout.dimensions[0].scale, 0.01);
  EXPECT_EQ(layout.dimensions[1].type, ExtraType::I16);
  EXPECT_EQ(layout.dimensions[2].name, "Deviation");
}

TEST(SharedLas, GeoTiffEpsgCodes) {
  SKIP_WITHOUT_DATA();
  struct Case {
    const char* file;
    std::optional<std::uint16_t> projected, geographic, vertical, linear_units;
  };
  const Case cases[] = {
      {"las-rs/32-1-472-150-76.las", 25832, std::nullopt, 5941, 9001},
      {"liblas/srs_vertcs.las", 32617, std::nullopt, 5703, 9001},
      {"pdal/permutations_1.2_0.las", 26915, std::nullopt, std::nullopt, 9001},
      {"pdal/autzen-utm.las", 26910, std::nullopt, std::nullopt, 9001},
      {"pdal/epsg_4326.las", std::nullopt, 4326, std::nullopt, std::nullopt},
      {"pdal/interesting.las", kGeoKeyUserDefined, kGeoKeyUserDefined, std::nullopt, 9002},
      {"laspy/plane.las", kGeoKeyUserDefined, kGeoKeyUserDefined, std::nullopt, 9001},
      {"liblas/certainty3d-color-utm-feet-navd88.las", 2229, std::nullopt, std::nullopt,
       std::nullopt},
      {"pdal/mvk-thin.las", 26995, 4269, std::nullopt, 9003},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.file);
    if (!fs::exists(data_dir() / c.file)) continue;
    auto opened = LasReader::open(data_dir() / c.file);
    ASSERT_TRUE(opened.ok()) << opened.error().message;
    const LasCrsRecords& crs = opened.value()->crs();
    EXPECT_TRUE(crs.has_geotiff);
    EXPECT_EQ(crs.projected_cs, c.projected);
    EXPECT_EQ(crs.geographic_cs, c.geographic);
    EXPECT_EQ(crs.vertical_cs, c.vertical);
    EXPECT_EQ(crs.projected_linear_units, c.linear_units);
  }
}

TEST(SharedLas, GeoTiffKeysResolveDoublesAndAscii) {
  OPEN_LAS(las, "pdal/interesting.las");
  const LasCrsRecords& crs = las.crs();
  EXPECT_EQ(crs.keys.size(), 21u);
  EXPECT_EQ(crs.geotiff_version, (std::array<std::uint16_t, 3>{1, 1, 0}));
  const GeoKey* standard_parallel = crs.find(3078);
  ASSERT_NE(standard_parallel, nullptr);
  EXPECT_EQ(standard_parallel->location, 34736);
  EXPECT_EQ(standard_parallel->doubles, std::vector<double>{43.0});
  const GeoKey* citation = crs.find(kGeoKeyCitation);
  ASSERT_NE(citation, nullptr);
  EXPECT_EQ(citation->ascii, "NAD_1983_Oregon_Statewide_Lambert_Feet_Intl");
  EXPECT_EQ(crs.find(kGeoKeyProjCoordTrans)->short_value(), 8);  // Lambert conformal conic 2SP
  EXPECT_TRUE(crs.warnings.empty());
  ASSERT_TRUE(crs.liblas_wkt.has_value());
  EXPECT_THAT(*crs.liblas_wkt, HasSubstr("PROJCS"));
  EXPECT_FALSE(crs.wkt.has_value());
}

TEST(SharedLas, BadGeoTiffKeysGiveAWarningNotACrash) {
  OPEN_LAS(las, "pdal/bad-geotiff-keys.las");
  EXPECT_EQ(las.crs().keys.size(), 4u);
  EXPECT_EQ(las.crs().projected_cs, 32617);
  EXPECT_TRUE(has_warning(las, "key id 0"));
  EXPECT_EQ(read_all(las).count, 10u);
}

TEST(SharedLas, WktFromVlrFromEvlrAndEmpty) {
  SKIP_WITHOUT_DATA();
  for (const char* file : {"pdal/test1_4.las", "pdal/wontcompress3.las"}) {
    SCOPED_TRACE(file);
    auto opened = LasReader::open(data_dir() / file);
    ASSERT_TRUE(opened.ok()) << opened.error().message;
    const auto& crs = opened.value()->crs();
    ASSERT_TRUE(crs.wkt.has_value());
    EXPECT_THAT(*crs.wkt, HasSubstr("PROJCS"));
    EXPECT_FALSE(crs.wkt_from_evlr);
    EXPECT_TRUE(crs.wkt_flag);
  }
  {
    auto opened = LasReader::open(data_dir() / "laspy/simple1_4.las");
    ASSERT_TRUE(opened.ok()) << opened.error().message;
    const auto& crs = opened.value()->crs();
    ASSERT_TRUE(crs.wkt.has_value());
    EXPECT_TRUE(crs.wkt_from_evlr);
    EXPECT_THAT(*crs.wkt, HasSubstr("GEOGCS"));
    EXPECT_EQ(crs.geographic_cs, 4326);
    ASSERT_EQ(opened.value()->evlrs().size(), 1u);
    EXPECT_EQ(opened.value()->evlrs()[0].record_id, 2112);
  }
  for (const char* file : {"pdal/warsaw_small.las", "laszip/5points_14.las"}) {
    SCOPED_TRACE(file);
    auto opened = LasReader::open(data_dir() / file);
    ASSERT_TRUE(opened.ok()) << opened.error().message;
    EXPECT_TRUE(opened.value()->crs().wkt.has_value());
    EXPECT_TRUE(has_warning(*opened.value(), "WKT record (LASF_Projection 2112) is empty"));
  }
}

TEST(SharedLas, NoCrsRecordsInTheAhnFiles) {
  OPEN_LAS(las, "3dfier/ahn3_cropped_2.las");
  EXPECT_TRUE(las.crs().empty());
  EXPECT_EQ(las.header().point_count, 208432u);
  EXPECT_TRUE(las.vlrs().empty());
}

// The records interpreted (las_file_crs): EPSG codes and descriptions of what each file
// declares, and clear errors where it declares nothing usable.
TEST(SharedLas, CrsRecordsResolveToTheirCrs) {
  SKIP_WITHOUT_DATA();
  struct Case {
    const char* file;
    int epsg;              // 0: user-defined
    const char* contains;  // in describe_crs
    int vertical;
  };
  const Case cases[] = {
      {"las-rs/32-1-472-150-76.las", 25832, "UTM zone 32N", 5941},
      {"liblas/srs_vertcs.las", 32617, "UTM zone 17N", 5703},
      {"pdal/permutations_1.2_0.las", 26915, "NAD83 / UTM zone 15N", 0},
      {"pdal/autzen-utm.las", 26910, "UTM zone 10N", 0},
      {"pdal/epsg_4326.las", 4326, "geographic", 0},
      {"pdal/autzen-dd.las", 4326, "geographic", 0},
      // ESRI's name for EPSG:2992; PROJ identifies it (same parameters, other names).
      {"pdal/interesting.las", 2992, "Lambert Conic Conformal (2SP), foot", 0},
      {"laspy/plane.las", 0, "Lambert Conic Conformal (2SP), metre", 0},
      {"liblas/certainty3d-color-utm-feet-navd88.las", 2229, "US survey foot", 0},
      // Its VERTCS nested inside the PROJCS is no WKT PROJ reads: no vertical CRS.
      {"pdal/test1_4.las", 2903, "New Mexico Central (ftUS)", 0},
      {"pdal/wontcompress3.las", 26919, "UTM zone 19N", 0},
      {"pdal/crop-on-edge_crop.las", 2154, "Lambert-93", 0},
      {"pnext/v4d0.las", 6676, "Japan Plane Rectangular CS VIII", 0},
      {"pnext/v1d0.las", 6676, "Japan Plane Rectangular CS VIII", 0},
      {"lazperf/1815.las", 6580, "Texas Centric", 5703},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.file);
    if (!fs::exists(data_dir() / c.file)) continue;
    auto opened = LasReader::open(data_dir() / c.file);
    ASSERT_TRUE(opened.ok()) << opened.error().message;
    auto crs = las_file_crs(opened.value()->crs());
    ASSERT_TRUE(crs.ok()) << crs.error().message;
    EXPECT_EQ(crs.value().epsg, c.epsg);
    EXPECT_THAT(describe_crs(crs.value()), HasSubstr(c.contains));
    EXPECT_EQ(crs.value().vertical ? crs.value().vertical->epsg : 0, c.vertical);
  }
}

TEST(SharedLas, FilesWithoutACrsTakeTheConfiguredOne) {
  OPEN_LAS(las, "3dfier/ahn3_cropped_2.las");
  auto none = las_file_crs(las.crs());
  ASSERT_FALSE(none.ok());
  EXPECT_THAT(none.error().message, HasSubstr("no CRS"));
  auto rd = las_file_crs(las.crs(), "EPSG:28992+5709");
  ASSERT_TRUE(rd.ok()) << rd.error().message;
  EXPECT_EQ(rd.value().epsg, 28992);
  EXPECT_EQ(rd.value().vertical->epsg, 5709);
}

TEST(SharedLas, ConfiguredCrsThatDisagreesWithTheFileIsAWarningOrAnOverride) {
  OPEN_LAS(las, "pdal/autzen-utm.las");
  auto file_wins = las_file_crs(las.crs(), "EPSG:28992");
  ASSERT_TRUE(file_wins.ok());
  EXPECT_EQ(file_wins.value().epsg, 26910);
  ASSERT_FALSE(file_wins.value().warnings.empty());
  EXPECT_THAT(file_wins.value().warnings.back(), HasSubstr("config"));
  auto config_wins = las_file_crs(las.crs(), "EPSG:28992", /*config_overrides_file=*/true);
  ASSERT_TRUE(config_wins.ok());
  EXPECT_EQ(config_wins.value().epsg, 28992);
}

TEST(SharedLas, EmptyOrUndefinedCrsRecordsAreNamedErrors) {
  {
    OPEN_LAS(las, "pdal/warsaw_small.las");
    auto crs = las_file_crs(las.crs());
    ASSERT_FALSE(crs.ok());
    EXPECT_THAT(crs.error().message, HasSubstr("WKT"));
  }
  {
    OPEN_LAS(las, "pdal/1.2-empty-geotiff-vlrs.las");
    auto crs = las_file_crs(las.crs());
    ASSERT_FALSE(crs.ok());
    EXPECT_THAT(crs.error().message, HasSubstr("GeoTIFF keys define no CRS"));
  }
}

TEST(SharedLas, EvlrAndManyVlrsAreListed) {
  {
    OPEN_LAS(las, "laspy/1_4_w_evlr.las");
    ASSERT_EQ(las.evlrs().size(), 1u);
    EXPECT_EQ(las.evlrs()[0].user_id, "pylastest");
    EXPECT_EQ(las.evlrs()[0].record_id, 42);
    EXPECT_EQ(las.evlrs()[0].length, 16u);
    EXPECT_EQ(las.evlrs()[0].description, "just a test evlr");
    EXPECT_EQ(las.evlrs()[0].data->size(), 16u);
    EXPECT_EQ(read_all(las).count, 1000u);
  }
  {
    OPEN_LAS(las, "pdal/lots_of_vlr.las");
    EXPECT_EQ(las.vlrs().size(), 390u);
    EXPECT_EQ(las.vlrs().front().user_id, "Merrick");
  }
}

TEST(SharedLas, NanGpsTimeIsAWarning) {
  OPEN_LAS(las, "pdal/gps-time-nan.las");
  EXPECT_EQ(read_all(las).count, 1u);
  EXPECT_TRUE(has_warning(las, "GPS time that is NaN"));
}

TEST(SharedLas, SeekRereadsTheSamePoints) {
  OPEN_LAS(las, "pdal/autzen_trim.las");
  PointBatch first, again;
  ASSERT_TRUE(las.seek(500).ok());
  ASSERT_TRUE(las.read(first, 10).ok());
  ASSERT_TRUE(las.seek(500).ok());
  ASSERT_TRUE(las.read(again, 10).ok());
  ASSERT_EQ(first.size(), 10u);
  for (std::size_t i = 0; i < 10; ++i)
    EXPECT_EQ(first.points[i].gps_time, again.points[i].gps_time);
  EXPECT_FALSE(las.seek(las.readable_points() + 1).ok());
}

TEST(SharedLas, ReadsTheSameInAnyBatchSize) {
  OPEN_LAS(las, "pdal/autzen_trim_7.las");
  auto other = LasReader::open(data_dir() / "pdal/autzen_trim_7.las");
  ASSERT_TRUE(other.ok());
  PointBatch a, b;
  std::vector<Point> all_a, all_b;
  while (las.read(a, 7919).value() > 0) all_a.insert(all_a.end(), a.points.begin(), a.points.end());
  while (other.value()->read(b, 1).value() > 0 && all_b.size() < 30000) {
    all_b.insert(all_b.end(), b.points.begin(), b.points.end());
  }
  ASSERT_EQ(all_a.size(), 110000u);
  for (std::size_t i = 0; i < all_b.size(); ++i) {
    ASSERT_EQ(all_a[i].x, all_b[i].x);
    ASSERT_EQ(all_a[i].gps_time, all_b[i].gps_time);
  }
}

TEST(SharedPcd, FloatUtmCoordinatesWarnOfTheirHalfMetreSteps) {
  SKIP_WITHOUT_DATA();
  auto opened = open_point_file(data_dir() / "pcl/CSite3_orig-utm.pcd");
  ASSERT_TRUE(opened.ok()) << opened.error().message;
  EXPECT_EQ(read_all(*opened.value()).count, 377028u);
  EXPECT_TRUE(has_warning(*opened.value(), "precision trap"));
  EXPECT_TRUE(has_warning(*opened.value(), "steps of 0.5"));
  const Bounds3& b = opened.value()->bounds_read();
  EXPECT_DOUBLE_EQ(b.min[0], 512022.46875);
  EXPECT_DOUBLE_EQ(b.max[1], 5403502.5);
}

TEST(SharedPcd, OrganisedCloudDropsItsNanHolesAndUnpacksRgba) {
  SKIP_WITHOUT_DATA();
  auto opened = open_point_file(data_dir() / "pcl/table_scene_mug_stereo_textured.pcd");
  ASSERT_TRUE(opened.ok()) << opened.error().message;
  PointReader& reader = *opened.value();
  EXPECT_EQ(reader.info().point_count, 307200u);
  EXPECT_TRUE(reader.info().fields.color);
  PointBatch batch;
  ASSERT_TRUE(reader.read(batch, 1).ok());
  // The first finite point is record 6538: (-0.38191, -0.4482, 2.0258), rgba 0xff43433e.
  EXPECT_FLOAT_EQ(static_cast<float>(batch.points[0].x), -0.3819099962711334F);
  EXPECT_EQ(batch.points[0].red, 0x43 * 257);
  EXPECT_EQ(batch.points[0].green, 0x43 * 257);
  EXPECT_EQ(batch.points[0].blue, 0x3e * 257);
  EXPECT_EQ(read_all(reader).count + 1, 209280u);
  EXPECT_TRUE(has_warning(reader, "97920 points with NaN"));
  EXPECT_FALSE(has_warning(reader, "precision trap"));  // small coordinates
}

TEST(SharedPcd, AsciiNormalsAndCurvature) {
  SKIP_WITHOUT_DATA();
  auto opened = open_point_file(data_dir() / "pcl/sac_plane_test.pcd");
  ASSERT_TRUE(opened.ok()) << opened.error().message;
  PointReader& reader = *opened.value();
  EXPECT_TRUE(reader.info().fields.normals);
  ASSERT_NE(reader.info().extra, nullptr);
  ASSERT_EQ(reader.info().extra->dimensions.size(), 1u);
  EXPECT_EQ(reader.info().extra->dimensions[0].name, "curvature");
  PointBatch batch;
  ASSERT_TRUE(reader.read(batch, 2).ok());
  EXPECT_DOUBLE_EQ(batch.points[0].x, static_cast<double>(1.068F));
  EXPECT_FLOAT_EQ(batch.points[0].normal[0], -0.33680952F);
  EXPECT_NEAR(batch.extra_value(0, "curvature").value(), 0.021525998, 1e-8);
}

}  // namespace
}  // namespace csgtile::geo
