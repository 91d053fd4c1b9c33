// LAS helpers shared by reader and writer: point format lengths and fields, extra-bytes data
// types, fixed-size strings, and the GeoTIFF key directory parser.

#include <algorithm>
#include <set>

#include "csgtile/geo/las.h"
#include "io/endian.h"
#include "io/las_format.h"

namespace csgtile::geo {

std::uint16_t LasHeader::extra_bytes_per_point() const {
  const std::uint16_t base = las_point_format_length(point_format);
  return base == 0 || record_length < base ? 0 : static_cast<std::uint16_t>(record_length - base);
}

std::uint16_t las_point_format_length(int format) {
  static constexpr std::uint16_t kLengths[] = {20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67};
  return format >= 0 && format <= 10 ? kLengths[format] : 0;
}

PointFields las_point_fields(int format) {
  PointFields f;
  if (format < 0 || format > 10) return f;
  f.intensity = f.returns = f.classification = f.scan_angle = f.user_data = f.point_source_id =
      true;
  f.gps_time = detail::las_format_has_gps(format);
  f.color = detail::las_format_has_rgb(format);
  f.nir = detail::las_format_has_nir(format);
  return f;
}

const GeoKey* LasCrsRecords::find(std::uint16_t id) const {
  for (const auto& key : keys) {
    if (key.id == id) return &key;
  }
  return nullptr;
}

void parse_geotiff_keys(std::span<const std::uint8_t> directory,
                        std::span<const std::uint8_t> doubles, std::span<const std::uint8_t> ascii,
                        LasCrsRecords& records) {
  using detail::load_le;
  records.has_geotiff = true;
  auto& warnings = records.warnings;
  if (directory.size() < 8) {
    warnings.push_back("GeoKeyDirectory (LASF_Projection 34735) is " +
                       std::to_string(directory.size()) +
                       " bytes, shorter than its 8-byte header; no keys read");
    return;
  }
  auto short_at = [&](std::size_t index) { return load_le<std::uint16_t>(&directory[2 * index]); };
  const std::size_t shorts = directory.size() / 2;
  records.geotiff_version = {short_at(0), short_at(1), short_at(2)};
  if (records.geotiff_version[0] != 1) {
    warnings.push_back("GeoKeyDirectory KeyDirectoryVersion is " +
                       std::to_string(records.geotiff_version[0]) + " (expected 1)");
  }
  std::size_t declared = short_at(3);
  const std::size_t fits = (shorts - 4) / 4;
  if (declared > fits) {
    warnings.push_back("GeoKeyDirectory declares " + std::to_string(declared) +
                       " keys but its record (" + std::to_string(directory.size()) +
                       " bytes) holds only " + std::to_string(fits) + "; the rest are ignored");
    declared = fits;
  }
  if (doubles.size() % 8 != 0) {
    warnings.push_back("GeoDoubleParams (LASF_Projection 34736) length " +
                       std::to_string(doubles.size()) + " is not a multiple of 8");
  }
  const std::size_t double_count = doubles.size() / 8;

  std::size_t zero_ids = 0;
  bool unsorted = false;
  std::set<std::uint16_t> seen;
  std::uint16_t previous = 0;
  for (std::size_t k = 0; k < declared; ++k) {
    GeoKey key;
    key.id = short_at(4 + 4 * k);
    key.location = short_at(5 + 4 * k);
    key.count = short_at(6 + 4 * k);
    key.value_offset = short_at(7 + 4 * k);
    if (key.id == 0) {
      ++zero_ids;
      continue;
    }
    const std::string label = "GeoKey " + std::to_string(key.id);
    if (key.id < previous) unsorted = true;
    previous = key.id;
    if (!seen.insert(key.id).second) {
      warnings.push_back(label + " appears more than once; the first is used");
    }
    if (key.location == 34736) {
      if (std::size_t{key.value_offset} + key.count > double_count) {
        warnings.push_back(label + ": double parameters [" + std::to_string(key.value_offset) +
                           ", " + std::to_string(key.value_offset + key.count) + ") pass the " +
                           std::to_string(double_count) + " values of GeoDoubleParams");
      } else {
        for (std::size_t i = 0; i < key.count; ++i) {
          key.doubles.push_back(load_le<double>(&doubles[8 * (key.value_offset + i)]));
        }
      }
    } else if (key.location == 34737) {
      if (std::size_t{key.value_offset} + key.count > ascii.size()) {
        warnings.push_back(label + ": ASCII parameter [" + std::to_string(key.value_offset) + ", " +
                           std::to_string(key.value_offset + key.count) + ") passes the " +
                           std::to_string(ascii.size()) + " bytes of GeoAsciiParams");
      } else {
        std::string text(reinterpret_cast<const char*>(ascii.data() + key.value_offset), key.count);
        // The count includes the '|' that ends each value; NULs pad some writers' values.
        while (!text.empty() && (text.back() == '|' || text.back() == '\0')) text.pop_back();
        key.ascii = std::move(text);
      }
    } else if (key.location != 0) {
      warnings.push_back(label + ": parameter location " + std::to_string(key.location) +
                         " is not resolved (expected 0, 34736 or 34737)");
    }
    if (key.location == 0 && seen.count(key.id) == 1) {
      const std::uint16_t v = key.value_offset;
      switch (key.id) {
        case kGeoKeyModelType:
          records.model_type = records.model_type.value_or(v);
          break;
        case kGeoKeyProjectedCsType:
          records.projected_cs = records.projected_cs.value_or(v);
          break;
        case kGeoKeyGeographicType:
          records.geographic_cs = records.geographic_cs.value_or(v);
          break;
        case kGeoKeyVerticalCsType:
          records.vertical_cs = records.vertical_cs.value_or(v);
          break;
        case kGeoKeyProjLinearUnits:
          records.projected_linear_units = records.projected_linear_units.value_or(v);
          break;
        case kGeoKeyVerticalUnits:
          records.vertical_units = records.vertical_units.value_or(v);
          break;
        default:
          break;
      }
    }
    records.keys.push_back(std::move(key));
  }
  if (zero_ids > 0) {
    warnings.push_back("GeoKeyDirectory has " + std::to_string(zero_ids) +
                       " entries with key id 0 (invalid); they are ignored");
  }
  if (unsorted) warnings.push_back("GeoKeyDirectory keys are not in ascending order");
}

namespace detail {

bool las_extra_type(std::uint8_t data_type, ExtraType& type, int& elements) {
  static constexpr ExtraType kBase[] = {
      ExtraType::U8,  ExtraType::I8,  ExtraType::U16, ExtraType::I16, ExtraType::U32,
      ExtraType::I32, ExtraType::U64, ExtraType::I64, ExtraType::F32, ExtraType::F64};
  if (data_type == 0) {
    type = ExtraType::Raw;
    elements = 1;
    return true;
  }
  if (data_type > 30) return false;
  type = kBase[(data_type - 1) % 10];
  elements = 1 + (data_type - 1) / 10;
  return true;
}

std::uint8_t las_extra_data_type(ExtraType type, int elements) {
  if (type == ExtraType::Raw) return 0;
  const int base = static_cast<int>(type);  // U8 = 1 ... F64 = 10
  return static_cast<std::uint8_t>(base + 10 * (std::clamp(elements, 1, 3) - 1));
}

std::string las_fixed_string(const std::uint8_t* p, std::size_t size) {
  std::size_t n = 0;
  while (n < size && p[n] != 0) ++n;
  std::string text(reinterpret_cast<const char*>(p), n);
  while (!text.empty() && text.back() == ' ') text.pop_back();
  return text;
}

}  // namespace detail
}  // namespace csgtile::geo
