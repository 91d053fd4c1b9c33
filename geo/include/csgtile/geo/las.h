#pragma once
/// \file
/// ASPRS LAS 1.0-1.4 (R15) reading and writing: header, VLRs and EVLRs, point formats 0-10,
/// extra bytes, and the raw CRS records (GeoTIFF keys, OGC WKT). Interpreting the CRS is
/// geo/crs.h's job; this header only hands over what the file says.
///
/// The reader streams: after open() it holds the header, the VLR/EVLR payloads it needs
/// (bounded) and one chunk buffer; points come in batches through PointReader::read().
/// Every header field that drives a read or an allocation is checked against the file size
/// before use, so a hostile header fails in microseconds with a message naming the file,
/// the field and the values. LAZ and COPC (compressed) files are decoded by geo's own LAZ
/// decoder.

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "csgtile/geo/byte_source.h"
#include "csgtile/geo/copc.h"
#include "csgtile/geo/crs.h"
#include "csgtile/geo/point.h"
#include "csgtile/geo/point_reader.h"
#include "csgtile/kernel/result.h"

namespace csgtile::geo {

/// The public header block, as stored (fields a version lacks stay zero).
struct LasHeader {
  std::uint8_t version_major = 1;
  std::uint8_t version_minor = 2;
  std::uint16_t file_source_id = 0;
  std::uint16_t global_encoding = 0;  ///< bit 0: adjusted standard GPS time; bit 4: WKT CRS
  std::array<std::uint8_t, 16> guid{};
  std::string system_identifier;
  std::string generating_software;
  std::uint16_t creation_day = 0;
  std::uint16_t creation_year = 0;
  std::uint16_t header_size = 0;
  std::uint32_t offset_to_point_data = 0;
  std::uint32_t vlr_count = 0;
  std::uint8_t point_format = 0;    ///< with the compression bits (6, 7) cleared
  std::uint16_t record_length = 0;  ///< bytes per point record, extra bytes included
  std::uint32_t legacy_point_count = 0;
  std::array<std::uint32_t, 5> legacy_points_by_return{};
  std::uint64_t point_count = 0;  ///< the count in force (1.4: 64-bit field, else legacy)
  std::array<std::uint64_t, 15> points_by_return{};  ///< 1.4 field, else the legacy five
  std::array<double, 3> scale{1.0, 1.0, 1.0};
  std::array<double, 3> offset{0.0, 0.0, 0.0};
  std::array<double, 3> min{0.0, 0.0, 0.0};
  std::array<double, 3> max{0.0, 0.0, 0.0};
  std::uint64_t waveform_data_start = 0;  ///< 1.3+
  std::uint64_t evlr_offset = 0;          ///< 1.4
  std::uint32_t evlr_count = 0;           ///< 1.4

  /// Record bytes beyond the point format's own fields.
  std::uint16_t extra_bytes_per_point() const;
};

/// A variable-length record (VLR) or extended VLR (EVLR).
struct LasRecord {
  std::string user_id;
  std::uint16_t record_id = 0;
  std::uint64_t length = 0;  ///< payload bytes the record declares
  std::string description;
  std::uint64_t payload_offset = 0;  ///< where the payload starts in the file
  bool extended = false;             ///< an EVLR
  /// The payload when loaded: VLRs (at most 64 KiB each) up to 64 MiB in total, EVLRs up to
  /// 16 MiB each and 64 MiB in total. Waveform data and other bulky records are described
  /// but not loaded.
  std::optional<std::vector<std::uint8_t>> data;
};

/// GeoTIFF key ids the CRS code asks for most (GeoTIFF 1.0 §6.2).
inline constexpr std::uint16_t kGeoKeyModelType = 1024;
inline constexpr std::uint16_t kGeoKeyCitation = 1026;
inline constexpr std::uint16_t kGeoKeyGeographicType = 2048;
inline constexpr std::uint16_t kGeoKeyGeogAngularUnits = 2054;
inline constexpr std::uint16_t kGeoKeyProjectedCsType = 3072;
inline constexpr std::uint16_t kGeoKeyProjection = 3074;
inline constexpr std::uint16_t kGeoKeyProjCoordTrans = 3075;
inline constexpr std::uint16_t kGeoKeyProjLinearUnits = 3076;
inline constexpr std::uint16_t kGeoKeyVerticalCsType = 4096;
inline constexpr std::uint16_t kGeoKeyVerticalUnits = 4099;
/// Value of a code key meaning "user-defined: see the other keys".
inline constexpr std::uint16_t kGeoKeyUserDefined = 32767;

/// One GeoKeyDirectory entry with its value resolved from the parameter records.
struct GeoKey {
  std::uint16_t id = 0;
  std::uint16_t location = 0;  ///< 0: inline short; 34736: doubles; 34737: ASCII
  std::uint16_t count = 0;
  std::uint16_t value_offset = 0;  ///< the short value (location 0) or the parameter index
  std::vector<double> doubles;     ///< location 34736, when in range
  std::string ascii;               ///< location 34737, when in range, without the '|' end mark

