// Loading csgtile's modules (csgtile/kernel/module.h): a module is found in the directory named
// by CSGTILE_MODULE_DIR, checked against the caller's ABI text and loaded once; one built for
// another ABI, a file that is no shared object, and a module that is not there are each named
// with what is wrong. (Each test loads its own file name: the loader remembers every file.)

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "csgtile/kernel/module.h"

namespace csgtile::kernel {
namespace {

namespace fs = std::filesystem;

// A fresh directory holding, as `name`, a copy of the test module (or `text` when given), and
// named by CSGTILE_MODULE_DIR.
fs::path module_dir(const std::string& test, const std::string& name, const char* text = nullptr) {
  fs::path dir = fs::temp_directory_path() / ("csgtile_module_test_" + test);
  fs::remove_all(dir);
  fs::create_directories(dir);
  if (text != nullptr) {
    std::ofstream(dir / name) << text;
  } else if (!name.empty()) {
    fs::copy_file(fs::path(CSGTILE_TEST_MODULE), dir / name);
  }
  // The tests run on one thread: nothing reads the environment meanwhile.
  setenv("CSGTILE_MODULE_DIR", dir.c_str(), 1);  // NOLINT(concurrency-mt-unsafe)
  return dir;
}

TEST(Modules, LoadsAModuleOnceAndFindsItsSymbols) {
  const fs::path dir = module_dir("loads", "libcsgtile_test_a.so");
  const Module& m = load_module("libcsgtile_test_a.so", "test-abi");
  ASSERT_NE(m.handle, nullptr) << m.error;
  EXPECT_TRUE(m.error.empty());
  EXPECT_EQ(m.path, (dir / "libcsgtile_test_a.so").string());
  using Answer = int();
  auto* answer = reinterpret_cast<Answer*>(module_symbol(m, "csgtile_test_answer"));
  ASSERT_NE(answer, nullptr);
  EXPECT_EQ(answer(), 42);
  EXPECT_EQ(module_symbol(m, "no_such_symbol"), nullptr);
  EXPECT_EQ(&load_module("libcsgtile_test_a.so", "test-abi"), &m);
}

TEST(Modules, RefusesAModuleBuiltFromOtherHeaders) {
  module_dir("abi", "libcsgtile_test_b.so");
  const Module& m = load_module("libcsgtile_test_b.so", "this-abi");
  EXPECT_EQ(m.handle, nullptr);
  EXPECT_NE(m.error.find("was built from other sources than this binary (ABI test-abi, this "
                         "binary this-abi)"),
            std::string::npos)
      << m.error;
  EXPECT_EQ(module_symbol(m, "csgtile_test_answer"), nullptr);
}

TEST(Modules, NamesAFileThatDoesNotLoad) {
  const fs::path dir = module_dir("garbage", "libcsgtile_test_c.so", "not a shared object\n");
  const Module& m = load_module("libcsgtile_test_c.so", "test-abi");
  EXPECT_EQ(m.handle, nullptr);
  EXPECT_NE(
      m.error.find("the module " + (dir / "libcsgtile_test_c.so").string() + " does not load: "),
      std::string::npos)
      << m.error;
}

TEST(Modules, NamesAModuleThatIsNotInstalled) {
  const fs::path dir = module_dir("absent", "");
  const Module& m = load_module("libcsgtile_test_d.so", "test-abi");
  EXPECT_EQ(m.handle, nullptr);
  EXPECT_NE(m.error.find("the module libcsgtile_test_d.so is not installed (looked in " +
                         dir.string() + ";"),
            std::string::npos)
      << m.error;
}

}  // namespace
}  // namespace csgtile::kernel
