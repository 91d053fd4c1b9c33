// read_footprints (footprints.h): loads the GDAL module (gdal_module.h) once, on the first
// read, and hands the read to it.

#include "csgtile/geo/footprints.h"

#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <string>
#include <vector>

#include "footprints/gdal_module.h"

namespace csgtile::geo {

namespace {

namespace fs = std::filesystem;

/// The directories searched for the module, in order: only $CSGTILE_MODULE_DIR when set;
/// else the running binary's directory, its ../lib/csgtile (an installed binary), and the
/// build tree's (tests and benchmarks run from their own directories).
std::vector<fs::path> module_dirs() {
  if (const char* dir = std::getenv("CSGTILE_MODULE_DIR"); dir != nullptr && *dir != '\0')
    return {fs::path(dir)};
  std::vector<fs::path> dirs;
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    dirs.push_back(exe.parent_path());
    dirs.push_back(exe.parent_path().parent_path() / "lib" / "csgtile");
  }
#ifdef CSGTILE_BUILD_MODULE_DIR
  dirs.emplace_back(CSGTILE_BUILD_MODULE_DIR);
#endif
  return dirs;
}

struct GdalModule {
  CsgtileGdalReadFootprints* read = nullptr;
  std::string error;  ///< why it could not be loaded (read is null)
};

/// Loads the module: the first directory holding its file decides (a module that is there
/// but does not load, e.g. because libgdal is missing, is an error, not skipped).
GdalModule load_module() {
  GdalModule m;
  std::string looked;
  for (const fs::path& dir : module_dirs()) {
    const fs::path file = dir / kGdalModuleFile;
    looked += (looked.empty() ? "" : ", ") + dir.string();
    std::error_code ec;
    if (!fs::is_regular_file(file, ec)) continue;
    // The module stays loaded for the life of the process (GDAL keeps its drivers and
    // caches); its symbols stay local to it.
    void* handle = dlopen(file.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (handle == nullptr) {
      const char* why = dlerror();
      m.error = "the GDAL module " + file.string() +
                " does not load: " + (why != nullptr ? why : "no reason given");
      return m;
    }
    auto* abi = reinterpret_cast<CsgtileGdalModuleAbi*>(dlsym(handle, "csgtile_gdal_module_abi"));
    auto* read =
        reinterpret_cast<CsgtileGdalReadFootprints*>(dlsym(handle, "csgtile_gdal_read_footprints"));
    if (abi == nullptr || read == nullptr) {
      m.error = "the GDAL module " + file.string() + " lacks its entry points";
      return m;
    }
    if (abi() != kGdalModuleAbi) {
      m.error = "the GDAL module " + file.string() + " was built for another csgtile (ABI " +
                std::to_string(abi()) + ", this binary " + std::to_string(kGdalModuleAbi) + ")";
      return m;
    }
    m.read = read;
    return m;
  }
  m.error = std::string("the GDAL module ") + kGdalModuleFile + " is not installed (looked in " +
            (looked.empty() ? std::string("no directory") : looked) +
            "; CSGTILE_MODULE_DIR names its directory)";
  return m;
}

const GdalModule& gdal_module() {
  static std::once_flag once;
  static GdalModule module;
  std::call_once(once, [] { module = load_module(); });
  return module;
}

}  // namespace

kernel::Result<FootprintSet> read_footprints(const FootprintSource& source,
                                             const FootprintQuery& query) {
  const GdalModule& module = gdal_module();
  if (module.read == nullptr) {
    return kernel::Error{kernel::ErrorCode::Unsupported,
                         "footprints " + source.source + ": " + module.error};
  }
  kernel::Result<FootprintSet> out = kernel::Error{kernel::ErrorCode::IoError, "not read"};
  module.read(source, query, out);
  return out;
}

}  // namespace csgtile::geo
