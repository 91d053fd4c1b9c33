// Streaming LAS 1.0-1.4 reader. Opening validates every header field that drives a read or an
// allocation against the file size, in the order the fields are needed, before anything is
// allocated from them; points are then decoded chunk by chunk.

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "csgtile/geo/las.h"

#include "csgtile/geo/copc.h"
#include "io/byte_source.h"
#include "io/endian.h"
#include "io/las_format.h"
#include "io/laz/laz_records.h"

namespace csgtile::geo {

namespace {

using detail::load_le;
using kernel::Error;
using kernel::ErrorCode;

// Point data is read in chunks of about this many bytes (at least one record).
constexpr std::size_t kChunkBytes = 1 << 20;
// EVLR payloads above this size (waveform data, big custom records) are described, not loaded.
constexpr std::uint64_t kMaxLoadedEvlr = 16u << 20;
// VLR payloads loaded in total (the largest real VLR areas hold a few hundred KiB).
constexpr std::uint64_t kMaxLoadedVlrBytes = 64u << 20;

std::string num(std::uint64_t v) { return std::to_string(v); }

std::string printable(const std::string& text) {
  std::string out;
  for (const char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (u >= 0x20 && u < 0x7f) {
      out += c;
    } else {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02x", u);
      out += hex;
    }
  }
  return out;
}

std::string record_label(const char* kind, std::size_t index, std::size_t count,
                         const LasRecord& r) {
  return std::string(kind) + " " + num(index + 1) + " of " + num(count) + " (user id \"" +
         printable(r.user_id) + "\", record id " + num(r.record_id) + ")";
}

// Text of a WKT payload: up to the first NUL.
std::string wkt_text(const std::vector<std::uint8_t>& data) {
  std::size_t n = 0;
  while (n < data.size() && data[n] != 0) ++n;
  std::string text(reinterpret_cast<const char*>(data.data()), n);
  while (!text.empty() && (text.back() == ' ' || text.back() == '\n')) text.pop_back();
  return text;
}

Error corrupt(const std::string& name, const std::string& what) {
  return Error{ErrorCode::CorruptData, name + ": " + what};
}

// Values the decoder needs per record.
struct Decoding {
  int format = 0;
  std::size_t record_length = 0;
  std::size_t base_length = 0;
  std::size_t extra_length = 0;
  std::array<double, 3> scale{};
  std::array<double, 3> offset{};
};

// Decodes `count` records of point format F. Templated so that the per-format branches fold
// away in the inner loop.
template <int F>
std::uint64_t decode_records(const Decoding& d, const std::uint8_t* data, std::size_t count,
                             Point* out, std::uint8_t* extra) {
  std::uint64_t nan_gps = 0;
  for (std::size_t i = 0; i < count; ++i) {
    const std::uint8_t* p = data + i * d.record_length;
    Point& q = out[i];
    q = Point{};  // the batch may hold an earlier read's points
    q.x = load_le<std::int32_t>(p) * d.scale[0] + d.offset[0];
    q.y = load_le<std::int32_t>(p + 4) * d.scale[1] + d.offset[1];
    q.z = load_le<std::int32_t>(p + 8) * d.scale[2] + d.offset[2];
    q.intensity = load_le<std::uint16_t>(p + 12);
    std::size_t at = 0;
    if constexpr (F < 6) {
      const std::uint8_t bits = p[14];
      q.return_number = bits & 7;
      q.number_of_returns = (bits >> 3) & 7;
      q.scan_direction = (bits >> 6) & 1;
      q.edge_of_flight_line = (bits >> 7) & 1;
      const std::uint8_t c = p[15];
      q.classification = c & 31;
      q.classification_flags = (c >> 5) & 7;
      q.scan_angle = static_cast<float>(static_cast<std::int8_t>(p[16]));
      q.user_data = p[17];
      q.point_source_id = load_le<std::uint16_t>(p + 18);
      at = 20;
    } else {
      const std::uint8_t bits = p[14];
      q.return_number = bits & 15;
      q.number_of_returns = bits >> 4;
      const std::uint8_t flags = p[15];
      q.classification_flags = flags & 15;
      q.scanner_channel = (flags >> 4) & 3;
      q.scan_direction = (flags >> 6) & 1;
      q.edge_of_flight_line = (flags >> 7) & 1;
      q.classification = p[16];
      q.user_data = p[17];
      q.scan_angle = static_cast<float>(load_le<std::int16_t>(p + 18) * 0.006);
      q.point_source_id = load_le<std::uint16_t>(p + 20);
      at = 22;
    }
    if constexpr (detail::las_format_has_gps(F)) {
      q.gps_time = load_le<double>(p + at);
      if (std::isnan(q.gps_time)) ++nan_gps;
      at += 8;
    }
    if constexpr (detail::las_format_has_rgb(F)) {
      q.red = load_le<std::uint16_t>(p + at);
      q.green = load_le<std::uint16_t>(p + at + 2);
      q.blue = load_le<std::uint16_t>(p + at + 4);
      at += 6;
    }
    if constexpr (detail::las_format_has_nir(F)) {
      q.nir = load_le<std::uint16_t>(p + at);
      at += 2;
    }
    // Waveform packet fields (descriptor index, offset, size, location, x(t), y(t), z(t)) are
    // skipped: the record length already covers them.
    if (d.extra_length > 0) {
      std::memcpy(extra + i * d.extra_length, p + d.base_length, d.extra_length);
    }
  }
  return nan_gps;
}

using Decoder = std::uint64_t (*)(const Decoding&, const std::uint8_t*, std::size_t, Point*,
                                  std::uint8_t*);

Decoder decoder_for(int format) {
  static constexpr Decoder kDecoders[] = {decode_records<0>, decode_records<1>, decode_records<2>,
                                          decode_records<3>, decode_records<4>, decode_records<5>,
                                          decode_records<6>, decode_records<7>, decode_records<8>,
                                          decode_records<9>, decode_records<10>};
  return kDecoders[format];
}

// Reads "anytype" no_data / min / max of an extra-bytes descriptor as a double.
double descriptor_value(const std::uint8_t* p, ExtraType type) {
  switch (type) {
    case ExtraType::U8:
    case ExtraType::U16:
    case ExtraType::U32:
    case ExtraType::U64:
      return static_cast<double>(load_le<std::uint64_t>(p));
    case ExtraType::I8:
    case ExtraType::I16:
    case ExtraType::I32:
    case ExtraType::I64:
      return static_cast<double>(load_le<std::int64_t>(p));
    default:
      return load_le<double>(p);
  }
}

// Everything open() learns before the points.
struct Parsed {
  std::unique_ptr<detail::ByteSource> source;
  LasHeader header;
  std::vector<LasRecord> vlrs;
  std::vector<LasRecord> evlrs;
  LasCrsRecords crs;
  Decoding decoding;
  std::uint64_t readable = 0;                    // complete records that will be read
  std::unique_ptr<detail::laz::LazRecords> laz;  // compressed point data (LAZ, COPC)
  std::optional<CopcInfo> copc;                  // COPC files
  std::optional<std::size_t> copc_nodes_read;    // a COPC query: nodes selected
};

// A file's bytes with the EVLR payloads already loaded served from memory: the COPC hierarchy
// EVLR is loaded with the other records, so its pages are not read again (over HTTP: not
// fetched twice).
class LoadedRecordsSource final : public ByteSource {
 public:
  LoadedRecordsSource(ByteSource& file, const std::vector<LasRecord>& records)
      : ByteSource(file.name()), file_(file), records_(records) {}
  std::uint64_t size() const override { return file_.size(); }
  kernel::Status read_at(std::uint64_t offset, std::span<std::uint8_t> out) override {
    for (const LasRecord& r : records_) {
      if (r.data && offset >= r.payload_offset && out.size() <= r.data->size() &&
          offset - r.payload_offset <= r.data->size() - out.size()) {
        std::copy_n(r.data->begin() + static_cast<std::ptrdiff_t>(offset - r.payload_offset),
                    out.size(), out.begin());
        return kernel::Status();
      }
    }
    return file_.read_at(offset, out);
  }

