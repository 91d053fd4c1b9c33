// COPC info VLR and hierarchy pages (see csgtile/geo/copc.h).

#include "csgtile/geo/copc.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <set>
#include <utility>

#include "io/endian.h"

namespace csgtile::geo {

namespace {

using kernel::Error;
using kernel::ErrorCode;

constexpr std::size_t kInfoSize = 160;
constexpr std::size_t kEntrySize = 32;
constexpr int kMaxDepth = 30;               // cells of 2^-30 of the root: far below any scale
constexpr std::size_t kMaxPages = 1 << 20;  // a hostile file cannot make us loop for ever

Error corrupt(const std::string& name, const std::string& what) {
  return Error{ErrorCode::CorruptData, name + ": COPC " + what};
}

std::string key_text(std::int32_t d, std::int32_t x, std::int32_t y, std::int32_t z) {
  return std::to_string(d) + "-" + std::to_string(x) + "-" + std::to_string(y) + "-" +
         std::to_string(z);
}

}  // namespace

kernel::Result<CopcInfo> parse_copc_info(std::span<const std::uint8_t> payload,
                                         std::uint64_t file_size, const std::string& name) {
  if (payload.size() < kInfoSize) {
    return corrupt(name, "info VLR holds " + std::to_string(payload.size()) + " bytes; it has 160");
  }
  using detail::load_le;
  CopcInfo info;
  const std::uint8_t* p = payload.data();
  for (int i = 0; i < 3; ++i) info.center[i] = load_le<double>(p + 8 * i);
  info.halfsize = load_le<double>(p + 24);
  info.spacing = load_le<double>(p + 32);
  info.root_hierarchy_offset = load_le<std::uint64_t>(p + 40);
  info.root_hierarchy_size = load_le<std::uint64_t>(p + 48);
  info.gpstime_minimum = load_le<double>(p + 56);
  info.gpstime_maximum = load_le<double>(p + 64);
  const bool finite = std::isfinite(info.center[0]) && std::isfinite(info.center[1]) &&
                      std::isfinite(info.center[2]) && std::isfinite(info.halfsize);
  if (!finite || !(info.halfsize > 0.0)) {
    return corrupt(name, "info VLR: the root cube (centre and half size " +
                             std::to_string(info.halfsize) + ") is not finite and positive");
  }
  if (info.root_hierarchy_size % kEntrySize != 0 || info.root_hierarchy_offset > file_size ||
      info.root_hierarchy_size > file_size - info.root_hierarchy_offset) {
    return corrupt(name, "info VLR: the root hierarchy page (offset " +
                             std::to_string(info.root_hierarchy_offset) + ", " +
                             std::to_string(info.root_hierarchy_size) +
                             " bytes) is not whole entries inside the file of " +
                             std::to_string(file_size) + " bytes");
  }
  return info;
}

kernel::Result<std::vector<CopcNode>> read_copc_hierarchy(ByteSource& source,
                                                          const CopcInfo& info) {
  using detail::load_le;
  const std::string& name = source.name();
  const std::uint64_t size = source.size();
  std::vector<CopcNode> nodes;
  std::deque<std::pair<std::uint64_t, std::uint64_t>> pages;  // offset, bytes
  std::set<std::uint64_t> seen;
  pages.emplace_back(info.root_hierarchy_offset, info.root_hierarchy_size);
  std::vector<std::uint8_t> page;
  while (!pages.empty()) {
    const auto [offset, bytes] = pages.front();
    pages.pop_front();
    if (!seen.insert(offset).second) {
      return corrupt(name, "hierarchy: the page at offset " + std::to_string(offset) +
                               " is referenced twice (a loop)");
    }
    if (seen.size() > kMaxPages) return corrupt(name, "hierarchy: more than 2^20 pages");
    page.resize(static_cast<std::size_t>(bytes));
    if (auto st = source.read_at(offset, page); !st.ok()) return st.error();
    for (std::size_t at = 0; at + kEntrySize <= page.size(); at += kEntrySize) {
      const std::uint8_t* e = page.data() + at;
      const auto d = load_le<std::int32_t>(e);
      const auto x = load_le<std::int32_t>(e + 4);
      const auto y = load_le<std::int32_t>(e + 8);
      const auto z = load_le<std::int32_t>(e + 12);
      const auto chunk_offset = load_le<std::uint64_t>(e + 16);
      const auto chunk_bytes = load_le<std::int32_t>(e + 24);
      const auto points = load_le<std::int32_t>(e + 28);
      const std::string where =
          "hierarchy page at " + std::to_string(offset) + ", node " + key_text(d, x, y, z);
      if (d < 0 || d > kMaxDepth) return corrupt(name, where + ": depth outside 0-30");
      const std::int64_t cells = std::int64_t{1} << d;
      if (x < 0 || y < 0 || z < 0 || x >= cells || y >= cells || z >= cells) {
        return corrupt(name, where + ": cell index outside its level");
      }
      if (chunk_bytes < 0 || chunk_offset > size ||
          static_cast<std::uint64_t>(chunk_bytes) > size - chunk_offset) {
        return corrupt(name, where + ": its data (offset " + std::to_string(chunk_offset) + ", " +
                                 std::to_string(chunk_bytes) + " bytes) is not inside the file");
      }
      if (points == -1) {  // a child page
        if (chunk_bytes % static_cast<std::int32_t>(kEntrySize) != 0) {
          return corrupt(name, where + ": child page size is not whole entries");
        }
        pages.emplace_back(chunk_offset, static_cast<std::uint64_t>(chunk_bytes));
        continue;
      }
      if (points < -1) return corrupt(name, where + ": point count " + std::to_string(points));
      if (points == 0) continue;
      if (chunk_bytes == 0) return corrupt(name, where + ": points but no data");
      CopcNode n;
      n.depth = d;
      n.x = x;
      n.y = y;
      n.z = z;
      n.offset = chunk_offset;
      n.bytes = static_cast<std::uint32_t>(chunk_bytes);
      n.points = static_cast<std::uint32_t>(points);
      const double side = 2.0 * info.halfsize / static_cast<double>(cells);
      const std::int32_t index[3] = {x, y, z};
      for (int i = 0; i < 3; ++i) {
        n.bounds.min[i] = info.center[i] - info.halfsize + side * index[i];
        n.bounds.max[i] = n.bounds.min[i] + side;
      }
      nodes.push_back(n);
    }
  }
  return nodes;
}

std::vector<CopcNode> select_copc_nodes(const std::vector<CopcNode>& nodes,
                                        const CopcQuery& query) {
  std::vector<CopcNode> out;
  for (const CopcNode& n : nodes) {
    if (query.max_depth >= 0 && n.depth > query.max_depth) continue;
    if (query.box) {
      const Bounds3& b = *query.box;
      bool meets = true;
      for (int i = 0; i < 3; ++i) {
        meets = meets && n.bounds.min[i] <= b.max[i] && b.min[i] <= n.bounds.max[i];
      }
      if (!meets) continue;
    }
    out.push_back(n);
  }
  std::sort(out.begin(), out.end(),
            [](const CopcNode& a, const CopcNode& b) { return a.offset < b.offset; });
  return out;
}

}  // namespace csgtile::geo
