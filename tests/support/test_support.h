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

}  // namespace csgtile::test
