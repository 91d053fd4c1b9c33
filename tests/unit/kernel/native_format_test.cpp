// Native model format: lossless round trips (write → read → write byte-identical, shapes
// structurally equal, sharing kept), determinism, hostile input (every truncation and
// byte flip of a small model, hand-made malformed files), versioning, atomic files, size.

#include "csgtile/kernel/native_format.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "csgtile/kernel/boolean.h"
#include "csgtile/kernel/check.h"
#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/primitives.h"
#include "csgtile/kernel/tessellation.h"

namespace csgtile::kernel {
namespace {

constexpr double kPi = std::numbers::pi;

Shape unwrap(Result<Shape> r) {
  EXPECT_TRUE(r.ok()) << (r.ok() ? "" : r.error().message);
  return r.ok() ? std::move(r).value() : Shape();
}

/// Random rotation about a random axis, scale in [0.5, 2], translation up to city scale.
Location random_similarity(std::mt19937_64& rng) {
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> angle(-kPi, kPi), scale(0.5, 2.0), coord(-5e3, 5e3);
  const Vec3 axis(normal(rng), normal(rng), normal(rng));
  const Vec3 origin(coord(rng), coord(rng), coord(rng));
  const Vec3 shift(coord(rng), coord(rng), coord(rng));
  return Location::translation(shift) * Location::scaling(scale(rng), origin) *
         Location::rotation(origin, axis, angle(rng));
}

Vec3 random_unit(std::mt19937_64& rng) {
  std::normal_distribution<double> normal;
  Vec3 v(normal(rng), normal(rng), normal(rng));
  return v.normalized();
}

/// Writes, reads, compares and writes again; returns the bytes.
std::string expect_round_trip(const Shape& shape) {
  std::string bytes = write_native(shape);
  auto read = read_native(bytes);
  EXPECT_TRUE(read.ok()) << read.error().message;
  if (!read.ok()) return bytes;
  EXPECT_TRUE(structurally_equal(shape, read.value()));
  EXPECT_TRUE(write_native(read.value()) == bytes) << "write -> read -> write is not identical";
  return bytes;
}

/// Recomputes the trailing checksum after a deliberate edit.
std::string reseal(std::string bytes) {
  const std::uint32_t crc = crc32c(std::string_view(bytes).substr(0, bytes.size() - 4));
  for (int i = 0; i < 4; ++i) bytes[bytes.size() - 4 + i] = static_cast<char>(crc >> (8 * i));
  return bytes;
}

/// A file from a hand-written body (header + sections), checksum appended.
std::string seal(const std::string& without_checksum) {
  return reseal(without_checksum + std::string(4, '\0'));
}

std::string header() { return std::string("CSGT\x01\x00", 6); }

std::string section(std::uint8_t tag, const std::string& payload) {
  EXPECT_LT(payload.size(), 128U);
  return std::string(1, static_cast<char>(tag)) +
         std::string(1, static_cast<char>(payload.size())) + payload;
}

struct NamedBuild {
  const char* name;
  Result<Shape> (*build)();
};

constexpr NamedBuild kPrimitives[] = {
    {"box", [] { return make_box(10, 8, 6); }},
    {"cylinder", [] { return make_cylinder(1, 3); }},
    {"cone", [] { return make_cone(2, 0, 3); }},
    {"frustum", [] { return make_cone(2, 1, 3); }},
    {"sphere", [] { return make_sphere(1); }},
    {"torus", [] { return make_torus(2, 0.5); }},
    {"extrusion_with_hole",
     [] {
       return make_extrusion({{0, 0}, {10, 0}, {10, 6}, {4, 9}, {0, 6}},
                             {{{2, 2}, {4, 2}, {4, 4}, {2, 4}}}, 12);
     }},
    {"revolution_full",
     [] {
       return make_revolution({{0, 0}, {2, 0}, {2, 1}, {1, 3}, {0, 3}}, 2 * kPi);
     }},
    {"revolution_partial",
     [] {
       return make_revolution({{1, 0}, {2, 0}, {2, 1}, {1, 1}}, 1.0);
     }},
};

// ---- round trips ------------------------------------------------------------------------

TEST(NativeFormat, Crc32cMatchesTheStandardCheckValue) {
  EXPECT_EQ(crc32c("123456789"), 0xE3069283U);
  EXPECT_EQ(crc32c(""), 0U);
  // Every length and offset (the hardware path takes eight bytes at a time, then the rest)
  // against the definition, one bit at a time.
  const auto by_bits = [](std::string_view bytes) {
    std::uint32_t c = 0xFFFFFFFFU;
    for (const char ch : bytes) {
      c ^= static_cast<std::uint8_t>(ch);
      for (int k = 0; k < 8; ++k) c = (c & 1U) ? (c >> 1) ^ 0x82F63B78U : c >> 1;
    }
    return c ^ 0xFFFFFFFFU;
  };
  std::string text;
  for (int i = 0; i < 100; ++i) text.push_back(static_cast<char>((i * 37 + 11) & 0xFF));
  for (std::size_t from = 0; from < 9; ++from) {
    for (std::size_t n = 0; from + n <= text.size(); ++n) {
      const std::string_view part = std::string_view(text).substr(from, n);
      ASSERT_EQ(crc32c(part), by_bits(part)) << from << " " << n;
    }
  }
}

TEST(NativeFormat, EveryPrimitiveAtRandomPlacementsRoundTrips) {
  const std::uint64_t seed = 20240611;
  std::mt19937_64 rng(seed);
  for (const NamedBuild& primitive : kPrimitives) {
    for (int trial = 0; trial < 5; ++trial) {
      SCOPED_TRACE(std::string(primitive.name) + " trial " + std::to_string(trial) + " seed " +
                   std::to_string(seed));
      const Shape placed = unwrap(primitive.build()).moved(random_similarity(rng));
      expect_round_trip(placed);
      const Shape read = unwrap(read_native(write_native(placed)));
      EXPECT_TRUE(check_shape(read).valid());
      EXPECT_EQ(count_shapes(read), count_shapes(placed));
    }
  }
}

TEST(NativeFormat, SharingSurvivesACompoundHoldingOneSolidTwice) {
  std::mt19937_64 rng(7);
  const Shape box = unwrap(make_box(1, 2, 3));
  const Shape twice = unwrap(ShapeFactory::compound(
      {box.moved(random_similarity(rng)), box.moved(random_similarity(rng)).reversed()}));
  expect_round_trip(twice);
  const Shape read = unwrap(read_native(write_native(twice)));
  ASSERT_EQ(read.child_count(), 2U);
  EXPECT_TRUE(read.child(0).shares_body(read.child(1)));
  EXPECT_FALSE(read.child(0).is_same(read.child(1)));
  EXPECT_EQ(read.child(1).orientation(), Orientation::Reversed);
  // Faces share their edges inside each copy: 12 distinct edges per placed box.
  EXPECT_EQ(map_child_shapes(read, ShapeKind::Edge).size(), 24U);
}

TEST(NativeFormat, SharingIsNotInventedForEqualButSeparateBodies) {
  const Shape a = unwrap(make_box(1, 1, 1));
  const Shape b = unwrap(make_box(1, 1, 1));
  const Shape separate =
      unwrap(ShapeFactory::compound({a, b.moved(Location::translation({2, 0, 0}))}));
  const Shape shared =
      unwrap(ShapeFactory::compound({a, a.moved(Location::translation({2, 0, 0}))}));
  expect_round_trip(separate);
  expect_round_trip(shared);
  EXPECT_FALSE(structurally_equal(separate, shared));
  EXPECT_LT(write_native(shared).size(), write_native(separate).size());
  const Shape read = unwrap(read_native(write_native(separate)));
  EXPECT_FALSE(read.child(0).shares_body(read.child(1)));
}

/// An edge on `curve` over [t0, t1] with vertices exactly at its ends.
Shape edge_on(const CurvePtr& curve, double t0, double t1, double tolerance = 1e-7) {
  const Shape start = unwrap(ShapeFactory::vertex(curve->point(t0), tolerance));
  const Shape end = unwrap(ShapeFactory::vertex(curve->point(t1), tolerance));
  return unwrap(ShapeFactory::edge(curve, t0, t1, start, end, tolerance));
}

/// Geometry and topology the primitives do not use: ellipses, polylines, trig curves and
/// pcurves, clockwise circle pcurves, extrusion and revolution surfaces on random axes, a
/// degenerate edge, Internal and External uses, faces without wires, a shared curve, a -0.0
/// in a location.
Shape exotic_model(std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  Frame tilted = Frame::from_z({1, 2, 3}, random_unit(rng), random_unit(rng));
  auto ellipse = std::make_shared<EllipseCurve>(tilted, 3.0, 1.5);
  auto polyline = std::make_shared<PolylineCurve>(
      std::vector<Vec3>{{0, 0, 0}, {1, 0.5, 0}, {2, 0, 0.25}, {3, 1, 1}}, 1e-4);
  auto line = std::make_shared<LineCurve>(Vec3(1, 1, 1), random_unit(rng));
  const Shape e_ellipse = edge_on(ellipse, 0.25, 2.5);
  const Shape e_polyline = edge_on(polyline, 0.0, 3.0, 2e-4);
  const Shape e_line = edge_on(line, -1.0, 4.0);
  const Shape e_line_again = edge_on(line, 5.0, 6.0);  // shares the curve
  auto trig =
      std::make_shared<TrigCurve>(Vec3(0.5, 0, 2), 2.0 * random_unit(rng), random_unit(rng));
  const Shape e_trig = edge_on(trig, -0.5, 2.0);
  const Shape pole = unwrap(ShapeFactory::vertex({0, 0, 1}, 1e-6));
  const Shape degenerate = unwrap(ShapeFactory::degenerate_edge(pole, 0.0, 2 * kPi, 1e-7));
  const Shape wire = unwrap(
      ShapeFactory::wire({e_ellipse, e_polyline.reversed(), e_line.oriented(Orientation::Internal),
                          e_line_again.oriented(Orientation::External), degenerate, e_trig}));
  std::vector<Curve2dPtr> pcurves = {
      std::make_shared<Circle2d>(Vec2(0.5, -0.25), 2.0, -1),
      std::make_shared<Polyline2d>(std::vector<Vec2>{{0, 0}, {1, 2}, {3, 1}}),
      std::make_shared<Line2d>(Vec2(1, 2), Vec2(-0.5, 3)),
      std::make_shared<Circle2d>(Vec2(0, 0), 1.0, 1),
      std::make_shared<Line2d>(Vec2(0, 1), Vec2(1, 0)),
      std::make_shared<Trig2d>(Vec2(1, 2), Vec2(0.5, 0), Vec2(0, 0.25), Vec2(0.1, -0.2))};
  auto extrusion = std::make_shared<ExtrusionSurface>(ellipse, random_unit(rng));
  const Shape on_extrusion = unwrap(ShapeFactory::face(extrusion, {wire}, {pcurves}, 1e-8));
  auto meridian = std::make_shared<LineCurve>(Vec3(2, 0, 0), Vec3(0.3, 0, 1));
  auto revolution = std::make_shared<RevolutionSurface>(meridian, Vec3(0, 0, 0), random_unit(rng));
  const Shape on_revolution = unwrap(ShapeFactory::face(revolution, {}, {}, 0.0));
  auto cone = std::make_shared<ConeSurface>(tilted, 0.0, 0.3);
  const Shape on_cone = unwrap(ShapeFactory::face(cone, {}, {}, 1e-7));
  const Shape lone_vertex = unwrap(ShapeFactory::vertex({-0.0, 0.0, 1e300}, 0.0));
  const Location negative_zero = Location::translation({-0.0, 0.0, 0.0});
  const Shape shell = unwrap(ShapeFactory::shell({on_extrusion, on_cone.reversed()}));
  return unwrap(ShapeFactory::compound(
      {shell, on_revolution.located(negative_zero), lone_vertex.oriented(Orientation::External),
       unwrap(ShapeFactory::compound({})), unwrap(ShapeFactory::wire({}))}));
}

TEST(NativeFormat, ExoticGeometryAndTopologyRoundTrip) {
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const Shape model = exotic_model(seed);
    expect_round_trip(model);
    std::mt19937_64 rng(seed);
    expect_round_trip(model.moved(random_similarity(rng)));
  }
}

TEST(NativeFormat, BooleanResultsRoundTrip) {
  // Boolean results carry section curves (trig curves and pcurves) and split faces.
  const Shape box = unwrap(make_box(4, 4, 4));
  const Shape column = unwrap(make_cylinder(1, 6)).moved(Location::translation({2, 2, -1}));
  for (const BooleanOp op : {BooleanOp::Cut, BooleanOp::Fuse, BooleanOp::Common}) {
    SCOPED_TRACE(boolean_op_name(op));
    auto result = boolean_operation(box, column, op);
    if (!result.ok()) {
      ADD_FAILURE() << "Boolean failed (not a format problem): " << result.error().message;
      continue;
    }
    expect_round_trip(result.value());
    std::mt19937_64 rng(31);
    expect_round_trip(result.value().moved(random_similarity(rng)));
  }
}

TEST(NativeFormat, UnitDirectionsComeBackBitForBit) {
  // Normalising a unit vector again moves about a third of them by an ulp; the writer must
  // store a vector that normalises to exactly the direction the curve holds.
  const std::uint64_t seed = 99;
  std::mt19937_64 rng(seed);
  std::vector<Shape> parts;
  for (int i = 0; i < 300; ++i) {
    auto line = std::make_shared<LineCurve>(Vec3(i, 0, 0), random_unit(rng) * (1.0 + i));
    parts.push_back(edge_on(line, 0.0, 1.0));
    auto basis = std::make_shared<CircleCurve>(Frame(), 1.0);
    parts.push_back(unwrap(ShapeFactory::face(
        std::make_shared<ExtrusionSurface>(basis, random_unit(rng)), {}, {}, 0.0)));
  }
  const Shape model = unwrap(ShapeFactory::compound(parts));
  expect_round_trip(model);
}

TEST(NativeFormat, NullShapeAndEmptyCompoundRoundTrip) {
  const std::string null_bytes = expect_round_trip(Shape());
  EXPECT_EQ(null_bytes.size(), 14U);  // magic, version, flags, body section (4), checksum
  EXPECT_TRUE(read_native(null_bytes).value().is_null());
  expect_round_trip(unwrap(ShapeFactory::compound({})));
  EXPECT_FALSE(structurally_equal(Shape(), unwrap(ShapeFactory::compound({}))));
}

TEST(NativeFormat, OutputIsDeterministic) {
  std::mt19937_64 rng1(5), rng2(5);
  const Shape a = unwrap(make_torus(3, 1)).moved(random_similarity(rng1));
  const Shape b = unwrap(make_torus(3, 1)).moved(random_similarity(rng2));
  EXPECT_EQ(write_native(a), write_native(a));
  EXPECT_EQ(write_native(a), write_native(b));  // separately built, same structure
  EXPECT_TRUE(structurally_equal(a, b));
}

TEST(NativeFormat, StructuralEqualityNoticesChanges) {
  std::mt19937_64 rng(11);
  const Location placement = random_similarity(rng);
  const Shape box = unwrap(make_box(1, 2, 3)).moved(placement);
  const Shape read = unwrap(read_native(write_native(box)));
  ASSERT_TRUE(structurally_equal(box, read));
  EXPECT_FALSE(structurally_equal(box, read.reversed()));
  EXPECT_FALSE(structurally_equal(box, read.moved(Location::translation({0, 0, 1e-12}))));
  EXPECT_FALSE(structurally_equal(box, unwrap(make_box(1, 2, 3.0000000001)).moved(placement)));
  EXPECT_FALSE(structurally_equal(box, unwrap(make_box(1, 2, 3, 2e-7)).moved(placement)));
  EXPECT_FALSE(structurally_equal(box, unwrap(make_box(1, 2, 3)).moved(placement.inverse())));
  EXPECT_FALSE(structurally_equal(box, Shape()));
}

// ---- corruption -------------------------------------------------------------------------

/// A small model using every table: a box and a placed cylinder sharing nothing.
Shape small_model() {
  const Shape box = unwrap(make_box(1, 2, 3));
  const Shape cylinder = unwrap(make_cylinder(0.5, 1)).moved(Location::translation({3, 0, 0}));
  return unwrap(ShapeFactory::compound({box, cylinder}));
}

TEST(NativeFormatHostile, EveryTruncationIsAnError) {
  const std::string bytes = write_native(small_model());
  for (std::size_t n = 0; n < bytes.size(); ++n) {
    auto read = read_native(std::string_view(bytes).substr(0, n));
    ASSERT_FALSE(read.ok()) << "prefix of " << n << " bytes was accepted";
    EXPECT_EQ(read.error().code, ErrorCode::CorruptData) << n << ": " << read.error().message;
  }
}

TEST(NativeFormatHostile, EverySingleByteFlipIsAnError) {
  const std::string bytes = write_native(small_model());
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    for (const unsigned mask : {0x01U, 0x80U, 0xFFU, 0x5AU}) {
      std::string damaged = bytes;
      damaged[i] = static_cast<char>(damaged[i] ^ mask);
      auto read = read_native(damaged);
      ASSERT_FALSE(read.ok()) << "flip " << mask << " at byte " << i << " was accepted";
      EXPECT_TRUE(read.error().code == ErrorCode::CorruptData ||
                  read.error().code == ErrorCode::UnsupportedVersion)
          << read.error().message;
    }
  }
}