 private:
  ByteSource& file_;
  const std::vector<LasRecord>& records_;
};

kernel::Result<std::vector<CopcNode>> copc_nodes(ByteSource& file, const CopcInfo& info,
                                                 const std::vector<LasRecord>& evlrs) {
  LoadedRecordsSource source(file, evlrs);
  return read_copc_hierarchy(source, info);
}

// The chunks of the COPC nodes a region (and a depth) selects, renumbered as one run of
// points; each node must be a chunk of the chunk table (same offset, size and count).
kernel::Result<std::vector<detail::laz::Chunk>> copc_chunks(
    detail::ByteSource& src, const CopcInfo& info, const std::vector<LasRecord>& evlrs,
    const std::vector<detail::laz::Chunk>& all, const PointReadOptions& options) {
  auto nodes = copc_nodes(src, info, evlrs);
  if (!nodes.ok()) return nodes.error();
  CopcQuery query;
  query.box = options.region;
  query.max_depth = options.copc_max_depth;
  std::vector<detail::laz::Chunk> out;
  std::uint64_t first = 0;
  for (const CopcNode& n : select_copc_nodes(nodes.value(), query)) {
    const auto it = std::lower_bound(
        all.begin(), all.end(), n.offset,
        [](const detail::laz::Chunk& c, std::uint64_t offset) { return c.offset < offset; });
    if (it == all.end() || it->offset != n.offset || it->bytes != n.bytes ||
        it->points != n.points) {
      return corrupt(src.name(), "COPC hierarchy node " + num(n.depth) + "-" + num(n.x) + "-" +
                                     num(n.y) + "-" + num(n.z) + " (offset " + num(n.offset) +
                                     ", " + num(n.bytes) + " bytes, " + num(n.points) +
                                     " points) is no chunk of the chunk table");
    }
    detail::laz::Chunk c = *it;
    c.first_point = first;
    first += c.points;
    out.push_back(c);
  }
  return out;
}

// The header: signature and version first (they decide how to read the rest), then every
// field of the version's header (fields a short header lacks read as zero). `count64` is LAS
// 1.4's 64-bit point count (0 before 1.4), `format_id` the point format byte as stored (the
// LASzip compression bits included).
kernel::Status read_las_header(detail::ByteSource& src, LasHeader& h, std::uint64_t& count64,
                               std::uint8_t& format_id, std::vector<std::string>& warnings) {
  const std::string& name = src.name();
  const std::uint64_t size = src.size();
  std::array<std::uint8_t, detail::kLasHeaderSize14> head{};
  const std::size_t head_read =
      static_cast<std::size_t>(std::min<std::uint64_t>(size, head.size()));
  if (auto st = src.read_at(0, std::span(head.data(), head_read)); !st.ok()) return st.error();
  if (size < 4 || std::memcmp(head.data(), "LASF", 4) != 0) {
    return corrupt(name, "not a LAS file: the file signature is \"" +
                             printable(std::string(reinterpret_cast<const char*>(head.data()),
                                                   std::min<std::size_t>(head_read, 4))) +
                             "\", not \"LASF\"");
  }
  if (size < detail::kLasHeaderSize12) {
    return corrupt(name, "file size " + num(size) +
                             " bytes is smaller than the smallest LAS header (227 bytes)");
  }
  h.version_major = head[detail::kLasVersionMajor];
  h.version_minor = head[detail::kLasVersionMinor];
  if (h.version_major != 1 || h.version_minor > 4) {
    return Error{ErrorCode::UnsupportedVersion, name + ": LAS version " + num(h.version_major) +
                                                    "." + num(h.version_minor) +
                                                    " is not supported (1.0-1.4)"};
  }
  h.header_size = load_le<std::uint16_t>(&head[detail::kLasHeaderSize]);
  const std::size_t version_header = detail::las_header_size(h.version_minor);
  if (h.header_size < detail::kLasHeaderSize12) {
    return corrupt(name, "header size " + num(h.header_size) +
                             " is smaller than the 227 bytes of every LAS header");
  }
  if (h.header_size > size) {
    return corrupt(name, "header size " + num(h.header_size) + " passes the end of the file (" +
                             num(size) + " bytes)");
  }
  if (h.header_size < version_header) {
    warnings.push_back(name + ": header size " + num(h.header_size) + " is smaller than LAS 1." +
                       num(h.version_minor) + "'s " + num(version_header) +
                       " bytes; the missing fields are taken as zero");
    std::fill(head.begin() + h.header_size, head.end(), std::uint8_t{0});
  }
  h.file_source_id = load_le<std::uint16_t>(&head[detail::kLasFileSourceId]);
  h.global_encoding = load_le<std::uint16_t>(&head[detail::kLasGlobalEncoding]);
  std::copy_n(head.begin() + detail::kLasGuid, 16, h.guid.begin());
  h.system_identifier = detail::las_fixed_string(&head[detail::kLasSystemIdentifier], 32);
  h.generating_software = detail::las_fixed_string(&head[detail::kLasGeneratingSoftware], 32);
  h.creation_day = load_le<std::uint16_t>(&head[detail::kLasCreationDay]);
  h.creation_year = load_le<std::uint16_t>(&head[detail::kLasCreationYear]);
  h.offset_to_point_data = load_le<std::uint32_t>(&head[detail::kLasOffsetToPoints]);
  h.vlr_count = load_le<std::uint32_t>(&head[detail::kLasVlrCount]);
  format_id = head[detail::kLasPointFormat];
  h.point_format = format_id & 0x3F;
  h.record_length = load_le<std::uint16_t>(&head[detail::kLasRecordLength]);
  h.legacy_point_count = load_le<std::uint32_t>(&head[detail::kLasLegacyCount]);
  for (int i = 0; i < 5; ++i) {
    h.legacy_points_by_return[i] =
        load_le<std::uint32_t>(&head[detail::kLasLegacyByReturn + 4 * i]);
  }
  for (int i = 0; i < 3; ++i) {
    h.scale[i] = load_le<double>(&head[detail::kLasScale + 8 * i]);
    h.offset[i] = load_le<double>(&head[detail::kLasOffset + 8 * i]);
    h.max[i] = load_le<double>(&head[detail::kLasBounds + 16 * i]);
    h.min[i] = load_le<double>(&head[detail::kLasBounds + 16 * i + 8]);
  }
  if (h.version_minor >= 3) {
    h.waveform_data_start = load_le<std::uint64_t>(&head[detail::kLasWaveformStart]);
  }
  if (h.version_minor >= 4) {
    h.evlr_offset = load_le<std::uint64_t>(&head[detail::kLasEvlrOffset]);
    h.evlr_count = load_le<std::uint32_t>(&head[detail::kLasEvlrCount]);
    count64 = load_le<std::uint64_t>(&head[detail::kLasPointCount]);
    for (int i = 0; i < 15; ++i) {
      h.points_by_return[i] = load_le<std::uint64_t>(&head[detail::kLasByReturn + 8 * i]);
    }
  } else {
    for (int i = 0; i < 5; ++i) h.points_by_return[i] = h.legacy_points_by_return[i];
  }
  return kernel::Status();
}

// The offset to the point data, then the VLRs between the header and it (payloads loaded up
// to kMaxLoadedVlrBytes in total).
kernel::Status read_las_vlrs(detail::ByteSource& src, const LasHeader& h,
                             std::vector<LasRecord>& vlrs, std::vector<std::string>& warnings) {
  const std::string& name = src.name();
  const std::uint64_t size = src.size();
  if (h.offset_to_point_data < h.header_size) {
    return corrupt(name, "offset to point data " + num(h.offset_to_point_data) +
                             " lies inside the header (header size " + num(h.header_size) + ")");
  }
  if (h.offset_to_point_data > size) {
    return corrupt(name, "offset to point data " + num(h.offset_to_point_data) +
                             " passes the end of the file (" + num(size) + " bytes)");
  }
  const std::uint64_t vlr_area = h.offset_to_point_data - h.header_size;
  if (std::uint64_t{h.vlr_count} * detail::kLasVlrHeaderSize > vlr_area) {
    return corrupt(name, "VLR count " + num(h.vlr_count) + " needs at least " +
                             num(std::uint64_t{h.vlr_count} * detail::kLasVlrHeaderSize) +
                             " bytes, but only " + num(vlr_area) + " lie between the header (" +
                             num(h.header_size) + " bytes) and the point data (offset " +
                             num(h.offset_to_point_data) + ")");
  }
  std::uint64_t pos = h.header_size;
  // Reservations are capped: a count is only as good as the records that parse.
  vlrs.reserve(std::min<std::uint32_t>(h.vlr_count, 1024));
  std::uint64_t vlr_loaded = 0;
  for (std::uint32_t i = 0; i < h.vlr_count; ++i) {
    if (pos + detail::kLasVlrHeaderSize > h.offset_to_point_data) {
      return corrupt(name,
                     "VLR " + num(i + 1) + " of " + num(h.vlr_count) + ": its header at byte " +
                         num(pos) + " passes the start of the point data (offset " +
                         num(h.offset_to_point_data) + "): the VLR count or a VLR length is wrong");
    }
    std::array<std::uint8_t, detail::kLasVlrHeaderSize> rh{};
    if (auto st = src.read_at(pos, rh); !st.ok()) return st.error();
    LasRecord r;
    r.user_id = detail::las_fixed_string(&rh[2], 16);
    r.record_id = load_le<std::uint16_t>(&rh[18]);
    r.length = load_le<std::uint16_t>(&rh[20]);
    r.description = detail::las_fixed_string(&rh[22], 32);
    r.payload_offset = pos + detail::kLasVlrHeaderSize;
    const std::uint64_t end = r.payload_offset + r.length;
    if (end > h.offset_to_point_data) {
      return corrupt(name, record_label("VLR", i, h.vlr_count, r) + ": length " + num(r.length) +
                               " ends at byte " + num(end) + ", past " +
                               (end > size ? "the end of the file (" + num(size) + " bytes)"
                                           : "the start of the point data (offset " +
                                                 num(h.offset_to_point_data) + ")"));
    }
    // VLRs are at most 64 KiB each, but a huge VLR area could hold thousands: past
    // kMaxLoadedVlrBytes in total they are listed without their payload.
    if (vlr_loaded + r.length <= kMaxLoadedVlrBytes) {
      std::vector<std::uint8_t> payload(r.length);
      if (auto st = src.read_at(r.payload_offset, payload); !st.ok()) return st.error();
      r.data = std::move(payload);
      vlr_loaded += r.length;
    } else if (vlr_loaded <= kMaxLoadedVlrBytes) {
      warnings.push_back(name + ": VLR payloads beyond " + num(kMaxLoadedVlrBytes) +
                         " bytes in total are listed but not loaded");
      vlr_loaded = kMaxLoadedVlrBytes + 1;
    }
    vlrs.push_back(std::move(r));
    pos = end;
  }
  return kernel::Status();
}

// The point count against the bytes actually present: sets h.point_count, the records that
// will be read (`readable`; a compressed file's are checked against its chunk table later)
// and where the point data ends (`data_end`: the first EVLR or the end of the file).
kernel::Status check_las_point_count(detail::ByteSource& src, LasHeader& h, std::uint64_t count64,
                                     bool compressed, const PointReadOptions& options,
                                     std::uint64_t& readable, std::uint64_t& data_end,
                                     std::vector<std::string>& warnings) {
  const std::string& name = src.name();
  const std::uint64_t size = src.size();
  h.point_count = h.legacy_point_count;
  if (h.version_minor >= 4 && h.header_size >= detail::kLasHeaderSize14) {
    if (count64 != 0 && h.legacy_point_count != 0 && count64 != h.legacy_point_count) {
      warnings.push_back(name + ": legacy point count " + num(h.legacy_point_count) +
                         " disagrees with the 64-bit point count " + num(count64) +
                         "; the 64-bit count is used");
    }
    if (count64 != 0) h.point_count = count64;
  }
  data_end = size;
  const char* data_end_what = "the end of the file";
  if (h.version_minor >= 4 && h.evlr_count > 0) {
    if (h.evlr_offset < h.offset_to_point_data) {
      return corrupt(name, "start of first EVLR " + num(h.evlr_offset) +
                               " lies before the point data (offset " +
                               num(h.offset_to_point_data) + ")");
    }
    if (h.evlr_offset > size) {
      return corrupt(name, "start of first EVLR " + num(h.evlr_offset) +
                               " passes the end of the file (" + num(size) + " bytes)");
    }
    data_end = h.evlr_offset;
    data_end_what = "the first EVLR";
  }
  const std::uint64_t data_bytes = data_end - h.offset_to_point_data;
  const std::uint64_t complete = data_bytes / h.record_length;
  readable = h.point_count;
  if (compressed) {
    // Checked against the chunk table below.
  } else if (h.point_count > complete) {
    const std::string what = "truncated: the header's point count is " + num(h.point_count) +
                             " records of " + num(h.record_length) + " bytes, but only " +
                             num(data_bytes) +
                             " bytes of point data lie between the offset to point data (" +
                             num(h.offset_to_point_data) + ") and " + data_end_what + " (byte " +
                             num(data_end) + "): " + num(complete) + " complete records";
    if (!options.accept_truncated) return corrupt(name, what);
    warnings.push_back(name + ": " + what + "; reading those");
    readable = complete;
  } else if (h.point_count < complete && h.evlr_count == 0 &&
             data_bytes - h.point_count * h.record_length >= h.record_length) {
    warnings.push_back(name + ": " + num(data_bytes - h.point_count * h.record_length) +
                       " bytes follow the " + num(h.point_count) +
                       " declared point records; they are ignored");
  }
  return kernel::Status();
}

// The EVLRs of LAS 1.4 (payloads up to kMaxLoadedEvlr each and four times that in total
// loaded), and the warnings about offsets that point past the file.
kernel::Status read_las_evlrs(detail::ByteSource& src, const LasHeader& h,
                              std::vector<LasRecord>& evlrs, std::vector<std::string>& warnings) {
  const std::string& name = src.name();
  const std::uint64_t size = src.size();
  if (h.version_minor >= 4 && h.evlr_count > 0) {
    const std::uint64_t area = size - h.evlr_offset;
    if (std::uint64_t{h.evlr_count} * detail::kLasEvlrHeaderSize > area) {
      return corrupt(name, "EVLR count " + num(h.evlr_count) + " needs at least " +
                               num(std::uint64_t{h.evlr_count} * detail::kLasEvlrHeaderSize) +
                               " bytes from the first EVLR (byte " + num(h.evlr_offset) +
                               "), but the file has " + num(area) + " bytes left");
    }
    std::uint64_t at = h.evlr_offset;
    std::uint64_t loaded = 0;
    evlrs.reserve(std::min<std::uint32_t>(h.evlr_count, 1024));
    for (std::uint32_t i = 0; i < h.evlr_count; ++i) {
      if (at + detail::kLasEvlrHeaderSize > size) {
        return corrupt(name, "EVLR " + num(i + 1) + " of " + num(h.evlr_count) +
                                 ": its header at byte " + num(at) +
                                 " passes the end of the file (" + num(size) + " bytes)");
      }
      std::array<std::uint8_t, detail::kLasEvlrHeaderSize> rh{};
      if (auto st = src.read_at(at, rh); !st.ok()) return st.error();
      LasRecord r;
      r.extended = true;
      r.user_id = detail::las_fixed_string(&rh[2], 16);
      r.record_id = load_le<std::uint16_t>(&rh[18]);
      r.length = load_le<std::uint64_t>(&rh[20]);
      r.description = detail::las_fixed_string(&rh[28], 32);
      r.payload_offset = at + detail::kLasEvlrHeaderSize;
      if (r.length > size - r.payload_offset) {
        return corrupt(name, record_label("EVLR", i, h.evlr_count, r) + ": length " +
                                 num(r.length) + " passes the end of the file (" + num(size) +
                                 " bytes; the payload starts at byte " + num(r.payload_offset) +
                                 ")");
      }
      if (r.length <= kMaxLoadedEvlr && loaded + r.length <= 4 * kMaxLoadedEvlr) {
        std::vector<std::uint8_t> payload(static_cast<std::size_t>(r.length));
        if (auto st = src.read_at(r.payload_offset, payload); !st.ok()) return st.error();
        r.data = std::move(payload);
        loaded += r.length;
      }
      at = r.payload_offset + r.length;
      evlrs.push_back(std::move(r));
    }
  } else if (h.version_minor >= 4 && h.evlr_offset != 0 && h.evlr_count == 0 &&
             h.evlr_offset > size) {
    warnings.push_back(name + ": start of first EVLR " + num(h.evlr_offset) +
                       " passes the end of the file, but the EVLR count is 0; ignored");
  }
  if (detail::las_format_has_waves(h.point_format) && (h.global_encoding & 2) != 0 &&
      h.waveform_data_start > size) {
    warnings.push_back(name + ": start of waveform data " + num(h.waveform_data_start) +
                       " passes the end of the file; waveform packets are ignored anyway");
  }
  return kernel::Status();
}

// The layout of the extra bytes after each record's `extra_length` standard ones, from the
// Extra Bytes descriptors (LASF_Spec 4) where present; null when there are none.
std::shared_ptr<ExtraLayout> parse_extra_bytes(const std::string& name,
                                               const std::vector<LasRecord>& vlrs,
                                               const std::vector<LasRecord>& evlrs,
                                               std::size_t extra_length,
                                               std::vector<std::string>& warnings) {
  const LasRecord* descriptors = nullptr;
  for (const auto* list : {&vlrs, &evlrs}) {
    for (const auto& r : *list) {
      if (r.user_id == "LASF_Spec" && r.record_id == 4 && r.data && descriptors == nullptr) {
        descriptors = &r;
      }
    }
  }
  if (extra_length > 0 || descriptors != nullptr) {
    auto layout = std::make_shared<ExtraLayout>();
    layout->record_size = extra_length;
    if (descriptors != nullptr) {
      const auto& d = *descriptors->data;
      if (d.size() % detail::kLasExtraDescriptorSize != 0) {
        warnings.push_back(name + ": Extra Bytes VLR length " + num(d.size()) +
                           " is not a multiple of 192; the partial descriptor is ignored");
      }
      std::size_t used = 0;
      const std::size_t n = d.size() / detail::kLasExtraDescriptorSize;
      for (std::size_t k = 0; k < n; ++k) {
        const std::uint8_t* e = d.data() + k * detail::kLasExtraDescriptorSize;
        ExtraDimension dim;
        dim.name = detail::las_fixed_string(e + 4, 32);
        dim.description = detail::las_fixed_string(e + 160, 32);
        const std::uint8_t data_type = e[2];
        const std::uint8_t opts = e[3];
        if (!detail::las_extra_type(data_type, dim.type, dim.elements)) {
          warnings.push_back(name + ": extra-bytes descriptor " + num(k + 1) + " (\"" +
                             printable(dim.name) + "\") has reserved data type " + num(data_type) +
                             "; it and later descriptors are ignored");
          break;
        }
        if (dim.type == ExtraType::Raw) {
          dim.elements = opts;  // for undocumented bytes, options holds their number
        } else {
          if (opts & 1) dim.no_data = descriptor_value(e + 40, dim.type);
          if (opts & 2) dim.minimum = descriptor_value(e + 64, dim.type);
          if (opts & 4) dim.maximum = descriptor_value(e + 88, dim.type);
          if (opts & 8) dim.scale = load_le<double>(e + 112);
          if (opts & 16) dim.offset = load_le<double>(e + 136);
        }
        dim.byte_offset = used;
        if (used + dim.size() > extra_length) {
          warnings.push_back(name + ": extra-bytes descriptor " + num(k + 1) + " (\"" +
                             printable(dim.name) + "\", " + num(dim.size()) + " bytes at offset " +
                             num(used) + ") does not fit the " + num(extra_length) +
                             " extra bytes of each record; it and later descriptors are ignored");
          break;
        }
        used += dim.size();
        if (dim.size() == 0) continue;
        if (layout->find(dim.name) != nullptr) {
          warnings.push_back(name + ": extra-bytes name \"" + printable(dim.name) +
                             "\" is used twice; lookups by name find the first");
        }
        layout->dimensions.push_back(std::move(dim));
      }
    }
    return layout;
  }
  return nullptr;
}

// The CRS records: GeoTIFF keys (LASF_Projection 34735-34737), OGC WKT (2112, in a VLR or an
// EVLR), liblas's WKT; what is odd about them goes to crs.warnings.
void parse_crs_records(const LasHeader& h, const std::vector<LasRecord>& vlrs,
                       const std::vector<LasRecord>& evlrs, LasCrsRecords& crs) {
  const LasRecord* keys = nullptr;
  const LasRecord* doubles = nullptr;
  const LasRecord* ascii = nullptr;
  const LasRecord* wkt = nullptr;
  for (const auto* list : {&vlrs, &evlrs}) {
    for (const auto& r : *list) {
      if (!r.data) continue;
      if (r.user_id == "LASF_Projection") {
        const LasRecord** slot = r.record_id == 34735   ? &keys
                                 : r.record_id == 34736 ? &doubles
                                 : r.record_id == 34737 ? &ascii
                                 : r.record_id == 2112  ? &wkt
                                                        : nullptr;
        if (slot == nullptr) continue;
        if (*slot != nullptr && r.record_id != 2112) {
          crs.warnings.push_back("LASF_Projection record " + num(r.record_id) +
                                 " appears more than once; the first is used");
          continue;
        }
        if (*slot != nullptr && r.record_id == 2112 &&
            wkt_text(*(*slot)->data) != wkt_text(*r.data)) {
          crs.warnings.push_back("two OGC WKT records differ; the " +
                                 std::string(r.extended ? "EVLR" : "later VLR") + "'s is used");
        }
        *slot = &r;
      } else if (r.user_id == "liblas" && r.record_id == 2112 && !crs.liblas_wkt) {
        crs.liblas_wkt = wkt_text(*r.data);
      }
    }
  }
  if (keys != nullptr) {
    static const std::vector<std::uint8_t> kNone;
    parse_geotiff_keys(*keys->data, doubles ? *doubles->data : kNone, ascii ? *ascii->data : kNone,
                       crs);
  } else if (doubles != nullptr || ascii != nullptr) {
    crs.warnings.push_back("GeoTIFF parameter records without a GeoKeyDirectory (34735)");
  }
  if (wkt != nullptr) {
    crs.wkt = wkt_text(*wkt->data);
    crs.wkt_from_evlr = wkt->extended;
    // Some writers store an empty string or a pair of quotes: no WKT at all.
    const bool blank = std::none_of(crs.wkt->begin(), crs.wkt->end(), [](char c) {
      return std::isalnum(static_cast<unsigned char>(c)) != 0;
    });
    if (blank) {
      crs.warnings.push_back("the OGC WKT record (LASF_Projection 2112) is empty (\"" +
                             printable(crs.wkt->substr(0, 16)) + "\")");
    }
  }
  crs.wkt_flag = h.version_minor >= 4 && (h.global_encoding & 16) != 0;
  // The WKT bit without a WKT record is a file without a CRS (LAS 1.4 sets the bit for every
  // file of formats 6-10): nothing to warn about. GeoTIFF keys with the bit set are.
  if (crs.wkt_flag && wkt == nullptr && keys != nullptr) {
    crs.warnings.push_back(
        "global encoding says the CRS is WKT, but the file has GeoTIFF keys and no WKT record");
  }
  if (h.point_format >= 6 && keys != nullptr && wkt == nullptr) {
    crs.warnings.push_back("point format " + num(h.point_format) +
                           " requires a WKT CRS (LAS 1.4), but the file has GeoTIFF keys only");
  }
}

// Parses and checks everything before the points, in the order the fields are needed.
kernel::Result<bool> parse_las(Parsed& s, PointCloudInfo& info, std::vector<std::string>& warnings,
                               const PointReadOptions& options) {
  detail::ByteSource& src = *s.source;
  const std::string& name = src.name();
  const std::uint64_t size = src.size();
  LasHeader& h = s.header;
  std::uint64_t count64 = 0;
  std::uint8_t format_id = 0;
  if (auto st = read_las_header(src, h, count64, format_id, warnings); !st.ok()) {
    return st.error();
  }

  // Compressed point data is recognised by the format id's top bits (LASzip convention) and
  // the laszip VLR.
  const bool compressed_bit = (format_id & 0xC0) != 0;

  if (auto st = read_las_vlrs(src, h, s.vlrs, warnings); !st.ok()) return st.error();
  const LasRecord* laszip = nullptr;
  const LasRecord* copc_vlr = nullptr;
  for (const auto& r : s.vlrs) {
    if (r.user_id == "laszip encoded" && r.record_id == 22204 && laszip == nullptr) laszip = &r;
    if (r.user_id == "copc" && r.record_id == 1 && copc_vlr == nullptr) copc_vlr = &r;
  }
  const bool copc = copc_vlr != nullptr;
  if (compressed_bit && laszip == nullptr) {
    return corrupt(name, "LAZ-compressed (point format id " + num(format_id) +
                             " has the compression bit set) but no laszip VLR (\"laszip "
                             "encoded\", 22204) says how");
  }
  if (laszip != nullptr && !laszip->data) {
    return corrupt(name, "the laszip VLR was not loaded (VLR area over its limit)");
  }
  const bool compressed = laszip != nullptr;
  if (laszip != nullptr && !compressed_bit) {
    warnings.push_back(name +
                       ": a laszip VLR without the compression bit in the point format "
                       "id; read as LAZ");
  }

  // Point format and record length.
  if (h.point_format > 10) {
    return Error{ErrorCode::Unsupported, name + ": point data format " + num(h.point_format) +
                                             " is not defined by LAS 1.0-1.4 (formats 0-10)"};
  }
  const std::uint16_t base_length = las_point_format_length(h.point_format);
  if (h.record_length < base_length) {
    return corrupt(name, "point record length " + num(h.record_length) +
                             " is smaller than point format " + num(h.point_format) +
                             "'s minimum of " + num(base_length) + " bytes");
  }
  if (detail::las_first_version_of_format(h.point_format) > h.version_minor) {
    warnings.push_back(name + ": point format " + num(h.point_format) +
                       " is not defined in LAS 1." + num(h.version_minor) + " (it needs 1." +
                       num(detail::las_first_version_of_format(h.point_format)) +
                       "); read as the format says");
  }

  std::uint64_t data_end = size;
  if (auto st = check_las_point_count(src, h, count64, compressed, options, s.readable, data_end,
                                      warnings);
      !st.ok()) {
    return st.error();
  }
  if (auto st = read_las_evlrs(src, h, s.evlrs, warnings); !st.ok()) return st.error();

  if (compressed) {
    auto spec = detail::laz::parse_laszip_vlr(*laszip->data, h.point_format, h.record_length, name);
    if (!spec.ok()) return spec.error();
    auto chunks = detail::laz::read_chunks(src, spec.value(), h.offset_to_point_data, data_end,
                                           h.point_count);
    if (!chunks.ok()) return chunks.error();
    if (copc_vlr != nullptr && copc_vlr->data) {
      auto parsed_info = parse_copc_info(*copc_vlr->data, size, name);
      if (!parsed_info.ok()) return parsed_info.error();
      s.copc = parsed_info.value();
      if (options.region || options.copc_max_depth >= 0) {
        auto selected = copc_chunks(src, *s.copc, s.evlrs, chunks.value(), options);
        if (!selected.ok()) return selected.error();
        s.copc_nodes_read = selected.value().size();
        s.readable = 0;
        for (const auto& c : selected.value()) s.readable += c.points;
        chunks = std::move(selected);
      }
    }
    s.laz = std::make_unique<detail::laz::LazRecords>(
        src, std::move(spec).value(), std::move(chunks).value(), h.record_length,
        options.all_attributes ? detail::laz::AllLayers : detail::laz::LayerZ);
  }

  // Extra bytes and their descriptors.
  const std::size_t extra_length = h.record_length - base_length;
  if (auto layout = parse_extra_bytes(name, s.vlrs, s.evlrs, extra_length, warnings)) {
    info.extra = std::move(layout);
  }

  // CRS records.
  parse_crs_records(h, s.vlrs, s.evlrs, s.crs);
  for (const auto& w : s.crs.warnings) warnings.push_back(name + ": " + w);

  // What the reader tells its users.
  s.decoding.format = h.point_format;
  s.decoding.record_length = h.record_length;
  s.decoding.base_length = base_length;
  s.decoding.extra_length = extra_length;
  s.decoding.scale = h.scale;
  s.decoding.offset = h.offset;
  for (int i = 0; i < 3; ++i) {
    if (!(h.scale[i] != 0.0) || !std::isfinite(h.scale[i]) || !std::isfinite(h.offset[i])) {
      return corrupt(name, std::string("scale/offset of ") + "xyz"[i] + " is " +
                               std::to_string(h.scale[i]) + " / " + std::to_string(h.offset[i]) +
                               " (the scale must be finite and non-zero)");
    }
  }
  info.format = PointFileFormat::Las;
  info.description = std::string(copc         ? "COPC (LAZ "
                                 : compressed ? "LAZ (LAS "
                                              : "LAS ") +
                     num(h.version_major) + "." + num(h.version_minor) + (compressed ? ")" : "") +
                     " point format " + num(h.point_format);
  if (compressed) info.description += ", " + s.laz->spec().describe();
  info.point_count = h.point_count;
  if (s.copc_nodes_read) {
    info.description += ", " + num(*s.copc_nodes_read) + " octree nodes of the region read";
    info.point_count = s.readable;  // the points of the nodes read
  }
  Bounds3 bounds;
  bounds.min = h.min;
  bounds.max = h.max;
  info.bounds = bounds;
  for (int i = 0; i < 3; ++i) {
    // Half a quantisation step, plus the rounding of the header's doubles.
    info.bounds_tolerance[i] =
        0.5 * std::abs(h.scale[i]) + 1e-9 * std::max(std::abs(h.min[i]), std::abs(h.max[i]));
  }
  info.fields = las_point_fields(h.point_format);
  return true;
}

// Records [first, first + n) as the uncompressed file holds them: read in place, or
// decoded from LAZ.
kernel::Status read_record_bytes(Parsed& file, std::uint64_t first, std::size_t n,
                                 std::uint8_t* out) {
  if (file.laz) return file.laz->read(first, n, out);
  const std::size_t length = file.decoding.record_length;
  const std::uint64_t at = file.header.offset_to_point_data + first * std::uint64_t{length};
  return file.source->read_at(at, std::span(out, n * length));
}

}  // namespace

struct LasReader::State {
  Parsed file;
  std::uint64_t next = 0;     // index of the next record to read
  std::uint64_t nan_gps = 0;  // records whose GPS time is NaN
  std::vector<std::uint8_t> chunk;
};

LasReader::LasReader(std::string name, PointCloudInfo info, PointReadOptions options,
                     std::unique_ptr<State> state)
    : PointReader(std::move(name), std::move(info), options), state_(std::move(state)) {}

LasReader::~LasReader() = default;

kernel::Result<std::unique_ptr<LasReader>> LasReader::open_source(
    std::unique_ptr<ByteSource> source, const PointReadOptions& options) {
  if (!source) return Error{ErrorCode::InvalidArgument, "LasReader::open_source: no source"};
  auto state = std::make_unique<State>();
  state->file.source = std::move(source);
  PointCloudInfo info;
  std::vector<std::string> warnings;
  auto parsed = parse_las(state->file, info, warnings, options);
  if (!parsed.ok()) return parsed.error();
  std::string name = state->file.source->name();
  std::unique_ptr<LasReader> reader(
      new LasReader(std::move(name), std::move(info), options, std::move(state)));
  for (auto& w : warnings) reader->warn(std::move(w));
  return reader;
}

kernel::Result<std::unique_ptr<LasReader>> LasReader::open(const std::filesystem::path& path,
                                                           const PointReadOptions& options) {
  auto source = detail::open_file_source(path);
  if (!source.ok()) return source.error();
  return open_source(std::move(source).value(), options);
}

kernel::Result<std::unique_ptr<LasReader>> LasReader::open_memory(
    std::string name, std::span<const std::uint8_t> bytes, const PointReadOptions& options) {
  return open_source(detail::memory_source(std::move(name), bytes), options);
}

const LasHeader& LasReader::header() const { return state_->file.header; }
const std::vector<LasRecord>& LasReader::vlrs() const { return state_->file.vlrs; }
const std::vector<LasRecord>& LasReader::evlrs() const { return state_->file.evlrs; }
const LasCrsRecords& LasReader::crs() const { return state_->file.crs; }
std::uint64_t LasReader::readable_points() const { return state_->file.readable; }
const std::optional<CopcInfo>& LasReader::copc() const { return state_->file.copc; }

kernel::Result<std::vector<CopcNode>> LasReader::copc_hierarchy() {
  if (!state_->file.copc) {
    return Error{ErrorCode::InvalidArgument, name() + ": not a COPC file (no copc info VLR)"};
  }
  return copc_nodes(*state_->file.source, *state_->file.copc, state_->file.evlrs);
}

kernel::Status LasReader::seek(std::uint64_t index) {
  if (index > state_->file.readable) {
    return {ErrorCode::InvalidArgument, name() + ": seek to point " + num(index) + " past the " +
                                            num(state_->file.readable) + " readable points"};
  }
  state_->next = index;
  return {};
}

kernel::Result<std::size_t> LasReader::read_records(PointBatch& batch, std::size_t max) {
  State& s = *state_;
  const Decoding& d = s.file.decoding;
  const std::uint64_t left = s.file.readable - s.next;
  const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(left, max));
  if (n == 0) return std::size_t{0};
  batch.points.resize(n);
  batch.extra_bytes.resize(n * d.extra_length);
  // Chunks of about kChunkBytes keep the buffer small and in cache whatever `max` is.
  const std::size_t per_chunk = std::max<std::size_t>(1, kChunkBytes / d.record_length);
  const Decoder decode = decoder_for(d.format);
  std::size_t done = 0;
  while (done < n) {
    const std::size_t k = std::min(per_chunk, n - done);
    s.chunk.resize(k * d.record_length);
    if (auto st = read_record_bytes(s.file, s.next + done, k, s.chunk.data()); !st.ok()) {
      return st.error();
    }
    s.nan_gps += decode(d, s.chunk.data(), k, batch.points.data() + done,
                        batch.extra_bytes.data() + done * d.extra_length);
    done += k;
  }
  s.next += n;
  return n;
}

bool LasReader::compressed() const { return state_->file.laz != nullptr; }

kernel::Result<std::size_t> LasReader::read_raw(std::vector<std::uint8_t>& out, std::size_t max) {
  State& s = *state_;
  const std::size_t length = s.file.decoding.record_length;
  const std::size_t n =
      static_cast<std::size_t>(std::min<std::uint64_t>(s.file.readable - s.next, max));
  out.resize(n * length);
  if (n == 0) return std::size_t{0};
  if (auto st = read_record_bytes(s.file, s.next, n, out.data()); !st.ok()) return st.error();
  s.next += n;
  return n;
}

void LasReader::finish() {
  if (state_->nan_gps > 0) {
    warn(name() + ": " + num(state_->nan_gps) + " points have a GPS time that is NaN");
  }
}

}  // namespace csgtile::geo
