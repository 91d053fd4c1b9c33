// PLY, PCD and XYZ text through the common PointReader interface: round trips through small
// writers of this file (every PLY encoding, every PCD DATA kind including LZF compression),
// LZF decoding on its own, format detection, and malformed inputs.

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "csgtile/geo/point_reader.h"
#include "test_support.h"

namespace csgtile::geo {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using Bytes = std::vector<std::uint8_t>;

// Temporary directory of this suite, with a helper that writes a file into it.
struct TempDir : test::TempDir {
  TempDir() : test::TempDir("csgtile_geo_formats_") {}
  fs::path write(const std::string& name, const std::string& content) const {
    std::ofstream(*this / name, std::ios::binary) << content;
    return *this / name;
  }
};

template <class T>
void append_value(std::string& out, T value, bool big_endian = false) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  if (big_endian) std::reverse(bytes, bytes + sizeof(T));
  out.append(bytes, sizeof(T));
}

struct Sample {
  double x, y, z;
  float nx, ny, nz;
  std::uint8_t r, g, b;
  float quality;
};

std::vector<Sample> samples(std::size_t count, double base = 0.0) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> coord(-100.0, 100.0);
  std::uniform_int_distribution<int> byte(0, 255);
  std::vector<Sample> out;
  for (std::size_t i = 0; i < count; ++i) {
    Sample s{};
    // Values exact in float32 so that every encoding gives the same numbers.
    s.x = static_cast<float>(coord(random) + base);
    s.y = static_cast<float>(coord(random));
    s.z = static_cast<float>(coord(random));
    s.nx = 0.0F;
    s.ny = 0.6F;
    s.nz = 0.8F;
    s.r = static_cast<std::uint8_t>(byte(random));
    s.g = static_cast<std::uint8_t>(byte(random));
    s.b = static_cast<std::uint8_t>(byte(random));
    s.quality = static_cast<float>(i) * 0.5F;
    out.push_back(s);
  }
  return out;
}

std::string format_float(double v) {
  std::ostringstream out;
  out.precision(17);
  out << v;
  return out.str();
}

// ---- PLY ----------------------------------------------------------------------------------

enum class PlyKind { Ascii, Little, Big };

// A PLY with an element before the vertices (with a list: it must be skipped record by
// record) and faces after them.
std::string write_ply(const std::vector<Sample>& points, PlyKind kind, bool doubles) {
  const char* encoding = kind == PlyKind::Ascii    ? "ascii"
                         : kind == PlyKind::Little ? "binary_little_endian"
                                                   : "binary_big_endian";
  const char* coord = doubles ? "double" : "float";
  std::string out = std::string("ply\nformat ") + encoding + " 1.0\ncomment csgtile test\n" +
                    "element camera 2\nproperty list uchar float position\nproperty int id\n" +
                    "element vertex " + std::to_string(points.size()) + "\n" + "property " + coord +
                    " x\nproperty " + coord + " y\nproperty " + coord +
                    " z\nproperty float nx\nproperty float ny\nproperty float nz\n" +
                    "property uchar red\nproperty uchar green\nproperty uchar blue\n" +
                    "property float quality\nelement face 1\n" +
                    "property list uchar int vertex_indices\nend_header\n";
  const bool big = kind == PlyKind::Big;
  if (kind == PlyKind::Ascii) {
    out += "3 1 2 3 7\n0 8\n";
    for (const auto& s : points) {
      out += format_float(s.x) + " " + format_float(s.y) + " " + format_float(s.z) + " " +
             format_float(s.nx) + " " + format_float(s.ny) + " " + format_float(s.nz) + " " +
             std::to_string(s.r) + " " + std::to_string(s.g) + " " + std::to_string(s.b) + " " +
             format_float(s.quality) + "\n";
    }
    out += "3 0 1 2\n";
    return out;
  }
  for (int camera = 0; camera < 2; ++camera) {
    const std::uint8_t n = camera == 0 ? 3 : 0;
    append_value(out, n, big);
    for (int k = 0; k < n; ++k) append_value(out, 1.5F, big);
    append_value(out, std::int32_t{7 + camera}, big);
  }
  for (const auto& s : points) {
    if (doubles) {
      append_value(out, s.x, big);
      append_value(out, s.y, big);
      append_value(out, s.z, big);
    } else {
      append_value(out, static_cast<float>(s.x), big);
      append_value(out, static_cast<float>(s.y), big);
      append_value(out, static_cast<float>(s.z), big);
    }
    append_value(out, s.nx, big);
    append_value(out, s.ny, big);
    append_value(out, s.nz, big);
    append_value(out, s.r, big);
    append_value(out, s.g, big);
    append_value(out, s.b, big);
    append_value(out, s.quality, big);
  }
  append_value(out, std::uint8_t{3}, big);
  for (int k = 0; k < 3; ++k) append_value(out, std::int32_t{k}, big);
  return out;
}