TEST(NativeFormatHostile, ResealedByteFlipsNeverCrashAndStayConsistent) {
  // With the checksum recomputed every flip reaches the parser. A flip may still describe a
  // valid shape (another number, another orientation); then writing and reading it again
  // must be stable.
  const std::string bytes = write_native(small_model());
  std::size_t accepted = 0;
  for (std::size_t i = 0; i + 4 < bytes.size(); ++i) {
    for (const unsigned mask : {0x01U, 0x02U, 0x10U, 0x80U, 0xFFU}) {
      std::string damaged = bytes;
      damaged[i] = static_cast<char>(damaged[i] ^ mask);
      auto read = read_native(reseal(damaged));
      if (!read.ok()) continue;
      ++accepted;
      const std::string again = write_native(read.value());
      auto reread = read_native(again);
      ASSERT_TRUE(reread.ok()) << reread.error().message;
      EXPECT_TRUE(structurally_equal(read.value(), reread.value())) << "flip at " << i;
    }
  }
  std::printf("[ native   ] %zu of %zu resealed flips still parse\n", accepted,
              (bytes.size() - 4) * 5);
}

TEST(NativeFormatHostile, VersionsFlagsAndSectionsAreChecked) {
  const std::string bytes = write_native(small_model());
  ASSERT_EQ(bytes[4], '\x01');  // the version varint
  for (const char version : {'\x00', '\x02', '\x7F'}) {
    std::string other = bytes;
    other[4] = version;
    // Newer or older, with or without a matching checksum: UnsupportedVersion.
    EXPECT_EQ(read_native(other).error().code, ErrorCode::UnsupportedVersion);
    EXPECT_EQ(read_native(reseal(other)).error().code, ErrorCode::UnsupportedVersion);
  }
  std::string flagged = bytes;
  flagged[5] = '\x01';
  EXPECT_EQ(read_native(reseal(flagged)).error().code, ErrorCode::UnsupportedVersion);

  std::string not_ours = bytes;
  not_ours[0] = 'X';
  EXPECT_EQ(read_native(not_ours).error().code, ErrorCode::CorruptData);
  EXPECT_EQ(read_native("").error().code, ErrorCode::CorruptData);
  std::string trailing = bytes;
  trailing.insert(trailing.size() - 4, "\x00", 1);
  EXPECT_EQ(read_native(reseal(trailing)).error().code, ErrorCode::CorruptData);
}

