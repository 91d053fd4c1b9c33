#pragma once
/// \file
/// Orientation (paper §2.3, Table 2).

#include <cstdint>

namespace csgtile::kernel {

/// Which side of a boundary is the interior.
/// - Vertex on an edge: Forward = at the small-parameter end (the start), Reversed = at the
///   large-parameter end.
/// - Edge on a face: Forward = the edge runs along its curve's natural direction, Reversed =
///   against it; the face lies on the left of the logical direction (seen from the normal).
/// - Face on a solid: Forward = the face's outward side is its surface normal (material on
///   the negative side), Reversed = the opposite.
/// - Internal: both sides are interior (an embedded boundary); External: neither is.
enum class Orientation : std::uint8_t { Forward = 0, Reversed = 1, Internal = 2, External = 3 };

/// Forward <-> Reversed; Internal and External are their own reverse.
constexpr Orientation reversed(Orientation o) {
  switch (o) {
    case Orientation::Forward:
      return Orientation::Reversed;
    case Orientation::Reversed:
      return Orientation::Forward;
    default:
      return o;
  }
}

/// Orientation of a child seen through a parent with orientation `parent`.
/// Forward parent: unchanged; Reversed parent: reversed(child); Internal or External parent:
/// the parent's orientation (an embedded or outside parent makes all its children so).
constexpr Orientation compose(Orientation parent, Orientation child) {
  switch (parent) {
    case Orientation::Forward:
      return child;
    case Orientation::Reversed:
      return reversed(child);
    default:
      return parent;
  }
}

/// "forward", "reversed", "internal", "external".
const char* orientation_name(Orientation o);

}  // namespace csgtile::kernel
