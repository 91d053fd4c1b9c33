#include "test_support.h"

#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

namespace csgtile::test {

std::filesystem::path source_dir() { return CSGTILE_SOURCE_DIR; }
std::filesystem::path shared_dir() {
  return std::filesystem::weakly_canonical(std::filesystem::path(CSGTILE_SHARED_DIR));
}
std::filesystem::path csgtile_binary() { return CSGTILE_BINARY; }

int property_scale() {
  const char* text = std::getenv("CSGTILE_PROPERTY_SCALE");
  if (text == nullptr) return 1;
  const int scale = std::atoi(text);
  return scale > 0 ? scale : 1;
}

std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

TempDir::TempDir(const std::string& prefix)
    : path_(std::filesystem::temp_directory_path() / (prefix + std::to_string(::getpid()))) {
  std::filesystem::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code ignored;
  std::filesystem::remove_all(path_, ignored);
}

}  // namespace csgtile::test
