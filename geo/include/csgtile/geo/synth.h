#pragma once
/// \file
/// Scan simulation (`csgtile synth`): scenes of known primitives, exact ray casting against
/// them, airborne strips and terrestrial stations with noise and outliers, written as LAS 1.4
/// with the ground truth in the scene format (../shared/spec/scene-format.md).
///
/// Frames. Scenes live in a tile-local frame: metres, x east, y north, z up, the ground the
/// plane z = 0. The LAS file stores `origin + local` with its offset equal to the origin; the
/// truth scene keeps the primitives in the local frame and records the origin and the CRS
/// (Scene::frame). So a truth primitive, placed by its placement, coincides with the LAS
/// points minus the LAS offset.
///
/// Classes (ASPRS): ground 2; building 6 (every primitive of the gate, the city block's
/// buildings and the random scene); unclassified 1 (the city block's free-standing objects:
/// ring sculpture, fountain); low noise 7 and high noise 18 (outliers).
///
/// Determinism. One std::mt19937_64 seeded with the seed drives everything through this
/// module's own uniform and normal transforms (the standard distributions differ between
/// standard libraries); the scan is single-threaded. Same options, same bytes.

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "csgtile/geo/point.h"
#include "csgtile/geo/scene.h"
#include "csgtile/kernel/bounding_box.h"
#include "csgtile/kernel/primitives.h"

namespace csgtile::geo {

inline constexpr std::uint8_t kClassUnclassified = 1;
inline constexpr std::uint8_t kClassGround = 2;
inline constexpr std::uint8_t kClassBuilding = 6;
inline constexpr std::uint8_t kClassLowNoise = 7;
inline constexpr std::uint8_t kClassHighNoise = 18;

/// A scene to scan: the truth primitives and the class their points get.
struct SynthScene {
  Scene scene;                        ///< name, seed, frame, primitives with ids
  std::vector<std::uint8_t> classes;  ///< per primitive: kClassBuilding or kClassUnclassified
  kernel::BoundingBox extent;         ///< of all primitives (local frame)
};

/// The scene names make_synth_scene knows: "gate", "city-block", "random".
const std::vector<std::string>& synth_scene_names();

/// Builds a named scene in the local frame, centred on the origin:
///  - gate: a timber pavilion gate, 81 cylinder columns (9 × 9, r 0.15 m, 4 m) and 148 box
///    beams (144 top beams between neighbouring columns, 4 corner braces); fixed layout.
///  - city-block: about 100 m × 100 m of buildings (boxes, L-shaped, courtyard and gabled
///    extrusions, a domed hall, towers with cone roofs, a colonnade), a ring sculpture
///    (torus) and a fountain (revolution); heights vary with the seed.
///  - random: `random_count` primitives of all seven types with random similarity
///    placements (rotation and scale) over 60 m × 60 m.
/// Errors: InvalidArgument for an unknown name (the message lists the valid ones) or
/// random_count outside [1, 100000].
kernel::Result<SynthScene> make_synth_scene(std::string_view name, std::uint64_t seed,
                                            int random_count = 40);

/// A ray's first crossing of a surface.
struct RayHit {
  double t = 0.0;                              ///< distance along the (unit) direction
  int primitive = -1;                          ///< index of the primitive hit; -1: the ground plane
  kernel::Vec3 normal = kernel::Vec3::Zero();  ///< unit normal, turned towards the origin
};

/// First crossing with t in (t_min, t_max] of the ray origin + t·direction (|direction| = 1)
/// with the boundary of the placed primitive, computed exactly up to rounding: hit points lie
/// on the surface to about 1e-12 of the primitive's size (the torus quartic is solved by root
/// isolation and polished). A ray starting inside returns where it leaves. Tangent rays may
/// or may not hit. `primitive` of the result is 0. Precondition: spec is valid
/// (build_primitive would succeed).
std::optional<RayHit> intersect_primitive(const kernel::PrimitiveSpec& spec,
                                          const kernel::Vec3& origin, const kernel::Vec3& direction,
                                          double t_min, double t_max);

/// True when `point` lies in the closed solid of the placed primitive.
bool primitive_contains(const kernel::PrimitiveSpec& spec, const kernel::Vec3& point);

/// First hits against many primitives and an optional ground plane, through a bounding
/// volume hierarchy over the primitives' bounds: O(log n) per ray for scattered scenes.
/// Immutable after construction; first_hit may be called from several threads.
class RayCaster {
 public:
  /// `ground_z`: the height of an infinite ground plane, hit from above only.
  explicit RayCaster(const std::vector<kernel::PrimitiveSpec>& primitives,
                     std::optional<double> ground_z = std::nullopt);
  ~RayCaster();
  RayCaster(RayCaster&&) noexcept;
  RayCaster& operator=(RayCaster&&) noexcept;

