// Loading csgtile's own modules (csgtile/kernel/module.h).

#include "csgtile/kernel/module.h"

#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
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

Module open_module(const std::string& file, const std::string& abi) {
  Module m;
  std::string looked;
  for (const fs::path& dir : module_dirs()) {
    const fs::path path = dir / file;
    looked += (looked.empty() ? "" : ", ") + dir.string();
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) continue;
    m.path = path.string();
    // Every symbol bound now: a library lacking one is this error, not a crash at its first
    // call. Loaded for the life of the process; its symbols stay local to it.
    void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (handle == nullptr) {
      const char* why = dlerror();
      m.error = "the module " + m.path + " does not load: " + (why != nullptr ? why : "no reason");
      return m;
    }
    using Abi = const char*();
    auto* built = reinterpret_cast<Abi*>(dlsym(handle, "csgtile_module_abi"));
    const char* got = built != nullptr ? built() : nullptr;
    if (got == nullptr || abi != got) {
      m.error = got == nullptr ? "the module " + m.path + " is not a csgtile module"
                               : "the module " + m.path +
                                     " was built from other sources than this binary (ABI " + got +
                                     ", this binary " + abi + ")";
      dlclose(handle);
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

struct Entry {
  std::once_flag once;
  Module module;
};

}  // namespace

const Module& load_module(const std::string& file, const std::string& abi) {
  static std::mutex mutex;
  static std::map<std::string, std::unique_ptr<Entry>> entries;  // entries never move or go
  Entry* entry = nullptr;
  {
    const std::lock_guard<std::mutex> lock(mutex);
    auto& slot = entries[file];
    if (!slot) slot = std::make_unique<Entry>();
    entry = slot.get();
  }
  // Each module once, outside the lock: two modules load concurrently.
  std::call_once(entry->once, [&] { entry->module = open_module(file, abi); });
  return entry->module;
}

std::jthread load_module_in_background(const std::string& file, const std::string& abi) {
  // A thread that cannot be started, or a load that throws (memory), leaves the loading to
  // the first load_module.
  try {
    return std::jthread([file, abi] {
      try {
        (void)load_module(file, abi);
      } catch (...) {
        // load_module is called again where the module is used
      }
    });
  } catch (...) {
    return {};
  }
}

void* module_symbol(const Module& module, const char* name) {
  return module.handle != nullptr ? dlsym(module.handle, name) : nullptr;
}

}  // namespace csgtile::kernel
