// Loading csgtile's own modules (csgtile/kernel/module.h).

#include "csgtile/kernel/module.h"

#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <map>
#include <mutex>
#include <vector>

namespace csgtile::kernel {

namespace {

namespace fs = std::filesystem;

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

Module open_module(const std::string& file, int abi) {
  Module m;
  std::string looked;
  for (const fs::path& dir : module_dirs()) {
    const fs::path path = dir / file;
    looked += (looked.empty() ? "" : ", ") + dir.string();
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) continue;
    m.path = path.string();
    // Loaded for the life of the process; its symbols stay local to it.
    void* handle = dlopen(path.c_str(), RTLD_LAZY | RTLD_LOCAL);
    if (handle == nullptr) {
      const char* why = dlerror();
      m.error = "the module " + m.path + " does not load: " + (why != nullptr ? why : "no reason");
      return m;
    }
    using Abi = int();
    auto* built = reinterpret_cast<Abi*>(dlsym(handle, "csgtile_module_abi"));
    if (built == nullptr) {
      m.error = "the module " + m.path + " is not a csgtile module (no csgtile_module_abi)";
      return m;
    }
    if (const int got = built(); got != abi) {
      m.error = "the module " + m.path + " was built for another csgtile (ABI " +
                std::to_string(got) + ", this binary " + std::to_string(abi) + ")";
      return m;
    }
    m.handle = handle;
    return m;
  }
  m.error = "the module " + file + " is not installed (looked in " +
            (looked.empty() ? std::string("no directory") : looked) +
            "; CSGTILE_MODULE_DIR names its directory)";
  return m;
}

}  // namespace

const Module& load_module(const std::string& file, int abi) {
  static std::mutex mutex;
  static std::map<std::string, Module> loaded;  // nodes are stable: references stay valid
  const std::lock_guard<std::mutex> lock(mutex);
  auto it = loaded.find(file);
  if (it == loaded.end()) it = loaded.emplace(file, open_module(file, abi)).first;
  return it->second;
}

void* module_symbol(const Module& module, const char* name) {
  return module.handle != nullptr ? dlsym(module.handle, name) : nullptr;
}

}  // namespace csgtile::kernel
