#include "ops/memory.h"

#include <cmath>
#include <fstream>
#include <string>

namespace csgtile::worker::ops {

namespace {
// A "Key:   1234 kB" line of /proc/self/status, in bytes.
std::optional<std::uint64_t> status_bytes(const std::string& key) {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.compare(0, key.size(), key) != 0 || line.size() <= key.size() ||
        line[key.size()] != ':') {
      continue;
    }
    try {
      return std::stoull(line.substr(key.size() + 1)) * 1024;
    } catch (const std::exception&) {
      return std::nullopt;
    }
  }
  return std::nullopt;
}
}  // namespace

std::optional<std::uint64_t> resident_bytes() { return status_bytes("VmRSS"); }

std::optional<std::uint64_t> peak_resident_bytes() { return status_bytes("VmHWM"); }

std::optional<double> peak_resident_mib() {
  const auto peak = peak_resident_bytes();
  if (!peak) return std::nullopt;
  return std::round(static_cast<double>(*peak) / (1024.0 * 1024.0) * 10.0) / 10.0;
}

bool reset_peak_resident() {
  std::ofstream out("/proc/self/clear_refs");
  out << "5";
  out.flush();
  return out.good();
}

}  // namespace csgtile::worker::ops