struct Collected {
  std::vector<Point> points;
  PointBatch last;  // layout holder
  std::vector<std::uint8_t> extra;
  std::optional<kernel::Error> error;
};

Collected collect(PointReader& reader, std::size_t batch_size = 100) {
  Collected out;
  PointBatch batch;
  for (;;) {
    auto n = reader.read(batch, batch_size);
    if (!n.ok()) {
      out.error = n.error();
      return out;
    }
    if (n.value() == 0) break;
    out.points.insert(out.points.end(), batch.points.begin(), batch.points.end());
    out.extra.insert(out.extra.end(), batch.extra_bytes.begin(), batch.extra_bytes.end());
  }
  out.last = batch;
  return out;
}

void expect_samples(const Collected& got, const std::vector<Sample>& want, bool colors = true) {
  ASSERT_FALSE(got.error) << got.error->message;
  ASSERT_EQ(got.points.size(), want.size());
  for (std::size_t i = 0; i < want.size(); ++i) {
    SCOPED_TRACE("point " + std::to_string(i));
    EXPECT_EQ(got.points[i].x, want[i].x);
    EXPECT_EQ(got.points[i].y, want[i].y);
    EXPECT_EQ(got.points[i].z, want[i].z);
    EXPECT_EQ(got.points[i].normal[1], want[i].ny);
    EXPECT_EQ(got.points[i].normal[2], want[i].nz);
    if (colors) {
      EXPECT_EQ(got.points[i].red, want[i].r * 257);
      EXPECT_EQ(got.points[i].green, want[i].g * 257);
      EXPECT_EQ(got.points[i].blue, want[i].b * 257);
    }
    if (::testing::Test::HasFailure()) return;
  }
}

class PlyRoundTrip : public ::testing::TestWithParam<std::tuple<PlyKind, bool>> {};

TEST_P(PlyRoundTrip, VerticesNormalsColoursAndExtraProperties) {
  const auto [kind, doubles] = GetParam();
  const auto points = samples(257);
  TempDir dir;
  const auto path = dir.write("cloud.ply", write_ply(points, kind, doubles));
  auto reader = open_point_file(path);
  ASSERT_TRUE(reader.ok()) << reader.error().message;
  EXPECT_EQ(reader.value()->info().format, PointFileFormat::Ply);
  EXPECT_EQ(reader.value()->info().point_count, 257u);
  EXPECT_TRUE(reader.value()->info().fields.normals);
  EXPECT_TRUE(reader.value()->info().fields.color);
  ASSERT_NE(reader.value()->info().extra, nullptr);
  const ExtraDimension* quality = reader.value()->info().extra->find("quality");
  ASSERT_NE(quality, nullptr);
  EXPECT_EQ(quality->type, ExtraType::F32);
  const Collected got = collect(*reader.value(), 100);
  expect_samples(got, points);
  for (std::size_t i = 0; i < points.size(); ++i) {
    ASSERT_EQ(decode_extra_scaled(*quality, std::span(got.extra).subspan(4 * i, 4)),
              points[i].quality);
  }
  EXPECT_TRUE(reader.value()->warnings().empty());
}

