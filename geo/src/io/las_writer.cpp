// Streaming LAS 1.0-1.4 writer: a placeholder header and the VLRs first, point records as
// they come, then EVLRs and the final header (counts, bounds) on close.

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <system_error>

#include "csgtile/geo/las.h"
#include "io/endian.h"
#include "io/las_format.h"

namespace csgtile::geo {

namespace {

using detail::store_le;
using kernel::Error;
using kernel::ErrorCode;

std::string num(std::uint64_t v) { return std::to_string(v); }

void put_fixed(std::vector<std::uint8_t>& out, std::size_t at, const std::string& text,
               std::size_t size) {
  std::memcpy(out.data() + at, text.data(), std::min(text.size(), size));
}

std::vector<std::uint8_t> record_bytes(const LasRecord& r, bool extended) {
  const std::size_t header = extended ? detail::kLasEvlrHeaderSize : detail::kLasVlrHeaderSize;
  const std::vector<std::uint8_t> empty;
  const auto& payload = r.data ? *r.data : empty;
  std::vector<std::uint8_t> out(header + payload.size(), 0);
  put_fixed(out, 2, r.user_id, 16);
  store_le<std::uint16_t>(&out[18], r.record_id);
  if (extended) {
    store_le<std::uint64_t>(&out[20], payload.size());
    put_fixed(out, 28, r.description, 32);
  } else {
    store_le<std::uint16_t>(&out[20], static_cast<std::uint16_t>(payload.size()));
    put_fixed(out, 22, r.description, 32);
  }
  if (!payload.empty()) std::memcpy(out.data() + header, payload.data(), payload.size());
  return out;
}

LasRecord make_record(std::string user_id, std::uint16_t record_id, std::string description,
                      std::vector<std::uint8_t> data) {
  LasRecord r;
  r.user_id = std::move(user_id);
  r.record_id = record_id;
  r.description = std::move(description);
  r.length = data.size();
  r.data = std::move(data);
  return r;
}

// The Extra Bytes VLR payload describing `layout` (R15 §2.6). Undescribed bytes between or
// after the dimensions get a data-type-0 descriptor so that offsets stay right.
std::vector<std::uint8_t> extra_descriptors(const ExtraLayout& layout) {
  std::vector<std::uint8_t> out;
  auto add = [&](const ExtraDimension& d) {
    std::vector<std::uint8_t> e(detail::kLasExtraDescriptorSize, 0);
    e[2] = detail::las_extra_data_type(d.type, d.elements);
    std::uint8_t options = 0;
    if (d.type == ExtraType::Raw) {
      options = static_cast<std::uint8_t>(d.elements);
    } else {
      const bool is_float = d.type == ExtraType::F32 || d.type == ExtraType::F64;
      const bool is_signed = d.type == ExtraType::I8 || d.type == ExtraType::I16 ||
                             d.type == ExtraType::I32 || d.type == ExtraType::I64;
      auto put_any = [&](std::size_t at, double v) {
        if (is_float) {
          store_le<double>(&e[at], v);
        } else if (is_signed) {
          store_le<std::int64_t>(&e[at], static_cast<std::int64_t>(v));
        } else {
          store_le<std::uint64_t>(&e[at], static_cast<std::uint64_t>(v));
        }
      };
      if (d.no_data) {
        options |= 1;
        put_any(40, *d.no_data);
      }
      if (d.minimum) {
        options |= 2;
        put_any(64, *d.minimum);
      }
      if (d.maximum) {
        options |= 4;
        put_any(88, *d.maximum);
      }
      if (d.scale) {
        options |= 8;
        store_le<double>(&e[112], *d.scale);
      }
      if (d.offset) {
        options |= 16;
        store_le<double>(&e[136], *d.offset);
      }
    }
    e[3] = options;
    put_fixed(e, 4, d.name, 32);
    put_fixed(e, 160, d.description, 32);
    out.insert(out.end(), e.begin(), e.end());
  };
  std::size_t at = 0;
  auto pad_to = [&](std::size_t offset) {
    while (at < offset) {
      ExtraDimension gap;
      gap.name = "unused " + num(at);
      gap.elements = static_cast<int>(std::min<std::size_t>(offset - at, 255));
      add(gap);
      at += static_cast<std::size_t>(gap.elements);
    }
  };
  for (const auto& d : layout.dimensions) {
    pad_to(d.byte_offset);
    add(d);
    at = d.byte_offset + d.size();
  }
  return out;
}

// GeoKeyDirectory, double and ASCII parameter payloads for `keys`.
void geotiff_payloads(const std::vector<GeoKey>& keys, std::vector<std::uint8_t>& directory,
                      std::vector<std::uint8_t>& doubles, std::vector<std::uint8_t>& ascii) {
  std::vector<std::uint16_t> dir = {1, 1, 0, static_cast<std::uint16_t>(keys.size())};
  std::vector<double> params;
  std::string text;
  for (const auto& key : keys) {
    if (!key.doubles.empty()) {
      dir.insert(dir.end(), {key.id, 34736, static_cast<std::uint16_t>(key.doubles.size()),
                             static_cast<std::uint16_t>(params.size())});
      params.insert(params.end(), key.doubles.begin(), key.doubles.end());
    } else if (key.location == 34737 || !key.ascii.empty()) {
      const std::string value = key.ascii + "|";
      dir.insert(dir.end(), {key.id, 34737, static_cast<std::uint16_t>(value.size()),
                             static_cast<std::uint16_t>(text.size())});
      text += value;
    } else {
      dir.insert(dir.end(), {key.id, 0, 1, key.value_offset});
    }
  }
  directory.resize(dir.size() * 2);
  for (std::size_t i = 0; i < dir.size(); ++i) store_le<std::uint16_t>(&directory[2 * i], dir[i]);
  doubles.resize(params.size() * 8);
  for (std::size_t i = 0; i < params.size(); ++i) store_le<double>(&doubles[8 * i], params[i]);
  ascii.assign(text.begin(), text.end());
  if (!ascii.empty()) ascii.push_back(0);
}

}  // namespace

struct LasWriter::State {
  std::string name;
  LasWriteOptions options;
  std::FILE* file = nullptr;
  std::uint16_t base_length = 0;
  std::uint16_t record_length = 0;
  std::uint32_t offset_to_points = 0;
  std::uint32_t vlr_count = 0;
  std::vector<LasRecord> evlrs;
  std::uint64_t count = 0;
  std::array<std::uint64_t, 15> by_return{};
  Bounds3 bounds;
  std::vector<std::uint8_t> buffer;
  bool closed = false;

