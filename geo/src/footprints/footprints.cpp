// read_footprints (footprints.h): loads the GDAL module (gdal_module.h) once, on the first
// read, and hands the read to it.

#include "csgtile/geo/footprints.h"

#include "csgtile/kernel/module.h"
#include "footprints/gdal_module.h"

namespace csgtile::geo {

std::jthread load_footprints_in_background() {
  return kernel::load_module_in_background(kGdalModuleFile, kGdalModuleAbi);
}

kernel::Result<FootprintSet> read_footprints(const FootprintSource& source,
                                             const FootprintQuery& query) {
  const kernel::Module& module = kernel::load_module(kGdalModuleFile, kGdalModuleAbi);
  auto* read =
      kernel::module_function<CsgtileGdalReadFootprints>(module, "csgtile_gdal_read_footprints");
  if (read == nullptr) {
    return kernel::Error{
        kernel::ErrorCode::Unsupported,
        "footprints " + source.source + ": GDAL, which reads them: " +
            (module.error.empty() ? "the module lacks its entry point" : module.error)};
  }
  kernel::Result<FootprintSet> out = kernel::Error{
      kernel::ErrorCode::IoError, "footprints " + source.source + ": GDAL failed with no reason"};
  read(source, query, out);
  return out;
}

}  // namespace csgtile::geo