INSTANTIATE_TEST_SUITE_P(EveryEncoding, PlyRoundTrip,
                         ::testing::Combine(::testing::Values(PlyKind::Ascii, PlyKind::Little,
                                                              PlyKind::Big),
                                            ::testing::Bool()),
                         [](const auto& param_info) {
                           const PlyKind kind = std::get<0>(param_info.param);
                           return std::string(kind == PlyKind::Ascii    ? "ascii"
                                              : kind == PlyKind::Little ? "little"
                                                                        : "big") +
                                  (std::get<1>(param_info.param) ? "_double" : "_float");
                         });

TEST(PlyReader, Float32UtmCoordinatesWarnOfThePrecisionTrap) {
  TempDir dir;
  const auto path = dir.write("utm.ply", write_ply(samples(10, 5400000.0), PlyKind::Little, false));
  auto reader = open_point_file(path);
  ASSERT_TRUE(reader.ok()) << reader.error().message;
  ASSERT_FALSE(collect(*reader.value()).error);
  ASSERT_EQ(reader.value()->warnings().size(), 1u);
  EXPECT_THAT(reader.value()->warnings()[0], HasSubstr("steps of 0.5"));
  // The same coordinates in doubles are fine.
  const auto exact =
      dir.write("utm64.ply", write_ply(samples(10, 5400000.0), PlyKind::Little, true));
  reader = open_point_file(exact);
  ASSERT_TRUE(reader.ok());
  ASSERT_FALSE(collect(*reader.value()).error);
  EXPECT_TRUE(reader.value()->warnings().empty());
}

TEST(PlyReader, TruncatedBinaryVerticesFailOrReadTheCompleteOnes) {
  TempDir dir;
  std::string ply = write_ply(samples(20), PlyKind::Little, false);
  ply.resize(ply.size() - 13 - 40 - 5);  // the face, the last vertex and part of another
  const auto path = dir.write("short.ply", ply);
  auto reader = open_point_file(path);
  ASSERT_FALSE(reader.ok());
  EXPECT_THAT(reader.error().message, HasSubstr("truncated: the header declares 20 vertices"));
  PointReadOptions lenient;
  lenient.accept_truncated = true;
  reader = open_point_file(path, lenient);
  ASSERT_TRUE(reader.ok()) << reader.error().message;
  EXPECT_EQ(collect(*reader.value()).points.size(), 18u);
}

TEST(PlyReader, MalformedHeadersAreNamed) {
  TempDir dir;
  // The error of opening `text`, or else of reading all its points.
  auto error_of = [&](const std::string& text) -> std::string {
    auto reader = open_point_file(dir.write("bad.ply", text));
    if (!reader.ok()) return reader.error().message;
    const Collected got = collect(*reader.value());
    return got.error ? got.error->message : "accepted";
  };
  EXPECT_THAT(
      error_of("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n1\n"),
      HasSubstr("lacks x, y or z"));
  EXPECT_THAT(error_of("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"),
              HasSubstr("ends before \"end_header\""));
  EXPECT_THAT(error_of("ply\nformat zip 1.0\nend_header\n"), HasSubstr("unknown format \"zip\""));
  EXPECT_THAT(error_of("ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n"),
              HasSubstr("unknown property type \"quad\""));
  EXPECT_THAT(error_of("ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty "
                       "float y\nproperty float z\nend_header\n1 2 3\n1 2\n"),
              HasSubstr("vertex 1 (line 9) has 2 values"));
  // A face element declaring far more records than the file holds, before the vertices.
  std::string lie =
      "ply\nformat binary_little_endian 1.0\nelement face 4000000000\n"
      "property list uchar int vertex_indices\nelement vertex 1\nproperty float x\n"
      "property float y\nproperty float z\nend_header\n";
  lie += std::string("\x01\x00\x00\x00\x00", 5);
  EXPECT_THAT(error_of(lie), HasSubstr("element \"face\" declares 4000000000 records"));
}

// ---- LZF ----------------------------------------------------------------------------------

