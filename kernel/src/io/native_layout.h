#pragma once
/// \file
/// The native format's byte layout, version 1: shared by the writer and the reader. Not API.
///
///   file     := "CSGT" version:varint flags:varint section* crc:u32le
///   section  := tag:varint length:varint payload[length]
///
/// `crc` is the CRC-32C of every byte before it. Sections appear in strictly increasing tag
/// order, each at most once. Tag bit 0 set = optional: a reader skips an optional tag it does
/// not know and refuses an unknown required (even) tag. Absent tables are empty; only the
/// body section is mandatory. The CSG history (csg.h: a tree of Booleans over PrimitiveSpec
/// leaves, per-face sources) is the optional section 13, written by write_native_model:
///   csg       (tag 13): node count, nodes (post-order) × { kind:u8, label (length + UTF-8),
///                       Primitive: type:u8, placement (rotation 9 f64, scale f64, translation
///                       3 f64), size 3 f64, radius, radius2, height, angle f64, profile
///                       (count, 2 f64 each), holes (count, each a profile), and when the
///                       kind byte has bit 7 set (a clipped primitive) clips (count ≥ 1,
///                       4 f64 each: n, d); operations:
///                       child count, child deltas (this index − child ≥ 1) },
///                       face count (= faces of the root shape), per face { count, count ×
///                       { node, face } }. f64 = IEEE double, 8 bytes little-endian.
///
/// Payloads (num = varint code << 1 | sign, the number being a table entry with its sign bit
/// set when `sign` is 1: code p < 16 is the entry at position p of the section's
/// RecentNumbers, code 16 + i is entry i; vec3 = 3 num; frame = origin x y z, 12 num; every
/// list is count:varint then items):
///   numbers   (tag 2):  count, ceil(count / 2) bytes of 4-bit lengths (entry 2k in the low
///                       nibble, 0–8), then each entry's `length` high-order bytes of its
///                       IEEE double, little-endian (the dropped low bytes are zero). Entries
///                       are finite magnitudes (sign clear), most used first, so that most
///                       references take one byte.
///   locations (tag 4):  count, count × { rotation row-major 9 num, scale num, vec3 }.
///                       The identity location is implicit and never stored.
///   curves    (tag 6):  count, count × { kind:u8 (CurveKind), fields }
///                       Line: origin vec3, direction vec3 (stored_unit_direction of the
///                       line's direction, unit_direction.h; readers refuse any other
///                       vector); Circle: frame, radius;
///                       Ellipse: frame, major, minor; Polyline: n ≥ 2, n × vec3, tolerance;
///                       Trig: centre vec3, a vec3, b vec3 (a × b ≠ 0)
///   surfaces  (tag 8):  count, count × { kind:u8 (SurfaceKind), fields }
///                       Plane: frame; Cylinder: frame, radius; Cone: frame, radius, semi-
///                       angle; Sphere: frame, radius; Torus: frame, major, minor;
///                       Extrusion: curve:varint, direction vec3 (preimage as for lines);
///                       Revolution: curve:varint, axis origin vec3, axis direction vec3
///   pcurves   (tag 10): count, count × { kind:u8 (kPcurve*), fields }
///                       Line: origin 2 num, direction 2 num; Circle (counter-clockwise or
///                       clockwise): centre 2 num, radius; Polyline: n ≥ 2, n × 2 num;
///                       Trig: c, a, b, d, 2 num each
///   bodies    (tag 12): count, count × body, then root
///     body  := head:varint = child_count << 3 | ShapeKind, then by kind:
///              Vertex: point vec3, tolerance (no children)
///              Edge:   curve:varint (0 = degenerate, k = curve k-1), first, last, tolerance,
///                      start ref (Forward), end ref (Reversed; the start's for degenerate)
///              Face:   surface:varint, tolerance, wire refs, then the pcurves of all
///                      edge uses (wire by wire): k + 1 when they are the pcurves k, k+1, …
///                      in order, else 0 followed by one pcurve:varint per edge use
///              other:  child refs
///     ref   := varint = delta << 3 | has_location << 2 | Orientation, then
///              location:varint when has_location. The child is body (this index − delta),
///              delta ≥ 1: bodies are in post-order, so references point backwards and the
///              graph cannot have cycles.
///     root  := varint 0 for the null shape, else a ref counted from index = body count.

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

#include "csgtile/kernel/result.h"
#include "csgtile/kernel/shape.h"