  /// The inline value of a location-0 key.
  std::optional<std::uint16_t> short_value() const {
    return location == 0 ? std::optional<std::uint16_t>(value_offset) : std::nullopt;
  }
};

/// The CRS records of a LAS file, raw (LAS 1.4 R15 §2.5): GeoTIFF keys (LASF_Projection
/// 34735 with 34736 doubles and 34737 ASCII) and OGC WKT (LASF_Projection 2112 in a VLR or
/// an EVLR). Codes are as stored: EPSG codes, or kGeoKeyUserDefined.
struct LasCrsRecords {
  bool has_geotiff = false;  ///< a GeoKeyDirectory record is present
  /// KeyDirectoryVersion, KeyRevision, MinorRevision.
  std::array<std::uint16_t, 3> geotiff_version{0, 0, 0};
  std::vector<GeoKey> keys;        ///< in file order; keys with id 0 are dropped (with a warning)
  std::optional<std::string> wkt;  ///< OGC WKT, NULs stripped; may be empty (see warnings)
  bool wkt_from_evlr = false;
  /// A copy of the WKT some writers (libLAS, old PDAL) store in a "liblas" 2112 VLR. Not
  /// part of the LAS standard; informative for pre-1.4 files.
  std::optional<std::string> liblas_wkt;
  bool wkt_flag = false;  ///< global encoding bit 4: the CRS is WKT (1.4)

  std::optional<std::uint16_t> model_type;     ///< 1024: 1 projected, 2 geographic, 3 geocentric
  std::optional<std::uint16_t> projected_cs;   ///< 3072 ProjectedCSTypeGeoKey
  std::optional<std::uint16_t> geographic_cs;  ///< 2048 GeographicTypeGeoKey
  std::optional<std::uint16_t> vertical_cs;    ///< 4096 VerticalCSTypeGeoKey
  std::optional<std::uint16_t> projected_linear_units;  ///< 3076 ProjLinearUnitsGeoKey
  std::optional<std::uint16_t> vertical_units;          ///< 4099 VerticalUnitsGeoKey

  /// Problems found in the records (counts past the record, dangling parameter indices,
  /// empty WKT, ...). They are also among the reader's warnings.
  std::vector<std::string> warnings;

  /// The first key with `id`, or nullptr.
  const GeoKey* find(std::uint16_t id) const;
  bool empty() const { return !has_geotiff && !wkt && !liblas_wkt; }
};

/// The CRS of a LAS file: its WKT (VLR or EVLR, else the libLAS copy) and its GeoTIFF keys,
/// each interpreted (crs.h) and reconciled by reconcile_crs. `config` (text as
/// crs_from_config takes; empty: none) is used when the file has no CRS, or always when
/// `config_overrides_file`. Disagreements and unreadable records become warnings on the CRS.
/// Errors: InvalidArgument "no CRS" when neither the file nor the config gives one; else the
/// chosen source's error.
kernel::Result<Crs> las_file_crs(const LasCrsRecords& records, std::string_view config = {},
                                 bool config_overrides_file = false);

/// Parses a GeoKeyDirectory (the payload of LASF_Projection 34735) with its double and ASCII
/// parameter payloads (34736, 34737; empty when absent) into `records` (keys, codes,
/// warnings). Never fails: counts are checked against the payload lengths and whatever does
/// not fit is reported in records.warnings. Linear in the payload sizes.
void parse_geotiff_keys(std::span<const std::uint8_t> directory,
                        std::span<const std::uint8_t> doubles, std::span<const std::uint8_t> ascii,
                        LasCrsRecords& records);

/// Bytes of point format `format`'s own fields (0 → 20 ... 10 → 67); 0 for formats > 10.
std::uint16_t las_point_format_length(int format);
/// The Point fields point format `format` carries.
PointFields las_point_fields(int format);

/// Streaming LAS reader.
class LasReader final : public PointReader {
 public:
  /// Opens and checks a LAS or LAZ (COPC) file. Errors: IoError (cannot open/read),
  /// CorruptData (a header field, the laszip VLR or the chunk table disagrees with the file:
  /// the message names the file, the field and the values), Unsupported (a LAZ compressor,
  /// coder or item LASzip does not define, point format > 10), UnsupportedVersion (not
  /// 1.0-1.4).
  static kernel::Result<std::unique_ptr<LasReader>> open(const std::filesystem::path& path,
                                                         const PointReadOptions& options = {});
  /// As open, over bytes in memory that outlive the reader.
  static kernel::Result<std::unique_ptr<LasReader>> open_memory(
      std::string name, std::span<const std::uint8_t> bytes, const PointReadOptions& options = {});
  /// As open, over any random-access source (the worker's HTTP range reader): only the
  /// header, the records, the chunk table and the chunks read are fetched; a COPC file with
  /// options.region fetches its hierarchy pages and the chunks of the nodes meeting it.
  static kernel::Result<std::unique_ptr<LasReader>> open_source(
      std::unique_ptr<ByteSource> source, const PointReadOptions& options = {});
  ~LasReader() override;