// A small LZF compressor for the tests: greedy matches found through a hash of 3 bytes.
Bytes lzf_compress(const Bytes& in) {
  Bytes out;
  std::vector<std::size_t> table(1 << 14, SIZE_MAX);
  std::size_t literal_start = 0;
  auto flush_literals = [&](std::size_t end) {
    while (literal_start < end) {
      const std::size_t n = std::min<std::size_t>(32, end - literal_start);
      out.push_back(static_cast<std::uint8_t>(n - 1));
      out.insert(out.end(), in.begin() + static_cast<std::ptrdiff_t>(literal_start),
                 in.begin() + static_cast<std::ptrdiff_t>(literal_start + n));
      literal_start += n;
    }
  };
  std::size_t i = 0;
  while (i + 2 < in.size()) {
    const std::size_t h = ((in[i] << 16 | in[i + 1] << 8 | in[i + 2]) * 2654435761u >> 18) & 0x3FFF;
    const std::size_t candidate = table[h];
    table[h] = i;
    if (candidate != SIZE_MAX && i - candidate <= 8192 && in[candidate] == in[i] &&
        in[candidate + 1] == in[i + 1] && in[candidate + 2] == in[i + 2]) {
      std::size_t length = 3;
      while (i + length < in.size() && length < 264 && in[candidate + length] == in[i + length]) {
        ++length;
      }
      flush_literals(i);
      const std::size_t distance = i - candidate - 1;
      const std::size_t code = length - 2;
      if (code < 7) {
        out.push_back(static_cast<std::uint8_t>((code << 5) | (distance >> 8)));
      } else {
        out.push_back(static_cast<std::uint8_t>((7 << 5) | (distance >> 8)));
        out.push_back(static_cast<std::uint8_t>(code - 7));
      }
      out.push_back(static_cast<std::uint8_t>(distance & 0xFF));
      i += length;
      literal_start = i;
      continue;
    }
    ++i;
  }
  flush_literals(in.size());
  return out;
}

// A binary_compressed PCD of x y z (float32) and one uint8 field "v" around an LZF stream.
std::string compressed_pcd(std::size_t points, const Bytes& stream, std::size_t uncompressed,
                           bool with_v = true) {
  std::string out = std::string("VERSION 0.7\nFIELDS x y z") + (with_v ? " v" : "") +
                    "\nSIZE 4 4 4" + (with_v ? " 1" : "") + "\nTYPE F F F" + (with_v ? " U" : "") +
                    "\nWIDTH " + std::to_string(points) + "\nDATA binary_compressed\n";
  append_value(out, static_cast<std::uint32_t>(stream.size()));
  append_value(out, static_cast<std::uint32_t>(uncompressed));
  out.append(stream.begin(), stream.end());
  return out;
}

TEST(PcdLzf, RunsRepeatsAndNoiseDecodeExactly) {
  constexpr std::size_t kPoints = 4000;
  std::mt19937 random(3);
  Bytes fields;                                // field-major: x, y, z, v
  for (std::size_t i = 0; i < kPoints; ++i) {  // x: a long run of one value
    const float x = 1.25F;
    fields.insert(fields.end(), reinterpret_cast<const std::uint8_t*>(&x),
                  reinterpret_cast<const std::uint8_t*>(&x) + 4);
  }
  for (std::size_t i = 0; i < kPoints; ++i) {  // y: short repeats
    const float y = static_cast<float>(random() % 4);
    fields.insert(fields.end(), reinterpret_cast<const std::uint8_t*>(&y),
                  reinterpret_cast<const std::uint8_t*>(&y) + 4);
  }
  for (std::size_t i = 0; i < kPoints; ++i) {  // z: noise
    const float z = static_cast<float>(random() % 100000) * 0.01F;
    fields.insert(fields.end(), reinterpret_cast<const std::uint8_t*>(&z),
                  reinterpret_cast<const std::uint8_t*>(&z) + 4);
  }
  for (std::size_t i = 0; i < kPoints; ++i) fields.push_back(static_cast<std::uint8_t>(i % 251));
  const Bytes stream = lzf_compress(fields);
  EXPECT_LT(stream.size(), fields.size());
  TempDir dir;
  auto reader =
      open_point_file(dir.write("lzf.pcd", compressed_pcd(kPoints, stream, fields.size())));
  ASSERT_TRUE(reader.ok()) << reader.error().message;
  const Collected got = collect(*reader.value(), 999);
  ASSERT_FALSE(got.error) << got.error->message;
  ASSERT_EQ(got.points.size(), kPoints);
  for (std::size_t i = 0; i < kPoints; ++i) {
    float y, z;
    std::memcpy(&y, &fields[4 * (kPoints + i)], 4);
    std::memcpy(&z, &fields[4 * (2 * kPoints + i)], 4);
    ASSERT_EQ(got.points[i].x, 1.25) << i;
    ASSERT_EQ(got.points[i].y, y) << i;
    ASSERT_EQ(got.points[i].z, z) << i;
    ASSERT_EQ(got.extra[i], i % 251) << i;
  }
}

