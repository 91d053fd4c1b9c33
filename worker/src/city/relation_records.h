#pragma once
// The relations of a cell's objects (party walls, overlaps) as its assemble job classified
// them, kept in the cell's record so that the run's index job takes them instead of running
// the same Booleans again (it classifies only pairs of objects in different cells).

#include <map>
#include <string>
#include <vector>

#include "city/city_internal.h"
#include "export/topology_index.h"

namespace csgtile::worker::city::detail {

/// The record of `relations` (indices into `objects`): [{"a": id, "b": id, "kind",
/// "shared_area", "common_volume", "reason"}, ...].
ordered_json relations_json(const std::vector<ObjectRelation>& relations,
                            const std::vector<IndexObject>& objects);

/// Appends the relations of a cell record's "relations" to `out`, with the objects' indices
/// from `index_of` (object id → index in the run), a < b (the kind turned for swapped ids).
/// `found` is false when the record has none (written before cells kept them). Error:
/// Internal for a malformed record or an unknown object id.
Failure read_relations(const ordered_json& record,
                       const std::map<std::string, std::size_t>& index_of,
                       std::vector<ObjectRelation>& out, bool& found);

}  // namespace csgtile::worker::city::detail