TEST(NativeFormatHostile, UnknownOptionalSectionsAreSkippedUnknownRequiredRefused) {
  const std::string null_body = section(12, std::string("\x00\x00", 2));
  const std::string later_optional = section(13, "history from a newer writer");
  const std::string later_required = section(14, "needed by a newer reader");
  auto skipped = read_native(seal(header() + null_body + later_optional));
  ASSERT_TRUE(skipped.ok()) << skipped.error().message;
  EXPECT_TRUE(skipped.value().is_null());
  auto early_optional = read_native(seal(header() + section(1, "x") + null_body));
  EXPECT_TRUE(early_optional.ok());
  auto refused = read_native(seal(header() + null_body + later_required));
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().code, ErrorCode::UnsupportedVersion);
  // Out of order, repeated, missing, overrunning.
  EXPECT_EQ(read_native(seal(header() + null_body + section(2, std::string(1, '\0')))).error().code,
            ErrorCode::CorruptData);
  EXPECT_EQ(read_native(seal(header() + null_body + null_body)).error().code,
            ErrorCode::CorruptData);
  EXPECT_EQ(read_native(seal(header())).error().code, ErrorCode::CorruptData);
  EXPECT_EQ(read_native(seal(header() + std::string("\x0c\x10\x00\x00", 4))).error().code,
            ErrorCode::CorruptData);
}