TEST(PcdLzf, OverlappingBackReferenceRepeatsAPattern) {
  // Literal 00 00 80 3F (1.0f), then 8 bytes copied from 4 back: x = y = z = 1.
  const Bytes stream{3, 0x00, 0x00, 0x80, 0x3F, 0xC0, 0x03};
  TempDir dir;
  auto reader = open_point_file(dir.write("overlap.pcd", compressed_pcd(1, stream, 12, false)));
  ASSERT_TRUE(reader.ok()) << reader.error().message;
  const Collected got = collect(*reader.value());
  ASSERT_EQ(got.points.size(), 1u);
  EXPECT_EQ(got.points[0].x, 1.0);
  EXPECT_EQ(got.points[0].y, 1.0);
  EXPECT_EQ(got.points[0].z, 1.0);
}

TEST(PcdLzf, MalformedStreamsAreRefusedWithoutOverrun) {
  TempDir dir;
  auto error_of = [&](const Bytes& stream) {
    auto reader = open_point_file(dir.write("bad.pcd", compressed_pcd(1, stream, 12, false)));
    return reader.ok() ? std::string("accepted") : reader.error().message;
  };
  EXPECT_THAT(error_of({4, 1, 2}), HasSubstr("literal run of 5 bytes at input byte 0 passes the "
                                             "end of the compressed data"));
  EXPECT_THAT(error_of({0, 'a', 0x20, 5}), HasSubstr("points before the start of the data"));
  Bytes long_literal(33, 7);  // a literal run of 32 bytes into a 12-byte output
  long_literal[0] = 31;
  EXPECT_THAT(error_of(long_literal), HasSubstr("exceeds the declared size 12"));
  EXPECT_THAT(error_of({1, 'a', 'b', 0x80, 1}),
              HasSubstr("decodes to 8 bytes, the header says 12"));
  EXPECT_THAT(error_of({0, 'a', 0xE0}), HasSubstr("back reference truncated"));
}

// ---- PCD ----------------------------------------------------------------------------------

enum class PcdKind { Ascii, Binary, Compressed };

std::uint32_t packed_rgb(const Sample& s) {
  return (std::uint32_t{s.r} << 16) | (std::uint32_t{s.g} << 8) | s.b;
}

