#pragma once
/// \file
/// A minimal glTF 2.0 binary (GLB) writer for 3D Tiles content: one mesh with one triangle
/// primitive whose vertices carry a feature id (EXT_mesh_features) into one property table
/// (EXT_structural_metadata).
///
/// Layout: a 12-byte header ("glTF", version 2, total length), a JSON chunk padded with
/// spaces and a BIN chunk padded with zeros, each a multiple of 4 bytes; all integers and
/// floats little-endian whatever the host. One buffer (the BIN chunk); buffer views start at
/// multiples of 8 (EXT_structural_metadata asks 8-byte alignment for its columns): positions,
/// normals, feature ids, indices, then the table's columns in order (strings: values then
/// offsets). One scene with one node holding the mesh, without a matrix; one opaque grey
/// material.
///
/// Internal API of the worker (exporters); not installed.

#include <array>
#include <cstdint>
#include <string>
#include <variant>
#include <vector>

#include "csgtile/worker/errors.h"

namespace csgtile::worker {

/// The triangles of one primitive in glTF's frame (y up, metres), vertices not shared
/// between faces that meet at an angle (each vertex has one normal).
struct GltfMesh {
  std::vector<std::array<float, 3>> positions;
  std::vector<std::array<float, 3>> normals;  ///< unit length, one per position
  /// Per position: the row of the property table it belongs to (_FEATURE_ID_0, stored as
  /// float32, exact below 2^24).
  std::vector<std::uint32_t> feature_ids;
  /// Three per triangle, counter-clockwise seen from outside.
  std::vector<std::uint32_t> indices;
};

/// One property of the table's class with one value per row. The value type picks the
/// metadata type: STRING, SCALAR FLOAT64, SCALAR UINT32, BOOLEAN.
struct PropertyColumn {
  std::string name;  ///< property id: [a-zA-Z_][a-zA-Z0-9_]*
  std::string description;
  std::variant<std::vector<std::string>, std::vector<double>, std::vector<std::uint32_t>,
               std::vector<bool>>
      values;
};

/// The property table of the features (EXT_structural_metadata), one row per feature id.
struct PropertyTable {
  std::string schema_id = "csgtile";
  std::string class_name = "object";
  std::string class_description;
  std::size_t count = 0;  ///< rows; every column has this many values
  std::vector<PropertyColumn> columns;
};

struct GltfOptions {
  std::string generator = "csgtile";
  std::array<double, 4> base_color = {0.8, 0.8, 0.8, 1.0};  ///< linear RGBA in [0, 1]
};

/// The GLB bytes of `mesh` with `table`. POSITION gets its min/max (exactly the float32
/// values stored); feature ids index the table's rows (featureCount = table.count).
/// Keys in a fixed order, numbers in their shortest round-trip form: the same input gives
/// the same bytes. Error: InputInvalid (an empty mesh or table, sizes that disagree, an
/// index or feature id out of range, a non-finite position or normal, a bad property name,
/// a table of 2^24 rows or more, more than 4 GiB of data).
Result<std::string> glb_bytes(const GltfMesh& mesh, const PropertyTable& table,
                              const GltfOptions& options = {});

}  // namespace csgtile::worker
