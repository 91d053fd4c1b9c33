#pragma once
/// \file
/// Points of a point cloud as every reader yields them (LAS, PLY, PCD, XYZ text), batches of
/// points, and the extra per-point dimensions a file may carry beyond the standard fields
/// (LAS "extra bytes", unrecognised PLY properties, PCD fields and XYZ columns).

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace csgtile::geo {

/// Axis-aligned bounds in file coordinates; empty until a point is added.
struct Bounds3 {
  std::array<double, 3> min{std::numeric_limits<double>::infinity(),
                            std::numeric_limits<double>::infinity(),
                            std::numeric_limits<double>::infinity()};
  std::array<double, 3> max{-std::numeric_limits<double>::infinity(),
                            -std::numeric_limits<double>::infinity(),
                            -std::numeric_limits<double>::infinity()};

  bool empty() const { return !(min[0] <= max[0]); }
  void add(double x, double y, double z);
  void add(const Bounds3& other);
  /// True when (x, y, z) lies inside, each axis widened by `tolerance[axis]`.
  bool contains(double x, double y, double z, const std::array<double, 3>& tolerance) const;
};

/// Bits of Point::classification_flags, with the LAS 1.4 meanings. Point formats 0-5 carry
/// the first three in the top bits of the classification byte; formats 6-10 all four.
inline constexpr std::uint8_t kFlagSynthetic = 1;
inline constexpr std::uint8_t kFlagKeyPoint = 2;
inline constexpr std::uint8_t kFlagWithheld = 4;
inline constexpr std::uint8_t kFlagOverlap = 8;

/// One point. Fields a source does not carry keep their defaults; PointCloudInfo::fields says
/// which ones a reader fills. Plain value of 72 bytes.
struct Point {
  double x = 0, y = 0, z = 0;  ///< coordinates in file units, LAS scale and offset applied
  double gps_time = 0;         ///< LAS GPS time (week seconds or adjusted standard, see header)
  std::array<float, 3> normal{0.0F, 0.0F, 0.0F};  ///< PLY/PCD normals; zero when absent
  float scan_angle = 0;  ///< degrees, negative left of nadir (LAS rank or 0.006° steps)
  std::uint16_t intensity = 0;
  std::uint16_t red = 0, green = 0, blue = 0;  ///< 16-bit range; 8-bit sources are scaled ×257
  std::uint16_t nir = 0;                       ///< near infrared (LAS formats 8 and 10)
  std::uint16_t point_source_id = 0;
  std::uint8_t return_number = 0;         ///< 1-based; 0-7 in formats 0-5, 0-15 in 6-10
  std::uint8_t number_of_returns = 0;     ///< returns of the pulse
  std::uint8_t classification = 0;        ///< ASPRS class: 0-31 in formats 0-5, 0-255 in 6-10
  std::uint8_t classification_flags = 0;  ///< kFlag* bits
  std::uint8_t scanner_channel = 0;       ///< 0-3 (formats 6-10)
  std::uint8_t user_data = 0;
  bool scan_direction = false;       ///< scan direction flag (positive direction when set)
  bool edge_of_flight_line = false;  ///< the last point of a scan line
};

/// Storage type of an extra dimension. Raw: undocumented bytes (LAS data type 0).
enum class ExtraType : std::uint8_t { Raw, U8, I8, U16, I16, U32, I32, U64, I64, F32, F64 };

/// Bytes of one element of `type` (1 for Raw).
std::size_t extra_type_size(ExtraType type);
/// Short name: "raw", "uint8", "int8", ..., "float32", "float64".
const char* extra_type_name(ExtraType type);

/// One extra per-point dimension. For LAS it comes from an "Extra Bytes" descriptor (VLR
/// LASF_Spec 4, LAS 1.4 R15 §2.6); other readers describe their unmapped fields the same way.
struct ExtraDimension {
  std::string name;
  std::string description;
  ExtraType type = ExtraType::Raw;
  int elements = 1;             ///< 1-3 values (LAS deprecated array types); Raw: byte count
  std::size_t byte_offset = 0;  ///< position inside a point's extra bytes
  std::optional<double> scale;  ///< value = raw × scale + offset, when given
  std::optional<double> offset;
  std::optional<double> no_data;  ///< first element's values as the descriptor gives them
  std::optional<double> minimum;
  std::optional<double> maximum;

  /// Bytes this dimension occupies in each point.
  std::size_t size() const { return extra_type_size(type) * static_cast<std::size_t>(elements); }
};

/// The extra bytes of every point of a file: `record_size` bytes per point, partly or wholly
/// described by `dimensions` (non-overlapping, in record order). Bytes no dimension covers
/// stay available raw.
struct ExtraLayout {
  std::size_t record_size = 0;
  std::vector<ExtraDimension> dimensions;

  /// The dimension called `name` (exact match), or nullptr.
  const ExtraDimension* find(std::string_view name) const;
  /// Bytes covered by no dimension.
  std::size_t undescribed_bytes() const;
};

/// A raw extra value: signed and unsigned integers keep their full 64 bits.
using ExtraValue = std::variant<std::int64_t, std::uint64_t, double>;

/// Decodes element `element` of `dimension` from one point's extra bytes (little-endian, as
/// LAS stores them). nullopt for Raw dimensions, a bad element, or too few bytes.
std::optional<ExtraValue> decode_extra(const ExtraDimension& dimension,
                                       std::span<const std::uint8_t> point_extra, int element = 0);
/// As decode_extra, converted to double with the dimension's scale and offset applied.
std::optional<double> decode_extra_scaled(const ExtraDimension& dimension,
                                          std::span<const std::uint8_t> point_extra,
                                          int element = 0);

/// Points read in one call, with their extra bytes side by side (`layout->record_size` bytes
/// per point, in point order). Readers replace the contents on every read.
struct PointBatch {
  std::vector<Point> points;
  std::vector<std::uint8_t> extra_bytes;
  std::shared_ptr<const ExtraLayout> layout;  ///< null when the source has no extra bytes

  std::size_t size() const { return points.size(); }
  bool empty() const { return points.empty(); }
  /// Removes the points, keeps the layout and the capacity.
  void clear() {
    points.clear();
    extra_bytes.clear();
  }
  std::size_t extra_record_size() const { return layout ? layout->record_size : 0; }
  /// The extra bytes of point `index` (empty without a layout).
  std::span<const std::uint8_t> extra(std::size_t index) const;
  /// Appends a point; `extra` must be empty (zero-filled) or extra_record_size() bytes.
  void append(const Point& point, std::span<const std::uint8_t> extra = {});

  /// Value of extra dimension `name` of point `index`, scaled; nullopt when absent.
  std::optional<double> extra_value(std::size_t index, std::string_view name,
                                    int element = 0) const;
  /// Raw value of extra dimension `name` of point `index`; nullopt when absent.
  std::optional<ExtraValue> extra_raw(std::size_t index, std::string_view name,
                                      int element = 0) const;
};

}  // namespace csgtile::geo