// FIELDS x y z rgb normal_x normal_y normal_z label hist(3) _ (padding).
std::string write_pcd(const std::vector<Sample>& points, PcdKind kind) {
  const char* data = kind == PcdKind::Ascii    ? "ascii"
                     : kind == PcdKind::Binary ? "binary"
                                               : "binary_compressed";
  std::string out =
      "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\n"
      "FIELDS x y z rgb normal_x normal_y normal_z label hist _\n"
      "SIZE 4 4 4 4 4 4 4 4 2 1\nTYPE F F F F F F F U I U\n"
      "COUNT 1 1 1 1 1 1 1 1 3 4\n" +
      std::string("WIDTH ") + std::to_string(points.size()) +
      "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " + std::to_string(points.size()) + "\nDATA " +
      data + "\n";
  auto rgb_float = [](const Sample& s) { return std::bit_cast<float>(packed_rgb(s)); };
  if (kind == PcdKind::Ascii) {
    for (std::size_t i = 0; i < points.size(); ++i) {
      const Sample& s = points[i];
      out += format_float(s.x) + " " + format_float(s.y) + " " + format_float(s.z) + " " +
             format_float(rgb_float(s)) + " " + format_float(s.nx) + " " + format_float(s.ny) +
             " " + format_float(s.nz) + " " + std::to_string(i) + " -1 0 " +
             std::to_string(i % 100) + " 0 0 0 0\n";
    }
    return out;
  }
  // One record per point...
  auto record = [&](std::string& r, std::size_t i) {
    const Sample& s = points[i];
    append_value(r, static_cast<float>(s.x));
    append_value(r, static_cast<float>(s.y));
    append_value(r, static_cast<float>(s.z));
    append_value(r, rgb_float(s));
    append_value(r, s.nx);
    append_value(r, s.ny);
    append_value(r, s.nz);
    append_value(r, static_cast<std::uint32_t>(i));
    append_value(r, std::int16_t{-1});
    append_value(r, std::int16_t{0});
    append_value(r, static_cast<std::int16_t>(i % 100));
    r.append(4, '\0');
  };
  if (kind == PcdKind::Binary) {
    for (std::size_t i = 0; i < points.size(); ++i) record(out, i);
    return out;
  }
  // ...or, compressed, field by field.
  const std::size_t widths[] = {4, 4, 4, 4, 4, 4, 4, 4, 6, 4};
  std::string records;
  for (std::size_t i = 0; i < points.size(); ++i) record(records, i);
  std::string by_field;
  std::size_t offset = 0;
  for (std::size_t w : widths) {
    for (std::size_t i = 0; i < points.size(); ++i) by_field.append(records, i * 42 + offset, w);
    offset += w;
  }
  const Bytes packed = lzf_compress(Bytes(by_field.begin(), by_field.end()));
  append_value(out, static_cast<std::uint32_t>(packed.size()));
  append_value(out, static_cast<std::uint32_t>(by_field.size()));
  out.append(packed.begin(), packed.end());
  return out;
}

class PcdRoundTrip : public ::testing::TestWithParam<PcdKind> {};

TEST_P(PcdRoundTrip, FieldsPackedColourCountsAndPadding) {
  const auto points = samples(300);
  TempDir dir;
  const auto path = dir.write("cloud.pcd", write_pcd(points, GetParam()));
  auto reader = open_point_file(path);
  ASSERT_TRUE(reader.ok()) << reader.error().message;
  const PointCloudInfo& info = reader.value()->info();
  EXPECT_EQ(info.format, PointFileFormat::Pcd);
  EXPECT_EQ(info.point_count, 300u);
  EXPECT_TRUE(info.fields.color);
  EXPECT_TRUE(info.fields.normals);
  ASSERT_NE(info.extra, nullptr);
  EXPECT_EQ(info.extra->record_size, 10u);  // label (4) + hist (3 × 2); padding dropped
  ASSERT_EQ(info.extra->dimensions.size(), 2u);
  EXPECT_EQ(info.extra->dimensions[1].name, "hist");
  EXPECT_EQ(info.extra->dimensions[1].elements, 3);
  EXPECT_EQ(info.extra->dimensions[1].type, ExtraType::I16);
  const Collected got = collect(*reader.value(), 64);
  expect_samples(got, points);
  PointBatch batch;
  batch.layout = info.extra;
  batch.extra_bytes = got.extra;
  batch.points = got.points;
  for (std::size_t i = 0; i < points.size(); i += 37) {
    EXPECT_EQ(std::get<std::uint64_t>(batch.extra_raw(i, "label").value()), i);
    EXPECT_EQ(batch.extra_value(i, "hist", 0), -1.0);
    EXPECT_EQ(batch.extra_value(i, "hist", 2), static_cast<double>(i % 100));
  }
  EXPECT_TRUE(reader.value()->warnings().empty());
}

