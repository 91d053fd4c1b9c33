#pragma once
/// \file
/// csgtile's own loadable modules: the parts that link heavy libraries (GDAL for footprints,
/// OpenVDB for the assembly's culling) are shared objects of their own, loaded on first use,
/// so that a process which never needs them does not pay for binding their symbols at start.
/// Every module exports `const char* csgtile_module_abi()`; the loader accepts it only when that
/// is the text the caller was built with (a hash of the headers both sides are built from).

#include <string>
#include <thread>

namespace csgtile::kernel {

/// A loaded module, or why it could not be loaded (`handle` null, `error` says).
struct Module {
  void* handle = nullptr;
  std::string path;   ///< the file loaded
  std::string error;  ///< empty when loaded
};

/// Loads the module file `file` (e.g. "libcsgtile_gdal.so") once per process: later calls
/// return the same record (a module that could not be loaded is not tried again). It is looked
/// for only in $CSGTILE_MODULE_DIR when that is set, else in the running binary's directory, in
/// ../lib/csgtile from it (an installed binary) and, in builds with tests, in the build tree
/// (tests run from their own directories); the first directory holding the file decides (a
/// module there that does not load, e.g. because a library it needs is missing, or that was
/// built from other headers, is an error, not skipped). Every symbol is bound at load time, so a
/// module that loads has all it calls. Thread-safe; modules load concurrently.
const Module& load_module(const std::string& file, const std::string& abi);

/// Loads a module as load_module does, on a thread of its own, so that a process about to need it
/// does other work meanwhile instead of waiting (binding a module's libraries takes about
/// 0.1 s). The thread joins when it goes out of scope; an empty thread when none can be started
/// (the first load_module then loads it).
std::jthread load_module_in_background(const std::string& file, const std::string& abi);

/// The address of `name` in a loaded module; null when absent or the module is not loaded.
void* module_symbol(const Module& module, const char* name);

/// The function `name` of a loaded module, of type F (e.g. `int(const char*)`); null as above.
template <class F>
F* module_function(const Module& module, const char* name) {
  return reinterpret_cast<F*>(module_symbol(module, name));
}

}  // namespace csgtile::kernel
