#pragma once
/// \file
/// Validity checker with named statuses.

#include <string>
#include <vector>

#include "csgtile/kernel/shape.h"

namespace csgtile::kernel {

/// Every defect the checker names.
enum class CheckStatus {
  NullShape,                 ///< the shape (or a child) is null
  InvalidLocation,           ///< a composed location is no longer a similarity
  ToleranceOrder,            ///< face tolerance > edge tolerance, or edge > vertex
  VertexOffCurve,            ///< an edge end is farther from its vertex than the tolerance
  EdgeOffFace,               ///< an edge's pcurve on a face strays from its 3D curve
  OpenWire,                  ///< consecutive edges of a wire do not share a vertex
  SelfIntersection,          ///< boundary loops of a face cross in its parameter plane
  FreeEdge,                  ///< an edge of a solid's shell is used by one face only
  OpenShell,                 ///< a shell of a solid is not closed (it has free edges)
  EdgeSameOrientationTwice,  ///< two faces use an edge in the same direction
  NonManifoldEdge,           ///< an edge used by more than two faces of one shell
  BadFaceOrientation,        ///< a solid's outer shell encloses negative volume
  EulerPoincareMismatch,     ///< V − E + F − (L − F) of a closed shell is odd or above 2
};

/// Stable snake_case name, e.g. "open_shell".
const char* check_status_name(CheckStatus status);

struct CheckIssue {
  CheckStatus status;
  std::string message;  ///< what is wrong and where (kind and index in explorer order)
};

struct CheckReport {
  std::vector<CheckIssue> issues;
  bool valid() const { return issues.empty(); }
  bool has(CheckStatus status) const;
};

/// Checks a shape and all its sub-shapes. Each sub-shape is checked once (child map);
/// O(n) plus a per-face O(k²) loop-crossing test over k boundary samples.
CheckReport check_shape(const Shape& shape);

}  // namespace csgtile::kernel