  ~State() {
    if (file != nullptr) std::fclose(file);
  }

  kernel::Status io_error(const std::string& what) const {
    return {ErrorCode::IoError, name + ": " + what + ": " + std::generic_category().message(errno)};
  }
  kernel::Status put(const std::vector<std::uint8_t>& bytes) {
    if (!bytes.empty() && std::fwrite(bytes.data(), 1, bytes.size(), file) != bytes.size()) {
      return io_error("write failed");
    }
    return {};
  }
};

LasWriter::LasWriter(std::unique_ptr<State> state) : state_(std::move(state)) {}

LasWriter::~LasWriter() = default;

std::uint64_t LasWriter::points_written() const { return state_->count; }

kernel::Result<std::unique_ptr<LasWriter>> LasWriter::create(const std::filesystem::path& path,
                                                             const LasWriteOptions& options) {
  const std::string name = path.string();
  auto invalid = [&](const std::string& what) {
    return Error{ErrorCode::InvalidArgument, name + ": " + what};
  };
  const int minor = options.version_minor;
  const int format = options.point_format;
  if (minor > 4) return invalid("LAS version 1." + num(minor) + " cannot be written (1.0-1.4)");
  if (format > 10) return invalid("point format " + num(format) + " does not exist (0-10)");
  if (detail::las_first_version_of_format(format) > minor) {
    return invalid("point format " + num(format) + " needs LAS 1." +
                   num(detail::las_first_version_of_format(format)) + " (asked for 1." +
                   num(minor) + ")");
  }
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(options.scale[i]) || options.scale[i] <= 0 ||
        !std::isfinite(options.offset[i])) {
      return invalid(std::string("scale/offset of ") + "xyz"[i] +
                     " must be finite, with a positive scale");
    }
  }
  if ((!options.evlrs.empty() || options.wkt_in_evlr) && minor < 4) {
    return invalid("EVLRs need LAS 1.4");
  }
  const auto& extra = options.extra;
  std::size_t end = 0;
  for (const auto& d : extra.dimensions) {
    if (d.byte_offset < end || d.byte_offset + d.size() > extra.record_size || d.size() == 0 ||
        d.elements < 1 || (d.type != ExtraType::Raw && d.elements > 3) || d.elements > 255) {
      return invalid("extra dimension \"" + d.name + "\" (offset " + num(d.byte_offset) + ", " +
                     num(d.size()) + " bytes) does not fit the " + num(extra.record_size) +
                     "-byte extra record after the previous dimension");
    }
    end = d.byte_offset + d.size();
  }
  auto state = std::make_unique<State>();
  State& s = *state;
  s.name = name;
  s.options = options;
  s.base_length = las_point_format_length(format);
  if (s.base_length + extra.record_size > 65535) {
    return invalid("point record of " + num(s.base_length + extra.record_size) +
                   " bytes is longer than LAS allows (65535)");
  }
  s.record_length = static_cast<std::uint16_t>(s.base_length + extra.record_size);

  std::vector<LasRecord> vlrs;
  if (!extra.dimensions.empty()) {
    vlrs.push_back(make_record("LASF_Spec", 4, "Extra Bytes Record", extra_descriptors(extra)));
  }
  if (!options.geo_keys.empty()) {
    std::vector<std::uint8_t> directory, doubles, ascii;
    geotiff_payloads(options.geo_keys, directory, doubles, ascii);
    vlrs.push_back(make_record("LASF_Projection", 34735, "GeoKeyDirectoryTag", directory));
    if (!doubles.empty()) {
      vlrs.push_back(make_record("LASF_Projection", 34736, "GeoDoubleParamsTag", doubles));
    }
    if (!ascii.empty()) {
      vlrs.push_back(make_record("LASF_Projection", 34737, "GeoAsciiParamsTag", ascii));
    }
  }
  if (options.wkt) {
    std::vector<std::uint8_t> text(options.wkt->begin(), options.wkt->end());
    text.push_back(0);
    auto record = make_record("LASF_Projection", 2112, "OGC WKT", std::move(text));
    (options.wkt_in_evlr ? s.evlrs : vlrs).push_back(std::move(record));
  }
  vlrs.insert(vlrs.end(), options.vlrs.begin(), options.vlrs.end());
  s.evlrs.insert(s.evlrs.end(), options.evlrs.begin(), options.evlrs.end());

  std::vector<std::uint8_t> vlr_bytes;
  for (const auto& r : vlrs) {
    if (r.data && r.data->size() > 65535) {
      return invalid("VLR \"" + r.user_id + "\" " + num(r.record_id) + " payload of " +
                     num(r.data->size()) + " bytes is longer than a VLR allows (65535)");
    }
    const auto bytes = record_bytes(r, false);
    vlr_bytes.insert(vlr_bytes.end(), bytes.begin(), bytes.end());
  }
  // LAS 1.0 puts the point data start signature 0xDD 0xCC after the VLRs.
  if (minor == 0) vlr_bytes.insert(vlr_bytes.end(), {0xDD, 0xCC});
  const std::uint64_t offset = detail::las_header_size(minor) + vlr_bytes.size();
  if (offset > std::numeric_limits<std::uint32_t>::max()) return invalid("VLRs too large");
  s.offset_to_points = static_cast<std::uint32_t>(offset);
  s.vlr_count = static_cast<std::uint32_t>(vlrs.size());

  s.file = std::fopen(name.c_str(), "wb");
  if (s.file == nullptr) {
    return Error{ErrorCode::IoError,
                 name + ": cannot create: " + std::generic_category().message(errno)};
  }
  if (auto st = s.put(std::vector<std::uint8_t>(detail::las_header_size(minor), 0)); !st.ok()) {
    return st.error();
  }
  if (auto st = s.put(vlr_bytes); !st.ok()) return st.error();
  return std::unique_ptr<LasWriter>(new LasWriter(std::move(state)));
}