/// Bodies: `count` compounds, each holding the previous one; root = the last.
std::string nested_compounds(int count) {
  std::string payload;
  payload.push_back(static_cast<char>((count & 0x7F) | 0x80));
  payload.push_back(static_cast<char>(count >> 7));
  payload.push_back('\x00');                                              // body 0: empty compound
  for (int i = 1; i < count; ++i) payload += std::string("\x08\x08", 2);  // 1 child, delta 1
  payload.push_back('\x08');  // root: delta 1 from the end
  std::string out = header() + "\x0c";
  std::size_t n = payload.size();
  while (n >= 0x80) {
    out.push_back(static_cast<char>((n & 0x7F) | 0x80));
    n >>= 7;
  }
  out.push_back(static_cast<char>(n));
  return seal(out + payload);
}

TEST(NativeFormatHostile, NestingIsBounded) {
  auto shallow = read_native(nested_compounds(200));
  ASSERT_TRUE(shallow.ok()) << shallow.error().message;
  auto deep = read_native(nested_compounds(300));
  ASSERT_FALSE(deep.ok());
  EXPECT_EQ(deep.error().code, ErrorCode::CorruptData);
  EXPECT_NE(deep.error().message.find("deeper"), std::string::npos) << deep.error().message;
}

TEST(NativeFormatHostile, MalformedRecordsAreCorruptData) {
  auto expect_corrupt = [](const std::string& file, const char* what) {
    auto read = read_native(file);
    ASSERT_FALSE(read.ok()) << what;
    EXPECT_EQ(read.error().code, ErrorCode::CorruptData) << what;
    std::printf("[ native   ] %-28s -> %s\n", what, read.error().message.c_str());
  };
  // A compound referring to itself or forwards: delta 1 from body 0.
  expect_corrupt(seal(header() + section(12, std::string("\x01\x08\x08\x08", 4))),
                 "forward reference");
  // A count far beyond the input.
  expect_corrupt(seal(header() + section(2, std::string("\xff\xff\xff\xff\x0f", 5))),
                 "huge number count");
  // A NaN, a negative entry and a 9-byte entry in the number table (count, lengths, bytes).
  const std::string null_body = section(12, std::string("\x00\x00", 2));
  expect_corrupt(seal(header() + section(2, std::string("\x01\x02\xf8\x7f", 4)) + null_body),
                 "NaN number");
  expect_corrupt(seal(header() + section(2, std::string("\x01\x01\x80", 3)) + null_body),
                 "negative number entry");
  expect_corrupt(
      seal(header() + section(2, std::string("\x01\x09", 2) + std::string(9, 'a')) + null_body),
      "number length 9");
  // A vertex whose number index is out of range.
  expect_corrupt(seal(header() + section(12, std::string("\x01\x07\x00\x00\x00\x00\x00", 7))),
                 "number index out of range");
  // Unknown curve kind.
  expect_corrupt(seal(header() + section(6, std::string("\x01\x09", 2)) +
                      section(12, std::string("\x00\x00", 2))),
                 "unknown curve kind");
  // A solid made of a vertex (ShapeFactory refuses): numbers {0}, vertex, solid of it.
  const std::string zero_table("\x01\x00", 2);  // one number, 0.0, stored in no bytes
  expect_corrupt(seal(header() + section(2, zero_table) +
                      section(12, std::string("\x02\x07\x00\x00\x00\x00\x0a\x08\x08", 9))),
                 "solid of a vertex");
  // An edge whose vertices are both Forward.
  expect_corrupt(
      seal(
          header() + section(2, zero_table) +
          section(12, std::string("\x02\x07\x00\x00\x00\x00\x16\x00\x00\x00\x00\x08\x08\x08", 14))),
      "edge orientations");
  // Regression (fuzzer, crash-7472bc5c): a line direction stored as (1, 1, 1) normalises to a
  // direction whose canonical stored form is another vector, so writing the shape again
  // would not reproduce it; such files are refused. Numbers {0, 1}; the line's six number
  // references are 16 + index on first use, then recent-window positions.
  const std::string zero_one("\x02\x20\xf0\x3f", 4);
  expect_corrupt(seal(header() + section(2, zero_one) +
                      section(6, std::string("\x01\x00\x20\x00\x00\x22\x00\x00", 8)) +
                      section(12, std::string("\x00\x00", 2))),
                 "non-canonical direction");
  // Varint longer than 10 bytes.
  expect_corrupt(seal(header() + section(12, std::string(12, '\xff'))), "overlong varint");
}

