#pragma once
/// \file
/// One streaming interface over every point-cloud input: LAS (las.h), PLY, PCD and XYZ text.
/// Readers yield batches of at most N points and keep their memory bounded by the batch size,
/// whatever the size of the file (one exception, documented at PointFileFormat::Pcd).

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "csgtile/geo/point.h"
#include "csgtile/kernel/result.h"

namespace csgtile::geo {

/// Formats open_point_file understands.
enum class PointFileFormat {
  Las,  ///< ASPRS LAS 1.0-1.4, LAZ (LASzip compressors 1-3) and COPC
  Ply,  ///< PLY ascii / binary_little_endian / binary_big_endian, element "vertex"
  Pcd,  ///< PCL PCD 0.5-0.7, DATA ascii / binary / binary_compressed. binary_compressed is one
        ///< LZF block stored field by field, so it is decoded whole (memory ≈ its uncompressed
        ///< size, which is checked against the header and the file before allocation)
  Xyz,  ///< whitespace- or comma-separated text "x y z [more columns]", '#' comments
};
/// "las", "ply", "pcd", "xyz".
const char* point_file_format_name(PointFileFormat format);

/// Which Point fields a reader fills; the others keep their defaults.
struct PointFields {
  bool intensity = false;
  bool returns = false;  ///< return number and number of returns
  bool classification = false;
  bool scan_angle = false;
  bool user_data = false;
  bool point_source_id = false;
  bool gps_time = false;
  bool color = false;
  bool nir = false;
  bool normals = false;
};

/// Choices of how strictly to read.
struct PointReadOptions {
  /// A file holding fewer point records than its header declares fails by default (the job
  /// must not silently lose points). When set, the complete records are read and a warning
  /// names the declared and the actual counts.
  bool accept_truncated = false;
  /// Points whose x, y or z is NaN or infinite (holes of organised PCD clouds) are dropped
  /// and counted in one warning. When unset they are passed on.
  bool skip_non_finite = true;
  /// When false, LAZ of point formats 6-10 decodes only what fitting needs: coordinates,
  /// return numbers, scanner channel and classification. Its other attributes (intensity,
  /// flags, scan angle, user data, point source, GPS time, colour, NIR, wave packets, extra
  /// bytes) are left undecoded and hold their chunk's first point's values. Other formats
  /// always decode everything.
  bool all_attributes = true;
  /// Only the points inside this box (CRS coordinates, bounds inclusive) are returned. COPC
  /// files read only the chunks of the octree nodes that meet it (csgtile/geo/copc.h); other
  /// files are read whole and the points outside are dropped.
  std::optional<Bounds3> region;
  /// COPC only: the deepest octree level read (0: the root node alone); -1 reads every level.
  int copc_max_depth = -1;
};

/// What a reader knows before reading points.
struct PointCloudInfo {
  PointFileFormat format = PointFileFormat::Las;
  std::string description;                   ///< e.g. "LAS 1.4 point format 6", "PCD binary"
  std::optional<std::uint64_t> point_count;  ///< records the header declares (XYZ: none)
  std::optional<Bounds3> bounds;             ///< bounds the header declares (LAS only)
  /// Points outside `bounds` widened by this much per axis give a warning (LAS: half a
  /// scale step plus rounding of the header's doubles).
  std::array<double, 3> bounds_tolerance{0.0, 0.0, 0.0};
  PointFields fields;
  std::shared_ptr<const ExtraLayout> extra;  ///< null when points carry no extra bytes
};

/// A source of points. Not thread-safe; one reader per thread.
///
/// Reading: call read() until it returns 0. Each call replaces the batch's contents with the
/// next points of the file in file order. Errors are final: a reader that returned an error
/// returns it again. Warnings (points outside the header bounds, dropped non-finite points,
/// float32 precision, ...) collect in warnings(); summaries are added when the end is reached.
class PointReader {
 public:
  virtual ~PointReader() = default;
  PointReader(const PointReader&) = delete;
  PointReader& operator=(const PointReader&) = delete;

  const PointCloudInfo& info() const { return info_; }
  /// The file's name as given to open (used in every message).
  const std::string& name() const { return name_; }

  /// Replaces `batch` with up to `max` (≥ 1) next points; returns how many (0: the end).
  /// Memory: O(max) beyond what the reader holds after opening. Errors: CorruptData
  /// (malformed or truncated data, naming the file and what is wrong), IoError.
  kernel::Result<std::size_t> read(PointBatch& batch, std::size_t max);

  const std::vector<std::string>& warnings() const { return warnings_; }
  /// Points returned so far.
  std::uint64_t points_read() const { return points_read_; }
  /// Bounds of the points returned so far (the "scanned" bounds once the end is reached).
  const Bounds3& bounds_read() const { return bounds_read_; }
  /// True after read() returned 0.
  bool at_end() const { return at_end_; }

 protected:
  PointReader(std::string name, PointCloudInfo info, PointReadOptions options);

  /// Sets `batch` (layout already set; points and extra bytes hold stale data of an earlier
  /// read) to exactly the next up-to-`max` records; 0 at the end of the data.
  virtual kernel::Result<std::size_t> read_records(PointBatch& batch, std::size_t max) = 0;
  /// Called once when the end is reached, to add summary warnings.
  virtual void finish() {}

  void warn(std::string message);
  const PointReadOptions& options() const { return options_; }
  PointCloudInfo& mutable_info() { return info_; }

 private:
  void finish_reading();

  std::string name_;
  PointCloudInfo info_;
  PointReadOptions options_;
  std::vector<std::string> warnings_;
  std::optional<kernel::Error> failed_;
  std::uint64_t points_read_ = 0;
  std::uint64_t non_finite_ = 0;
  std::uint64_t outside_bounds_ = 0;
  std::optional<Point> first_outside_;
  Bounds3 bounds_read_;
  bool at_end_ = false;
};

/// The format of `path` from its first bytes ("LASF", "ply", a PCD header keyword) or, for
/// text, its extension (.xyz .txt .csv .pts .asc; .laz/.copc.laz give Las).
/// Errors: IoError (cannot open), Unsupported (not a point-cloud format known here).
kernel::Result<PointFileFormat> detect_point_format(const std::filesystem::path& path);

/// Opens a point-cloud file of any supported format, checking its header against the file.
/// Errors: IoError (cannot open or read), CorruptData (malformed header, with the file, the
/// field and the values), Unsupported (unknown formats, unsupported features),
/// UnsupportedVersion (a LAS version after 1.4).
kernel::Result<std::unique_ptr<PointReader>> open_point_file(const std::filesystem::path& path,
                                                             const PointReadOptions& options = {});

/// As open_point_file, over bytes in memory (fetched data, fuzzing). `bytes` must outlive the
/// reader; `name` is used in messages and, when the bytes are text, to pick the format.
kernel::Result<std::unique_ptr<PointReader>> open_point_memory(
    std::string name, std::span<const std::uint8_t> bytes, const PointReadOptions& options = {});

}  // namespace csgtile::geo
