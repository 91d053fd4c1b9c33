#pragma once
// A building's heights and LoD1.2 / LoD1.3 blocks as the assemble job of its cell computed
// them (add_building_lods), kept in the cell's object record so that the index job reads them
// instead of computing every block a second time. The blocks are content-addressed native
// model files under objects/, like the objects' own models.

#include <filesystem>
#include <string>
#include <vector>

#include "city/city_internal.h"
#include "csgtile/kernel/location.h"
#include "export/topology_index.h"

namespace csgtile::worker::city::detail {

/// Adds `object`'s blocks to `batch` and returns their record: {"heights": {...} | null,
/// "lod12": key | null, "lod12_error", "lod13": key | null, "lod13_error"}.
Failure publish_blocks(const IndexObject& object, ObjectBatch& batch, ordered_json& record);

/// The keys of the block files an object record names (none when it has no blocks).
std::vector<std::string> block_keys(const ordered_json& entry);

/// Fills heights, lod12(_error) and lod13(_error) of `object` from an object record's
/// "blocks", each block moved by `by` as the object's model is. `found` is false (and the
/// object untouched) when the record has none (a record written before blocks were kept).
/// Errors: Io or a corrupt block file, naming it; Internal for a malformed record.
Failure read_blocks(const std::filesystem::path& run_dir, const ordered_json& entry,
                    const kernel::Location& by, IndexObject& object, bool& found);

}  // namespace csgtile::worker::city::detail