// ---- files ------------------------------------------------------------------------------

class NativeFormatFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("csgtile_native_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
            "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  std::vector<std::string> listing() const {
    std::vector<std::string> names;
    for (const auto& entry : std::filesystem::directory_iterator(dir_)) {
      names.push_back(entry.path().filename().string());
    }
    std::sort(names.begin(), names.end());
    return names;
  }

  std::filesystem::path dir_;
};

TEST_F(NativeFormatFile, WritesAtomicallyAndReadsBack) {
  const Shape model = small_model();
  const auto path = dir_ / "model.csgt";
  ASSERT_TRUE(write_native_file(path, model).ok());
  EXPECT_EQ(listing(), std::vector<std::string>{"model.csgt"});  // no temporary left behind
  auto read = read_native_file(path);
  ASSERT_TRUE(read.ok()) << read.error().message;
  EXPECT_TRUE(structurally_equal(model, read.value()));

  // Replacing an existing file leaves exactly the new content.
  const Shape other = unwrap(make_sphere(2));
  ASSERT_TRUE(write_native_file(path, other).ok());
  EXPECT_EQ(listing(), std::vector<std::string>{"model.csgt"});
  EXPECT_TRUE(structurally_equal(other, read_native_file(path).value()));
}

TEST_F(NativeFormatFile, FailuresAreIoErrorsAndLeaveNothingBehind) {
  const auto missing_dir = dir_ / "no" / "such" / "dir" / "model.csgt";
  const Status s = write_native_file(missing_dir, small_model());
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().code, ErrorCode::IoError);
  EXPECT_TRUE(listing().empty());

  auto missing = read_native_file(dir_ / "absent.csgt");
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.error().code, ErrorCode::IoError);

  // A truncated file on disk is CorruptData, and the message names the file.
  const auto path = dir_ / "cut.csgt";
  const std::string bytes = write_native(small_model());
  std::ofstream(path, std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  auto cut = read_native_file(path);
  ASSERT_FALSE(cut.ok());
  EXPECT_EQ(cut.error().code, ErrorCode::CorruptData);
  EXPECT_NE(cut.error().message.find("cut.csgt"), std::string::npos);
}