INSTANTIATE_TEST_SUITE_P(EveryDataKind, PcdRoundTrip,
                         ::testing::Values(PcdKind::Ascii, PcdKind::Binary, PcdKind::Compressed),
                         [](const auto& param_info) {
                           return std::string(param_info.param == PcdKind::Ascii    ? "ascii"
                                              : param_info.param == PcdKind::Binary ? "binary"
                                                                                    : "compressed");
                         });

TEST(PcdReader, HeaderLiesAreNamedBeforeAllocation) {
  TempDir dir;
  auto error_of = [&](const std::string& text) -> std::string {
    auto reader = open_point_file(dir.write("bad.pcd", text));
    if (!reader.ok()) return reader.error().message;
    const Collected got = collect(*reader.value());
    return got.error ? got.error->message : "accepted";
  };
  const std::string head = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n";
  EXPECT_THAT(error_of(head + "WIDTH 10\nHEIGHT 1\nPOINTS 11\nDATA ascii\n"),
              HasSubstr("POINTS 11 disagrees with WIDTH × HEIGHT = 10 × 1 = 10"));
  EXPECT_THAT(error_of("VERSION 0.7\nFIELDS x y z\nSIZE 4 4\nTYPE F F F\nWIDTH 1\nDATA ascii\n"),
              HasSubstr("FIELDS has 3 entries but SIZE 2"));
  EXPECT_THAT(error_of("VERSION 0.7\nFIELDS x y z\nSIZE 4 4 3\nTYPE F F F\nWIDTH 1\nDATA ascii\n"),
              HasSubstr("TYPE F with SIZE 3"));
  EXPECT_THAT(error_of(head + "WIDTH 1\nDATA lzma\n"), HasSubstr("DATA \"lzma\" is not supported"));
  EXPECT_THAT(
      error_of(head + "WIDTH 100\nDATA binary\n" + std::string(12 * 99, '\0')),
      HasSubstr("truncated: the header declares 100 points of 12 bytes, the file holds 99"));
  // binary_compressed claiming 4 GB from 10 bytes.
  std::string lie = head + "WIDTH 357913941\nDATA binary_compressed\n";
  append_value(lie, std::uint32_t{10});
  append_value(lie, std::uint32_t{357913941u * 12u});
  lie.append(10, '\0');
  EXPECT_THAT(error_of(lie), HasSubstr("cannot come from 10 LZF-compressed bytes"));
  std::string wrong = head + "WIDTH 2\nDATA binary_compressed\n";
  append_value(wrong, std::uint32_t{10});
  append_value(wrong, std::uint32_t{25});
  wrong.append(10, '\0');
  EXPECT_THAT(error_of(wrong), HasSubstr("uncompressed size 25 is not POINTS × record size"));
  EXPECT_THAT(error_of(head + "WIDTH 2\nDATA ascii\n1 2 3\n1 2 x\n"),
              HasSubstr("line 9, field \"z\": \"x\" is not a number"));
}

// ---- XYZ ----------------------------------------------------------------------------------

TEST(XyzReader, PlainColumnsCommentsAndExtraColumns) {
  TempDir dir;
  const auto path = dir.write("cloud.xyz",
                              "# a comment\n\n1.5 2.5 3.5 10 # trailing comment\n"
                              "-1 -2 -3 20\r\n4e2\t5 6 30\n");
  auto reader = open_point_file(path);
  ASSERT_TRUE(reader.ok()) << reader.error().message;
  EXPECT_EQ(reader.value()->info().format, PointFileFormat::Xyz);
  EXPECT_FALSE(reader.value()->info().point_count.has_value());
  const Collected got = collect(*reader.value(), 2);
  ASSERT_FALSE(got.error) << got.error->message;
  ASSERT_EQ(got.points.size(), 3u);
  EXPECT_EQ(got.points[0].x, 1.5);
  EXPECT_EQ(got.points[1].z, -3.0);
  EXPECT_EQ(got.points[2].x, 400.0);
  ASSERT_NE(reader.value()->info().extra, nullptr);
  const ExtraDimension* column = reader.value()->info().extra->find("column_4");
  ASSERT_NE(column, nullptr);
  EXPECT_EQ(decode_extra_scaled(*column, std::span(got.extra).subspan(16, 8)), 30.0);
}