  const LasHeader& header() const;
  const std::vector<LasRecord>& vlrs() const;
  const std::vector<LasRecord>& evlrs() const;
  const LasCrsRecords& crs() const;
  /// Complete point records present: the header count, or fewer when a truncated file was
  /// accepted (PointReadOptions::accept_truncated).
  std::uint64_t readable_points() const;
  /// Continues reading at point `index` (≤ readable_points()). Errors: InvalidArgument.
  kernel::Status seek(std::uint64_t index);
  /// The next `max` (or fewer, 0 at the end) point records as the file's uncompressed records
  /// (record length bytes each; LAZ is decoded into the records of its LAS), replacing `out`.
  /// Moves the read position like read(). Errors: as read().
  kernel::Result<std::size_t> read_raw(std::vector<std::uint8_t>& out, std::size_t max);
  /// True when the point data is LAZ-compressed (LAZ or COPC).
  bool compressed() const;
  /// The COPC info VLR of a COPC file (nullopt otherwise).
  const std::optional<CopcInfo>& copc() const;
  /// Reads the COPC hierarchy (all nodes holding points). Errors: InvalidArgument when the
  /// file is not COPC; as read_copc_hierarchy.
  kernel::Result<std::vector<CopcNode>> copc_hierarchy();

 protected:
  kernel::Result<std::size_t> read_records(PointBatch& batch, std::size_t max) override;
  void finish() override;

 private:
  struct State;
  LasReader(std::string name, PointCloudInfo info, PointReadOptions options,
            std::unique_ptr<State> state);
  std::unique_ptr<State> state_;
};

/// What to write. Defaults give LAS 1.4, point format 6, millimetre scale.
struct LasWriteOptions {
  std::uint8_t version_minor = 4;  ///< 0-4; the format must exist in that version
  std::uint8_t point_format = 6;   ///< 0-10 (waveform fields of 4, 5, 9, 10 are written as 0)
  std::array<double, 3> scale{0.001, 0.001, 0.001};
  std::array<double, 3> offset{0.0, 0.0, 0.0};
  /// Extra bytes of each point: record_size bytes; described dimensions are written as an
  /// Extra Bytes VLR (LASF_Spec 4), undescribed bytes are written without one.
  ExtraLayout extra;
  /// Written as LASF_Projection 2112. In 1.4 global encoding bit 4 (WKT) is set when a WKT is
  /// given, or for formats 6-10 without GeoTIFF keys (the standard requires WKT there).
  std::optional<std::string> wkt;
  bool wkt_in_evlr = false;  ///< 1.4 only: put the WKT in an EVLR instead of a VLR
  /// GeoTIFF keys, written as LASF_Projection 34735 (+ 34736 / 34737 from the keys' doubles
  /// and ASCII values; location and value_offset are recomputed).
  std::vector<GeoKey> geo_keys;
  std::vector<LasRecord> vlrs;   ///< further VLRs (payload from `data`)
  std::vector<LasRecord> evlrs;  ///< further EVLRs (1.4 only)
  std::string system_identifier = "csgtile";
  std::string generating_software = "csgtile";
  std::uint16_t file_source_id = 0;
  std::uint16_t global_encoding = 0;  ///< bit 4 is managed as `wkt` says
  std::uint16_t creation_day = 1;     ///< fixed defaults keep outputs byte-identical
  std::uint16_t creation_year = 2025;
};

/// Streaming LAS writer: header, VLRs, points in batches, then EVLRs and the final header
/// (counts, bounds) on close(). A writer not closed leaves an incomplete file.
class LasWriter {
 public:
  /// Creates `path`. Errors: InvalidArgument (format not in the version, bad scale, record
  /// longer than 65535 bytes, EVLRs before 1.4, ...), IoError.
  static kernel::Result<std::unique_ptr<LasWriter>> create(const std::filesystem::path& path,
                                                           const LasWriteOptions& options);
  ~LasWriter();
  LasWriter(const LasWriter&) = delete;
  LasWriter& operator=(const LasWriter&) = delete;

  /// Appends points; extra bytes come from the batch (zeros when it has none). Errors:
  /// InvalidArgument (a coordinate does not fit the scale/offset as int32, the batch's
  /// extra record size differs from the options'), IoError.
  kernel::Status write(const PointBatch& batch);
  /// Writes EVLRs and the final header. Errors: IoError, InvalidArgument (too many points
  /// for the version's 32-bit count).
  kernel::Status close();
  std::uint64_t points_written() const;

 private:
  struct State;
  explicit LasWriter(std::unique_ptr<State> state);
  std::unique_ptr<State> state_;
};

/// Writes `batch` to a new LAS file in one call (create, write, close).
kernel::Status write_las(const std::filesystem::path& path, const LasWriteOptions& options,
                         const PointBatch& batch);

}  // namespace csgtile::geo