  /// The nearest hit with t in (0, t_max]; `primitive` is the index in the constructor's list.
  std::optional<RayHit> first_hit(const kernel::Vec3& origin, const kernel::Vec3& direction,
                                  double t_max) const;
  /// True when `point` lies inside a primitive (the ground is not a solid). Linear in the
  /// number of primitives: meant for a few checks, not for every ray.
  bool inside(const kernel::Vec3& point) const;
  std::size_t size() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

enum class ScanMode { Airborne, Terrestrial };
const char* scan_mode_name(ScanMode mode);  ///< "airborne", "terrestrial"

/// Everything `csgtile synth` can be told; defaults make a typical scan.
struct SynthOptions {
  std::string scene = "gate";
  ScanMode mode = ScanMode::Airborne;
  std::uint64_t points = 1000000;  ///< target number of returns (met within about 1 %)
  std::uint64_t seed = 1;
  int random_primitives = 40;       ///< primitives of the "random" scene
  double noise_sigma = 0.01;        ///< Gaussian range noise along the ray (m), >= 0
  double outlier_fraction = 0.001;  ///< share of pulses returning an outlier, in [0, 1]
  // Airborne: parallel strips flown along x over the scene extent grown by `margin`.
  double altitude = 500.0;       ///< flying height above the ground (m)
  double scan_angle_deg = 20.0;  ///< half field of view across the track, (0, 75]
  int strips = 2;                ///< at least this many strips (more when the swath is short)
  double margin = 10.0;          ///< ground scanned around the scene extent (m)
  // Terrestrial: stations on tripods, spherical scans, occlusion by the first hit.
  int stations = 5;                  ///< 1-64: corners around the scene first, then the middle
  double station_height = 1.8;       ///< scanner above the ground (m)
  double max_range = 120.0;          ///< returns farther away are lost (m)
  double min_elevation_deg = -60.0;  ///< lowest ray; the highest is the zenith
  // Output.
  std::string crs = "EPSG:28992+5709";  ///< RD New + NAP height, as crs_from_config reads it
  std::array<double, 3> origin{121500.0, 487000.0, 0.0};  ///< local (0,0,0) in the CRS
  std::uint8_t point_format = 7;  ///< 6 (no colour) or 7 (RGB by class, shaded)

  /// Checks ranges. Errors: InvalidArgument naming the option and its allowed range.
  kernel::Status validate() const;
};

/// Counts of a simulated scan.
struct SynthSummary {
  std::uint64_t points = 0;
  std::array<std::uint64_t, 256> points_per_class{};
  std::array<int, kernel::kPrimitiveTypeCount> primitives_per_type{};
  int passes = 0;  ///< strips (airborne) or stations (terrestrial)
  Bounds3 bounds;  ///< of the points, in CRS coordinates
};

/// Receives the simulated points in batches, in scan order. A failed status stops the scan.
using PointSink = std::function<kernel::Status(const PointBatch&)>;

/// Scans `scene` as `options` say. Points are in CRS coordinates (options.origin + local),
/// return 1 of 1, point source id = strip or station number (from 1), GPS time (adjusted
/// standard) increasing, scan angle in degrees (terrestrial: the ray's elevation), and carry
/// one extra dimension "truth_index" (int32: the index of the truth primitive hit, -1 for
/// the ground and outliers). Errors: those of validate(), then the sink's.
kernel::Result<SynthSummary> scan_scene(const SynthScene& scene, const SynthOptions& options,
                                        const PointSink& sink);

/// The extra-bytes layout of scan_scene's points.
std::shared_ptr<const ExtraLayout> synth_extra_layout();

/// make_synth_scene, scan_scene and the two files: `las_path` (LAS 1.4, options.point_format,
/// millimetre scale, offset at the origin, the CRS as OGC WKT) and `truth_path`
/// (scene_to_json of the scene, with frame and seed). The scan runs on the truth as it reads
/// back, so what was scanned is exactly what the file says. Each file is written to a
/// temporary name beside it and renamed when complete: a failure leaves neither half-written.
/// Errors: InvalidArgument (options, scene name), Unsupported (CRS), IoError.
kernel::Result<SynthSummary> synthesize(const SynthOptions& options,
                                        const std::filesystem::path& las_path,
                                        const std::filesystem::path& truth_path);

}  // namespace csgtile::geo
