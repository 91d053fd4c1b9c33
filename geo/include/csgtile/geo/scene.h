#pragma once
/// \file
/// The scene / case exchange format (../shared/spec/scene-format.md): sets of primitives,
/// an optional Boolean operation, and expected results.

#include <array>
#include <cstdint>
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
  /// σ (m): the noise of the region's scan where it is flattest (fit's estimate_noise); absent
  /// when the region has too few points to tell.
  std::optional<double> sigma;
  std::optional<double> within_2sigma;  ///< share of its points within 2σ of its solid
};

struct ScenePrimitive {
  kernel::PrimitiveSpec spec;
  std::string id;  ///< may be empty
  std::optional<FitQuality> quality;
  /// The building it was fitted for (key "building", an extension): the id of its footprint
  /// (geo/footprints.h). Primitives of different buildings are never fused into one object;
  /// "" (the key absent): no footprint.
  std::string building{};
  /// Without a footprint, the house of its block it was fitted for (key "house", an
  /// extension; fit: PrimitiveOptions::split_houses), unique within its scene: primitives of
  /// different houses are never fused into one object either. "" (the key absent): none.
  std::string house{};
};

/// The assembly group of a primitive (primitives of different groups are never one object):
/// "footprint " + its building, else "house " + `scope` + "/" + its house (`scope`: what makes
/// house names unique when several scenes are assembled together, e.g. the tile), else "".
std::string assembly_group(const ScenePrimitive& p, std::string_view scope = {});

/// Counts of distinct sub-shapes; -1 where the scene does not give one.
struct TopologyCounts {
  long long solids = -1, shells = -1, faces = -1, edges = -1, vertices = -1;
};

struct SceneExpectation {
  std::optional<double> volume;
  std::optional<double> area;
  std::optional<TopologyCounts> topology;
};

/// Where a scene's coordinates sit in the world: p_crs = origin + p_local. Written and read as
/// the top-level keys "crs" and "origin", a csgtile extension that other readers of the
/// format ignore (unknown keys are ignored).
struct SceneFrame {
  std::string crs;                 ///< as crs_from_config reads it, e.g. "EPSG:28992+5709"
  std::array<double, 3> origin{};  ///< in the CRS's units
};

struct Scene {
  std::string name;
  BooleanOp op = BooleanOp::None;
  std::vector<ScenePrimitive> primitives;
  std::optional<SceneExpectation> expected;
  std::optional<SceneFrame> frame;    ///< keys "crs" and "origin" (extension, see SceneFrame)
  std::optional<std::uint64_t> seed;  ///< key "seed": the seed of a generated scene (extension)
};

/// Parses scene JSON. Unknown keys are ignored; a missing or invalid required key is an
/// InvalidArgument error naming the primitive (index, type and id) and the key.
kernel::Result<Scene> parse_scene(std::string_view json);

/// Scene JSON that parse_scene reads back to an equal scene: numbers in their shortest
/// round-trip form, keys in a fixed order (name, op, crs, origin, seed, primitives, expected;
/// per primitive: type, id, parameters, placement, quality, building, house), one primitive per
/// line. Same scene, same bytes. Placements are written as 3×4 matrices [s·R | t]; parse_scene
/// re-orthonormalises R, so a general rotation may move in its last bits when read back.
std::string scene_to_json(const Scene& scene);

/// A primitive's fit quality as the scene format writes it (its "quality" object, compact),
/// for other records that carry it (a cell's assembly.json); parse_fit_quality reads it back
/// (absent keys stay at their defaults). Error: InvalidArgument when `json` is no object.
std::string fit_quality_to_json(const FitQuality& quality);
kernel::Result<FitQuality> parse_fit_quality(std::string_view json);

/// Reads and parses a scene file. Errors: IoError (cannot read), then as parse_scene.
kernel::Result<Scene> read_scene(const std::filesystem::path& path);

}  // namespace csgtile::geo
