#pragma once
/// \file
/// Helpers shared by the test suites: locating the source tree and ../shared.

#include <filesystem>
#include <string>

namespace csgtile::test {

/// The project's source directory.
std::filesystem::path source_dir();
/// `../shared` beside the checkout (cases, data, schemas). May not exist.
std::filesystem::path shared_dir();
/// The built csgtile executable.
std::filesystem::path csgtile_binary();
/// Reads a whole file; empty string when missing.
std::string read_file(const std::filesystem::path& path);

/// How many times the seeded property tests multiply their case counts: the environment's
/// CSGTILE_PROPERTY_SCALE (a positive integer; the optimised CI stage sets 10), else 1.
int property_scale();

/// A temporary directory `<tmp>/<prefix><pid>`, created on construction and removed with
/// everything in it on destruction.
class TempDir {
 public:
  explicit TempDir(const std::string& prefix);
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

}  // namespace csgtile::test