// ---- size ------------------------------------------------------------------------------

TEST(NativeFormat, BytesPerPrimitiveAgainstBinaryStlAtOneCentimetre) {
  // Logged for the size benchmark. Curved primitives are far smaller than their meshes; a
  // box's 26 topological entities and 24 pcurves are about the size of its 12 triangles.
  struct Case {
    const char* name;
    Result<Shape> shape;
    bool curved;
  };
  Case cases[] = {
      {"box 10x8x6", make_box(10, 8, 6), false},
      {"cylinder r1 h3", make_cylinder(1, 3), true},
      {"sphere r1", make_sphere(1), true},
      {"torus R2 r0.5", make_torus(2, 0.5), true},
  };
  std::mt19937_64 rng(3);
  for (Case& c : cases) {
    const Shape shape = unwrap(std::move(c.shape));
    const std::size_t local = write_native(shape).size();
    const std::size_t placed = write_native(shape.moved(random_similarity(rng))).size();
    TessellationOptions options;
    options.chordal_tolerance = 0.01;
    auto mesh = tessellate(shape, options);
    ASSERT_TRUE(mesh.ok()) << mesh.error().message;
    const std::size_t stl = to_binary_stl(mesh.value()).size();
    std::printf(
        "[ native   ] %-15s %4zu bytes (placed %4zu); binary STL at 1 cm %6zu bytes "
        "(%zu triangles): %5.1f%%\n",
        c.name, local, placed, stl, mesh->triangles.size(),
        100.0 * static_cast<double>(placed) / static_cast<double>(stl));
    if (c.curved) {
      EXPECT_LT(placed * 10, stl) << c.name;
    }
  }
}

TEST(NativeFormat, LocationFromPartsKeepsBitsAndRejectsNonRotations) {
  std::mt19937_64 rng(17);
  const Location l = random_similarity(rng);
  auto rebuilt = Location::from_parts(l.rotation(), l.scale(), l.translation());
  ASSERT_TRUE(rebuilt.ok());
  EXPECT_TRUE(rebuilt.value() == l);
  Eigen::Matrix3d mirror = Eigen::Matrix3d::Identity();
  mirror(2, 2) = -1;
  EXPECT_EQ(Location::from_parts(mirror, 1, Vec3::Zero()).error().code, ErrorCode::InvalidLocation);
  EXPECT_FALSE(Location::from_parts(2 * Eigen::Matrix3d::Identity(), 1, Vec3::Zero()).ok());
  EXPECT_FALSE(Location::from_parts(Eigen::Matrix3d::Identity(), 0, Vec3::Zero()).ok());
  EXPECT_FALSE(Location::from_parts(Eigen::Matrix3d::Identity(), 1, Vec3(NAN, 0, 0)).ok());
}

}  // namespace
}  // namespace csgtile::kernel