namespace csgtile::kernel::detail {

inline constexpr char kNativeMagic[4] = {'C', 'S', 'G', 'T'};
inline constexpr std::size_t kNativeChecksumSize = 4;

enum class SectionTag : std::uint32_t {
  Numbers = 2,
  Locations = 4,
  Curves = 6,
  Surfaces = 8,
  Pcurves = 10,
  Bodies = 12,
  Csg = 13,  ///< optional: CSG tree and face history (kernel/src/csg/csg_codec.cpp)
};

/// write_native with an extra optional section (tag, payload) after the body section.
std::string write_native_with(const Shape& shape, SectionTag extra_tag, std::string_view extra);

/// read_native that also hands out the payload (and its file offset) of one optional
/// section, left empty when the file has none.
struct NativeExtra {
  std::uint64_t tag = 0;
  std::string_view payload;
  std::size_t offset = 0;
  bool present = false;
};
/// Writes bytes to `path` atomically (temporary in the same directory, fsync, rename,
/// directory fsync); the temporary is removed on failure. Error: IoError.
Status write_file_atomically(const std::filesystem::path& path, std::string_view bytes);
/// A whole file's bytes. Error: IoError.
Result<std::string> read_whole_file(const std::filesystem::path& path);

/// read_native, filling `extra` when the file holds the optional section extra.tag.
Result<Shape> read_native_with(std::string_view bytes, NativeExtra& extra);

inline constexpr std::uint64_t kSignBit = std::uint64_t{1} << 63;

/// Bytes of a number-table entry that are kept: the low-order bytes that are zero (short
/// mantissas: integers, halves, 0) are dropped. 0 to 8.
inline int significant_bytes(std::uint64_t bits) {
  int n = 8;
  while (n > 0 && (bits & 0xFFU) == 0) {
    bits >>= 8;
    --n;
  }
  return n;
}

/// The most recently used number-table indices, most recent first (move to front). Writer
/// and reader keep one per section payload, starting empty, and update it after every number
/// reference, so both always agree on its content. A model's data comes in runs (a box's
/// vertices, then its edges, …) that reuse a few numbers, so most references hit it and
/// take one byte even when the table is large.
class RecentNumbers {
 public:
  static constexpr std::size_t kCapacity = 16;

  std::size_t size() const { return size_; }
  /// Position of `index`, or kCapacity when it is not there.
  std::size_t find(std::size_t index) const {
    for (std::size_t p = 0; p < size_; ++p) {
      if (entries_[p] == index) return p;
    }
    return kCapacity;
  }
  /// Precondition: position < size().
  std::size_t at(std::size_t position) const { return entries_[position]; }
  /// Moves `index` to the front (inserting it, and dropping the oldest when full).
  void use(std::size_t index) {
    std::size_t p = find(index);
    if (p == kCapacity) p = size_ < kCapacity ? size_++ : kCapacity - 1;
    for (; p > 0; --p) entries_[p] = entries_[p - 1];
    entries_[0] = index;
  }

 private:
  std::array<std::size_t, kCapacity> entries_{};
  std::size_t size_ = 0;
};

inline constexpr bool is_optional_tag(std::uint64_t tag) { return (tag & 1U) != 0; }

/// Pcurve kind codes: the Curve2dKind values, plus a code for clockwise circles (sense −1).
inline constexpr std::uint8_t kPcurveLine = 0;
inline constexpr std::uint8_t kPcurveCircle = 1;
inline constexpr std::uint8_t kPcurvePolyline = 2;
inline constexpr std::uint8_t kPcurveTrig = 3;
inline constexpr std::uint8_t kPcurveClockwiseCircle = 4;

/// Child references pack the orientation in bits 0–1 and a location flag in bit 2.
inline constexpr unsigned kRefShift = 3;
inline constexpr std::uint64_t kRefHasLocation = 4;
inline constexpr std::uint64_t kRefOrientationMask = 3;
/// Body headers pack the ShapeKind in bits 0–2.
inline constexpr unsigned kBodyHeadShift = 3;
inline constexpr std::uint64_t kBodyKindMask = 7;

/// Deepest body nesting a reader accepts (compounds of compounds …): deeper shapes could
/// overflow the stack when they are destroyed. Kernel models nest a few levels.
inline constexpr int kMaxNestingDepth = 256;

}  // namespace csgtile::kernel::detail
