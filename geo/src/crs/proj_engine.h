#pragma once
// A projection computed by PROJ from a PROJ string (ProjectionMethod::ComputedByProj, and
// the oblique stereographic of RD New as "+proj=sterea"). PROJ objects are not thread-safe:
// each thread builds its own PJ from the string on first use and keeps it in a small cache.

#include <memory>
#include <string>

#include "crs/geodesy.h"
#include "csgtile/kernel/result.h"

namespace csgtile::geo::detail {

/// Builds the engine; checks once that PROJ accepts the string and that it is a projection
/// (geodetic in, metres out). Errors: InvalidArgument naming the string and PROJ's reason.
kernel::Result<std::unique_ptr<ProjectionEngine>> make_proj_engine(const std::string& proj_string);

/// A PROJ transformation of geodetic coordinates (a datum shift PROJ chose): longitude and
/// latitude in degrees, height in metres, in place. Throws DomainError where PROJ cannot
/// transform (outside its grid). Thread-safe (one PJ per thread).
class GeodeticTransform {
 public:
  virtual ~GeodeticTransform() = default;
  virtual void forward(double& lat, double& lon, double& h) const = 0;
  virtual void inverse(double& lat, double& lon, double& h) const = 0;
};

/// Errors: InvalidArgument naming the pipeline and PROJ's reason.
kernel::Result<std::shared_ptr<const GeodeticTransform>> make_geodetic_transform(
    const std::string& pipeline);

}  // namespace csgtile::geo::detail
