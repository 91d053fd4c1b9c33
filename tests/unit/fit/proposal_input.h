#pragma once
// A proposer's inputs (fit_internal.h) for a test cloud and its detected shapes: nothing used
// or absorbed yet, the connectivity cell three RANSAC epsilons.

#include <vector>

#include "fit_clouds.h"
#include "fit_internal.h"

namespace csgtile::fit::testing {

struct FreshProposalInput {
  std::vector<char> used, absorbed;
  detail::ProposalInput in;

  FreshProposalInput(const Cloud& c, const RansacResult& shapes, const PrimitiveOptions& options,
                     const RansacOptions& ransac)
      : used(c.points.size(), 0), absorbed(shapes.shapes.size(), 0) {
    in.points = c.points;
    in.normals = c.normals;
    in.shapes = &shapes;
    in.used = &used;
    in.absorbed = &absorbed;
    in.options = &options;
    in.ransac = &ransac;
    in.cell = 3.0 * ransac.epsilon;
  }
  // `in` points into this object.
  FreshProposalInput(const FreshProposalInput&) = delete;
  FreshProposalInput& operator=(const FreshProposalInput&) = delete;
};

}  // namespace csgtile::fit::testing
