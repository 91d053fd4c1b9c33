#pragma once
/// \file
/// The scene / case exchange format (../shared/spec/scene-format.md): sets of primitives,
/// an optional Boolean operation, and expected results.

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "csgtile/kernel/primitives.h"

namespace csgtile::geo {

/// `op` of a scene. None: the primitives are a set.
enum class BooleanOp { None, Fuse, Common, Cut };
const char* boolean_op_name(BooleanOp op);  ///< "", "fuse", "common", "cut"

/// Fit quality carried by fitted primitives.
struct FitQuality {
  long long inliers = 0;
  double rms = 0.0;
  double coverage = 0.0;
};

struct ScenePrimitive {
  kernel::PrimitiveSpec spec;
  std::string id;                     ///< may be empty
  std::optional<FitQuality> quality;
};

/// Counts of distinct sub-shapes; -1 where the scene does not give one.
struct TopologyCounts {
  long long solids = -1, shells = -1, faces = -1, edges = -1, vertices = -1;
};

struct SceneExpectation {
  std::optional<double> volume;
  std::optional<double> area;
  std::optional<TopologyCounts> topology;
};

struct Scene {
  std::string name;
  BooleanOp op = BooleanOp::None;
  std::vector<ScenePrimitive> primitives;
  std::optional<SceneExpectation> expected;
};

/// Parses scene JSON. Unknown keys are ignored; a missing or invalid required key is an
/// InvalidArgument error naming the primitive (index, type and id) and the key.
kernel::Result<Scene> parse_scene(std::string_view json);

/// Reads and parses a scene file. Errors: IoError (cannot read), then as parse_scene.
kernel::Result<Scene> read_scene(const std::filesystem::path& path);

}  // namespace csgtile::geo
