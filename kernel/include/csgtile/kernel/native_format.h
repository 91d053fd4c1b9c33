#pragma once
/// \file
/// The native model format (DESIGN.md §3): a versioned, checksummed, lossless and compact
/// binary encoding of a shape — topology with its sharing, locations, orientations,
/// tolerances and geometry.
///
/// Layout (version 1; kernel/src/io/native_layout.h has the full grammar):
///   "CSGT" | version (varint) | flags (varint, 0) | sections … | CRC-32C (4 bytes, LE)
/// A section is tag (varint) + payload length (varint) + payload. Tag bit 0 marks an optional
/// section: readers skip optional sections they do not know and refuse unknown required
/// ones (UnsupportedVersion), so later versions add sections (e.g. CSG history) without
/// breaking older readers; the CSG history is such a section (write_native_model). Numbers are IEEE
/// doubles, written once in a number table (short mantissas shortened) and referenced by index or
/// by position in a window of recently used numbers; counts and indices are LEB128 varints;
/// geometry is shared by pointer identity.

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

#include "csgtile/kernel/csg.h"
#include "csgtile/kernel/result.h"
#include "csgtile/kernel/shape.h"

namespace csgtile::kernel {

/// The format version write_native produces; read_native reads exactly this version.
inline constexpr std::uint32_t kNativeFormatVersion = 1;

/// Serialises a shape of any kind (the null shape too) losslessly: read_native gives back a
/// shape that is structurally_equal to it, and writing that again gives the same bytes.
/// Deterministic: the same shape gives the same bytes (no dependence on pointer values).
/// Preconditions: the geometry's numbers are finite (ShapeFactory guarantees it for points,
/// parameters and tolerances) and line, extrusion and revolution directions are non-zero.
/// O(n log n) in the model size; thread-safe.
std::string write_native(const Shape& shape);

/// Parses bytes written by write_native. Never crashes on hostile input: every count is
/// checked against the remaining bytes before anything is allocated, every index against
/// its table, and every body is rebuilt through ShapeFactory.
/// Errors: UnsupportedVersion (another format version, non-zero flags, an unknown required
/// section); CorruptData (bad magic, checksum mismatch, truncation, out-of-range index, bad
/// kind/orientation, non-finite number, nesting deeper than 256, a body ShapeFactory
/// rejects, a geometry precondition broken, a direction not stored the way write_native
/// stores it, trailing bytes). Whatever it accepts, write_native writes back so that it
/// reads as the same shape. O(n) in the input size.
Result<Shape> read_native(std::string_view bytes);

/// Writes write_native(shape) to `path` atomically: a temporary file in the same directory
/// is written, fsync'ed and renamed over `path`, so readers see the old file or the new one,
/// never a half-written one; the temporary is removed on failure. Error: IoError.
Status write_native_file(const std::filesystem::path& path, const Shape& shape);

/// Reads a whole file and parses it with read_native. Errors: IoError, and read_native's.
Result<Shape> read_native_file(const std::filesystem::path& path);

/// A shape with its CSG history (csg.h): write_native of the shape plus the optional CSG
/// section (tag 13; readers that know only shapes skip it). Deterministic and lossless:
/// read_native_model gives back the same nodes (bit-identical numbers), face sources, and a
/// structurally_equal shape.
std::string write_native_model(const CsgModel& model);

/// Parses write_native_model's bytes (or write_native's: the model then has no history). The
/// history is checked against the shape with check_csg. Errors: read_native's, and
/// CorruptData for a malformed or inconsistent CSG section.
Result<CsgModel> read_native_model(std::string_view bytes);

/// File forms, atomic as write_native_file. Errors: IoError, and the parsers'.
Status write_native_model_file(const std::filesystem::path& path, const CsgModel& model);
Result<CsgModel> read_native_model_file(const std::filesystem::path& path);

/// Structural equality (the round-trip check): the same topology graph with the same
/// sharing — a body used twice in `a` corresponds to one body used twice in `b`, and
/// likewise for shared curves, surfaces and pcurves — and bit-identical locations,
/// orientations, tolerances and geometry parameters. O(n) expected; thread-safe.
bool structurally_equal(const Shape& a, const Shape& b);

/// CRC-32C (Castagnoli) of `bytes`: the checksum a native file ends with. Exposed for tools
/// that patch files on purpose (the fuzzer re-seals its mutations to reach the parser).
std::uint32_t crc32c(std::string_view bytes);

}  // namespace csgtile::kernel