kernel::Status LasWriter::write(const PointBatch& batch) {
  State& s = *state_;
  if (s.closed) return {ErrorCode::InvalidArgument, s.name + ": write after close"};
  const auto& o = s.options;
  const int format = o.point_format;
  const std::size_t extra = o.extra.record_size;
  const std::size_t given = batch.extra_record_size();
  if (given != 0 && given != extra) {
    return {ErrorCode::InvalidArgument, s.name + ": the batch carries " + num(given) +
                                            " extra bytes per point, the file " + num(extra)};
  }
  s.buffer.assign(batch.points.size() * s.record_length, 0);
  for (std::size_t i = 0; i < batch.points.size(); ++i) {
    const Point& q = batch.points[i];
    std::uint8_t* p = s.buffer.data() + i * s.record_length;
    const double xyz[3] = {q.x, q.y, q.z};
    std::int32_t quantised[3];
    for (int a = 0; a < 3; ++a) {
      const double v = std::round((xyz[a] - o.offset[a]) / o.scale[a]);
      if (!(v >= std::numeric_limits<std::int32_t>::min() &&
            v <= std::numeric_limits<std::int32_t>::max())) {
        return {ErrorCode::InvalidArgument,
                s.name + ": point " + num(s.count + i) + ": " + "xyz"[a] + " = " +
                    std::to_string(xyz[a]) + " does not fit a 32-bit integer with scale " +
                    std::to_string(o.scale[a]) + " and offset " + std::to_string(o.offset[a])};
      }
      quantised[a] = static_cast<std::int32_t>(v);
      store_le<std::int32_t>(p + 4 * a, quantised[a]);
    }
    s.bounds.add(quantised[0] * o.scale[0] + o.offset[0], quantised[1] * o.scale[1] + o.offset[1],
                 quantised[2] * o.scale[2] + o.offset[2]);
    store_le<std::uint16_t>(p + 12, q.intensity);
    std::size_t at = 0;
    if (format < 6) {
      if (q.return_number > 7 || q.number_of_returns > 7 || q.classification > 31) {
        return {ErrorCode::InvalidArgument,
                s.name + ": point " + num(s.count + i) + ": return " + num(q.return_number) +
                    " of " + num(q.number_of_returns) + ", class " + num(q.classification) +
                    " do not fit point format " + num(format) + " (returns 0-7, classes 0-31)"};
      }
      p[14] = static_cast<std::uint8_t>(q.return_number | (q.number_of_returns << 3) |
                                        (q.scan_direction ? 0x40 : 0) |
                                        (q.edge_of_flight_line ? 0x80 : 0));
      p[15] = static_cast<std::uint8_t>(q.classification | ((q.classification_flags & 7) << 5));
      p[16] = static_cast<std::uint8_t>(
          static_cast<std::int8_t>(std::clamp(std::round(q.scan_angle), -128.0F, 127.0F)));
      p[17] = q.user_data;
      store_le<std::uint16_t>(p + 18, q.point_source_id);
      at = 20;
    } else {
      if (q.return_number > 15 || q.number_of_returns > 15) {
        return {ErrorCode::InvalidArgument, s.name + ": point " + num(s.count + i) + ": return " +
                                                num(q.return_number) + " of " +
                                                num(q.number_of_returns) + " does not fit 4 bits"};
      }
      p[14] = static_cast<std::uint8_t>(q.return_number | (q.number_of_returns << 4));
      p[15] = static_cast<std::uint8_t>(
          (q.classification_flags & 15) | ((q.scanner_channel & 3) << 4) |
          (q.scan_direction ? 0x40 : 0) | (q.edge_of_flight_line ? 0x80 : 0));
      p[16] = q.classification;
      p[17] = q.user_data;
      const double steps = std::clamp(std::round(q.scan_angle / 0.006), -32768.0, 32767.0);
      store_le<std::int16_t>(p + 18, static_cast<std::int16_t>(steps));
      store_le<std::uint16_t>(p + 20, q.point_source_id);
      at = 22;
    }
    if (detail::las_format_has_gps(format)) {
      store_le<double>(p + at, q.gps_time);
      at += 8;
    }
    if (detail::las_format_has_rgb(format)) {
      store_le<std::uint16_t>(p + at, q.red);
      store_le<std::uint16_t>(p + at + 2, q.green);
      store_le<std::uint16_t>(p + at + 4, q.blue);
      at += 6;
    }
    if (detail::las_format_has_nir(format)) store_le<std::uint16_t>(p + at, q.nir);
    // Waveform packet fields stay zero: no descriptor, no packet.
    if (given != 0) std::memcpy(p + s.base_length, batch.extra_bytes.data() + i * extra, extra);
    if (q.return_number >= 1 && q.return_number <= 15) ++s.by_return[q.return_number - 1];
  }
  if (auto st = s.put(s.buffer); !st.ok()) return st;
  s.count += batch.points.size();
  return {};
}