TEST(XyzReader, HeaderNamesFieldsAndCommasSeparate) {
  TempDir dir;
  const auto path = dir.write("cloud.csv", "X,Y,Z,Intensity,r,g,b,height\n1,2,3,100,255,0,1,7.5\n");
  auto reader = open_point_file(path);
  ASSERT_TRUE(reader.ok()) << reader.error().message;
  EXPECT_TRUE(reader.value()->info().fields.intensity);
  EXPECT_TRUE(reader.value()->info().fields.color);
  const Collected got = collect(*reader.value());
  ASSERT_EQ(got.points.size(), 1u);
  EXPECT_EQ(got.points[0].intensity, 100);
  EXPECT_EQ(got.points[0].red, 65535);
  EXPECT_EQ(got.points[0].blue, 257);
  EXPECT_EQ(decode_extra_scaled(*reader.value()->info().extra->find("height"), got.extra), 7.5);
}

TEST(XyzReader, InconsistentOrNonNumericLinesAreNamed) {
  TempDir dir;
  auto error_after_reading = [&](const std::string& text) -> std::string {
    auto reader = open_point_file(dir.write("bad.txt", text));
    if (!reader.ok()) return reader.error().message;
    const Collected got = collect(*reader.value());
    return got.error ? got.error->message : "accepted";
  };
  EXPECT_THAT(error_after_reading("1 2 3\n4 5\n"), HasSubstr("line 2 has 2 columns, expected 3"));
  EXPECT_THAT(error_after_reading("1 2 3\n4 5 six\n"), HasSubstr("line 2, column 3: \"six\""));
  EXPECT_THAT(error_after_reading("1 2\n"), HasSubstr("needs at least x y z"));
  EXPECT_THAT(error_after_reading("a b c\n1 2 3\n"), HasSubstr("names no x, y and z"));
}

// ---- detection ----------------------------------------------------------------------------

TEST(PointFormatDetection, MagicFirstThenExtension) {
  TempDir dir;
  EXPECT_EQ(detect_point_format(dir.write("a.bin", "ply\nformat ascii 1.0\n")).value(),
            PointFileFormat::Ply);
  EXPECT_EQ(detect_point_format(dir.write("b.dat", "# .PCD v0.7\nVERSION 0.7\n")).value(),
            PointFileFormat::Pcd);
  EXPECT_EQ(detect_point_format(dir.write("c.pts", "1 2 3\n")).value(), PointFileFormat::Xyz);
  EXPECT_EQ(detect_point_format(dir.write("d.txt", "LASF")).value(), PointFileFormat::Las);
  const auto unknown = detect_point_format(dir.write("e.bin", "\x01\x02\x03"));
  ASSERT_FALSE(unknown.ok());
  EXPECT_EQ(unknown.error().code, kernel::ErrorCode::Unsupported);
  const auto missing = detect_point_format("/nonexistent/cloud.las");
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.error().code, kernel::ErrorCode::IoError);
}

TEST(PointFormatDetection, MemoryReadersUseTheSameFormats) {
  const std::string text =
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty "
      "float y\nproperty float z\nend_header\n1 2 3\n";
  const Bytes bytes(text.begin(), text.end());
  auto reader = open_point_memory("memory.ply", bytes);
  ASSERT_TRUE(reader.ok()) << reader.error().message;
  const Collected got = collect(*reader.value());
  ASSERT_EQ(got.points.size(), 1u);
  EXPECT_EQ(got.points[0].z, 3.0);
}

}  // namespace
}  // namespace csgtile::geo
