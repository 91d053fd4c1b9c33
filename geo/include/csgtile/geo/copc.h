#pragma once
/// \file
/// COPC (Cloud Optimized Point Cloud, copc.io 1.0): a LAZ 1.4 file (point formats 6-8) whose
/// variable-size chunks are the nodes of an octree. The "copc" info VLR (record 1) gives the
/// root cube and where the hierarchy starts; the hierarchy (EVLR "copc", record 1000) is a
/// tree of pages whose entries name a node (depth, x, y, z), where its chunk lies and how
/// many points it holds, or where a child page lies.
///
/// A reader given a region (PointReadOptions::region, ::copc_max_depth) reads the hierarchy
/// pages and only the chunks of the nodes that meet the region: over HTTP range requests
/// (a ByteSource from the worker) that is what gets fetched, not the file.

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "csgtile/geo/byte_source.h"
#include "csgtile/geo/point.h"
#include "csgtile/kernel/result.h"

namespace csgtile::geo {

/// The COPC info VLR (160 bytes).
struct CopcInfo {
  std::array<double, 3> center{0.0, 0.0, 0.0};  ///< centre of the root cube
  double halfsize = 0.0;                        ///< half the root cube's side
  double spacing = 0.0;                         ///< point spacing at the root
  std::uint64_t root_hierarchy_offset = 0;
  std::uint64_t root_hierarchy_size = 0;
  double gpstime_minimum = 0.0;
  double gpstime_maximum = 0.0;
};

/// One node of the octree that holds points.
struct CopcNode {
  std::int32_t depth = 0, x = 0, y = 0, z = 0;  ///< key: level and cell index at that level
  std::uint64_t offset = 0;                     ///< its chunk's first byte
  std::uint32_t bytes = 0;                      ///< its chunk's size
  std::uint32_t points = 0;
  Bounds3 bounds;  ///< the node's cube
};

/// Which nodes to read: those meeting `box` (all when unset) down to `max_depth` (-1: all).
struct CopcQuery {
  std::optional<Bounds3> box;
  int max_depth = -1;
};

/// Parses the info VLR's payload. Errors: CorruptData naming `name` (size, non-finite or
/// non-positive cube, hierarchy outside a file of `file_size` bytes).
kernel::Result<CopcInfo> parse_copc_info(std::span<const std::uint8_t> payload,
                                         std::uint64_t file_size, const std::string& name);

/// Reads every hierarchy page from `source` (page by page: over HTTP each is one range
/// request) and returns the nodes holding points, in page order. Checks: page sizes are
/// whole entries inside the file, keys are inside their level, no page is read twice (a loop),
/// node chunks lie inside the file. Errors: CorruptData naming the file and the page or node.
kernel::Result<std::vector<CopcNode>> read_copc_hierarchy(ByteSource& source, const CopcInfo& info);

/// The nodes meeting the query, sorted by chunk offset (file order).
std::vector<CopcNode> select_copc_nodes(const std::vector<CopcNode>& nodes, const CopcQuery& query);

}  // namespace csgtile::geo