kernel::Status LasWriter::close() {
  State& s = *state_;
  if (s.closed) return {};
  s.closed = true;
  const auto& o = s.options;
  const int minor = o.version_minor;
  const int format = o.point_format;
  if (s.count > std::numeric_limits<std::uint32_t>::max() && minor < 4) {
    return {ErrorCode::InvalidArgument,
            s.name + ": " + num(s.count) + " points need LAS 1.4 (32-bit count before)"};
  }
  std::uint64_t evlr_offset = 0;
  if (minor >= 4 && !s.evlrs.empty()) {
    evlr_offset = s.offset_to_points + s.count * s.record_length;
    for (const auto& r : s.evlrs) {
      if (auto st = s.put(record_bytes(r, true)); !st.ok()) return st;
    }
  }
  std::vector<std::uint8_t> h(detail::las_header_size(minor), 0);
  std::memcpy(h.data(), "LASF", 4);
  store_le<std::uint16_t>(&h[detail::kLasFileSourceId], o.file_source_id);
  std::uint16_t encoding = o.global_encoding;
  // LAS 1.4: the WKT bit is required for formats 6-10, and says which CRS record counts.
  if (minor >= 4 && (o.wkt || (format >= 6 && o.geo_keys.empty()))) encoding |= 16;
  store_le<std::uint16_t>(&h[detail::kLasGlobalEncoding], encoding);
  h[detail::kLasVersionMajor] = 1;
  h[detail::kLasVersionMinor] = static_cast<std::uint8_t>(minor);
  put_fixed(h, detail::kLasSystemIdentifier, o.system_identifier, 32);
  put_fixed(h, detail::kLasGeneratingSoftware, o.generating_software, 32);
  store_le<std::uint16_t>(&h[detail::kLasCreationDay], o.creation_day);
  store_le<std::uint16_t>(&h[detail::kLasCreationYear], o.creation_year);
  store_le<std::uint16_t>(&h[detail::kLasHeaderSize], static_cast<std::uint16_t>(h.size()));
  store_le<std::uint32_t>(&h[detail::kLasOffsetToPoints], s.offset_to_points);
  store_le<std::uint32_t>(&h[detail::kLasVlrCount], s.vlr_count);
  h[detail::kLasPointFormat] = static_cast<std::uint8_t>(format);
  store_le<std::uint16_t>(&h[detail::kLasRecordLength], s.record_length);
  // LAS 1.4 keeps the legacy fields zero for formats 6-10 and for counts beyond 32 bits.
  const bool legacy = format < 6 && s.count <= std::numeric_limits<std::uint32_t>::max();
  if (legacy) {
    store_le<std::uint32_t>(&h[detail::kLasLegacyCount], static_cast<std::uint32_t>(s.count));
    for (int i = 0; i < 5; ++i) {
      store_le<std::uint32_t>(&h[detail::kLasLegacyByReturn + 4 * i],
                              static_cast<std::uint32_t>(s.by_return[i]));
    }
  }
  for (int i = 0; i < 3; ++i) {
    store_le<double>(&h[detail::kLasScale + 8 * i], o.scale[i]);
    store_le<double>(&h[detail::kLasOffset + 8 * i], o.offset[i]);
    const bool any = s.count > 0;
    store_le<double>(&h[detail::kLasBounds + 16 * i], any ? s.bounds.max[i] : 0.0);
    store_le<double>(&h[detail::kLasBounds + 16 * i + 8], any ? s.bounds.min[i] : 0.0);
  }
  if (minor >= 4) {
    store_le<std::uint64_t>(&h[detail::kLasEvlrOffset], evlr_offset);
    store_le<std::uint32_t>(&h[detail::kLasEvlrCount], static_cast<std::uint32_t>(s.evlrs.size()));
    store_le<std::uint64_t>(&h[detail::kLasPointCount], s.count);
    for (int i = 0; i < 15; ++i) {
      store_le<std::uint64_t>(&h[detail::kLasByReturn + 8 * i], s.by_return[i]);
    }
  }
  if (std::fseek(s.file, 0, SEEK_SET) != 0) return s.io_error("seek failed");
  if (auto st = s.put(h); !st.ok()) return st;
  const int closed = std::fclose(s.file);
  s.file = nullptr;
  if (closed != 0) return s.io_error("close failed");
  return {};
}

kernel::Status write_las(const std::filesystem::path& path, const LasWriteOptions& options,
                         const PointBatch& batch) {
  auto writer = LasWriter::create(path, options);
  if (!writer.ok()) return writer.error();
  if (auto st = writer.value()->write(batch); !st.ok()) return st;
  return writer.value()->close();
}

}  // namespace csgtile::geo
