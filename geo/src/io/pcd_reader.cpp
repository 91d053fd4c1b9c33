// PCD (Point Cloud Library) 0.5-0.7: a text header (VERSION, FIELDS, SIZE, TYPE, COUNT,
// WIDTH, HEIGHT, VIEWPOINT, POINTS, DATA) and the data as ascii lines, binary records, or
// binary_compressed: two uint32 sizes and one LZF block whose content is stored field by
// field (all x, then all y, ...). Fields named after Point fields fill them (x y z,
// normal_x..z, rgb / rgba packed 0x00RRGGBB, intensity, ...); padding fields "_" are skipped;
// every other field becomes an extra dimension of its own type and count.

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>

#include "io/endian.h"
#include "io/lzf.h"
#include "io/readers.h"

namespace csgtile::geo::detail {

namespace {

using kernel::Error;
using kernel::ErrorCode;

enum class PcdData { Ascii, Binary, BinaryCompressed };

struct PcdField {
  std::string name;
  std::size_t size = 4;
  char type = 'F';
  std::size_t count = 1;
  std::size_t offset = 0;  // in a binary record
  ExtraType extra_type = ExtraType::F32;
  PointTarget target = PointTarget::None;
  bool padding = false;
  int extra_offset = -1;
};

std::optional<ExtraType> pcd_type(char type, std::size_t size) {
  switch (type) {
    case 'I':
      return size == 1   ? ExtraType::I8
             : size == 2 ? ExtraType::I16
             : size == 4 ? ExtraType::I32
             : size == 8 ? std::optional(ExtraType::I64)
                         : std::nullopt;
    case 'U':
      return size == 1   ? ExtraType::U8
             : size == 2 ? ExtraType::U16
             : size == 4 ? ExtraType::U32
             : size == 8 ? std::optional(ExtraType::U64)
                         : std::nullopt;
    case 'F':
      return size == 4 ? ExtraType::F32 : size == 8 ? std::optional(ExtraType::F64) : std::nullopt;
    default:
      return std::nullopt;
  }
}

double le_value(const std::uint8_t* p, ExtraType type) {
  switch (type) {
    case ExtraType::I8:
      return static_cast<std::int8_t>(p[0]);
    case ExtraType::U8:
      return p[0];
    case ExtraType::I16:
      return load_le<std::int16_t>(p);
    case ExtraType::U16:
      return load_le<std::uint16_t>(p);
    case ExtraType::I32:
      return load_le<std::int32_t>(p);
    case ExtraType::U32:
      return load_le<std::uint32_t>(p);
    case ExtraType::I64:
      return static_cast<double>(load_le<std::int64_t>(p));
    case ExtraType::U64:
      return static_cast<double>(load_le<std::uint64_t>(p));
    case ExtraType::F32:
      return load_le<float>(p);
    case ExtraType::F64:
      return load_le<double>(p);
    default:
      return 0;
  }
}

class PcdReader final : public PointReader {
 public:
  PcdReader(std::string name, PointCloudInfo info, PointReadOptions options,
            std::unique_ptr<ByteSource> source, std::unique_ptr<SequentialReader> data,
            PcdData kind, std::vector<PcdField> fields, std::size_t record_size,
            std::uint64_t readable, std::vector<std::uint8_t> decoded, bool float32_xyz)
      : PointReader(std::move(name), std::move(info), options),
        source_(std::move(source)),
        data_(std::move(data)),
        kind_(kind),
        fields_(std::move(fields)),
        record_size_(record_size),
        readable_(readable),
        decoded_(std::move(decoded)),
        float32_xyz_(float32_xyz) {
    for (const auto& f : fields_) tokens_per_line_ += f.count;
  }

  void note(std::string warning) { warn(std::move(warning)); }

 protected:
  kernel::Result<std::size_t> read_records(PointBatch& batch, std::size_t max) override {
    const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(max, readable_ - next_));
    if (n == 0) return std::size_t{0};
    const std::size_t stride = batch.extra_record_size();
    batch.points.assign(n, Point{});
    batch.extra_bytes.assign(n * stride, 0);
    std::size_t produced = n;
    if (kind_ == PcdData::Ascii) {
      auto got = read_ascii(batch, n, stride);
      if (!got.ok()) return got.error();
      produced = got.value();
    } else if (kind_ == PcdData::Binary) {
      chunk_.resize(n * record_size_);
      if (auto st = data_->read_exact(chunk_); !st.ok()) return st.error();
      for (std::size_t i = 0; i < n; ++i) {
        const std::uint8_t* record = chunk_.data() + i * record_size_;
        for (const auto& f : fields_) {
          store_binary(batch, i, stride, f, record + f.offset);
        }
      }
    } else {
      // Field-major: field f of point j sits at readable_·offset_f + j·size_f·count_f.
      for (std::size_t i = 0; i < n; ++i) {
        const std::uint64_t j = next_ + i;
        for (const auto& f : fields_) {
          const std::size_t width = f.size * f.count;
          const std::uint8_t* p = decoded_.data() + total_ * f.offset + j * width;
          store_binary(batch, i, stride, f, p);
        }
      }
    }
    if (float32_xyz_) {
      for (std::size_t i = 0; i < produced; ++i) {
        const Point& p = batch.points[i];
        if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) {
          precision_.add(std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)}));
        }
      }
    }
    next_ += produced;
    return produced;
  }

  void finish() override {
    if (auto w = precision_.warning(name())) warn(*w);
    decoded_.clear();
    decoded_.shrink_to_fit();
  }

 public:
  void set_total(std::uint64_t total) { total_ = total; }

 private:
  void store_binary(PointBatch& batch, std::size_t i, std::size_t stride, const PcdField& f,
                    const std::uint8_t* p) {
    if (f.padding) return;
    if (f.extra_offset >= 0) {
      std::memcpy(batch.extra_bytes.data() + i * stride + static_cast<std::size_t>(f.extra_offset),
                  p, f.size * f.count);
      return;
    }
    double v = 0;
    if (f.target == PointTarget::Rgb) {
      v = static_cast<double>(load_le<std::uint32_t>(p));  // the bits, even when TYPE is F
    } else {
      v = le_value(p, f.extra_type);
    }
    assign_target(batch.points[i], f.target, v, f.size == 1);
  }

  kernel::Result<std::size_t> read_ascii(PointBatch& batch, std::size_t n, std::size_t stride) {
    std::string_view line;
    std::size_t i = 0;
    while (i < n) {
      auto more = data_->next_line(line);
      if (!more.ok()) return more.error();
      if (!more.value()) {
        const std::string what = "truncated: the header declares " +
                                 std::to_string(info().point_count.value_or(0)) +
                                 " points, the data ends after " + std::to_string(next_ + i);
        if (!options().accept_truncated) return Error{ErrorCode::CorruptData, name() + ": " + what};
        warn(name() + ": " + what + "; reading those");
        readable_ = next_ + i;
        batch.points.resize(i);
        batch.extra_bytes.resize(i * stride);
        return i;
      }
      line = trim(line);
      if (line.empty() || line.front() == '#') continue;
      const auto tokens = split_fields(line);
      if (tokens.size() != tokens_per_line_) {
        return Error{ErrorCode::CorruptData,
                     name() + ": line " + std::to_string(data_->line_number()) + " has " +
                         std::to_string(tokens.size()) + " values, the header declares " +
                         std::to_string(tokens_per_line_)};
      }
      std::size_t t = 0;
      for (const auto& f : fields_) {
        for (std::size_t e = 0; e < f.count; ++e, ++t) {
          if (auto st = store_text(batch, i, stride, f, e, tokens[t]); !st.ok()) return st.error();
        }
      }
      ++i;
    }
    return i;
  }

  kernel::Status store_text(PointBatch& batch, std::size_t i, std::size_t stride, const PcdField& f,
                            std::size_t element, std::string_view token) {
    auto not_a_number = [&] {
      return kernel::Status{ErrorCode::CorruptData,
                            name() + ": line " + std::to_string(data_->line_number()) +
                                ", field \"" + f.name + "\": \"" +
                                std::string(token.substr(0, 40)) + "\" is not a number"};
    };
    if (f.padding) return {};
    std::uint8_t bytes[8] = {};
    // Integers are parsed as integers to keep 64-bit values exact.
    if (f.type == 'U') {
      const auto v = parse_number<std::uint64_t>(token);
      if (!v) return not_a_number();
      store_le<std::uint64_t>(bytes, *v);
    } else if (f.type == 'I') {
      const auto v = parse_number<std::int64_t>(token);
      if (!v) return not_a_number();
      store_le<std::int64_t>(bytes, *v);
    } else {
      const auto v = parse_number<double>(token);
      if (!v) return not_a_number();
      if (f.size == 4)
        store_le<float>(bytes, static_cast<float>(*v));
      else
        store_le<double>(bytes, *v);
    }
    if (f.extra_offset >= 0) {
      // Little-endian truncation of the 64-bit integer keeps the low bytes: the value itself
      // when it fits the field.
      std::memcpy(batch.extra_bytes.data() + i * stride + static_cast<std::size_t>(f.extra_offset) +
                      element * f.size,
                  bytes, f.size);
      return {};
    }
    store_binary(batch, i, stride, f, bytes);
    return {};
  }

  std::unique_ptr<ByteSource> source_;
  std::unique_ptr<SequentialReader> data_;
  PcdData kind_;
  std::vector<PcdField> fields_;
  std::size_t record_size_;
  std::uint64_t readable_;
  std::uint64_t total_ = 0;  // points in the compressed block (field stride)
  std::uint64_t next_ = 0;
  std::size_t tokens_per_line_ = 0;
  std::vector<std::uint8_t> decoded_;
  bool float32_xyz_;
  Float32PrecisionCheck precision_;
  std::vector<std::uint8_t> chunk_;
};

}  // namespace

kernel::Result<std::unique_ptr<PointReader>> open_pcd(std::unique_ptr<ByteSource> source,
                                                      const PointReadOptions& options) {
  const std::string name = source->name();
  auto data = std::make_unique<SequentialReader>(*source, 0);
  auto bad = [&](const std::string& what) {
    return Error{ErrorCode::CorruptData,
                 name + ": PCD header line " + std::to_string(data->line_number()) + ": " + what};
  };
  std::vector<std::string> names;
  std::vector<std::size_t> sizes, counts;
  std::vector<char> types;
  std::optional<std::uint64_t> width, height, points;
  std::optional<PcdData> kind;
  std::string version;
  std::string viewpoint;
  std::string_view line;
  for (std::size_t lines = 0; !kind; ++lines) {
    if (lines > 10000) return bad("more than 10000 header lines");
    auto more = data->next_line(line);
    if (!more.ok()) return more.error();
    if (!more.value()) return bad("the file ends before the DATA line");
    line = trim(line);
    if (line.empty() || line.front() == '#') continue;
    const auto t = split_fields(line);
    const std::string_view key = t[0];
    auto numbers = [&](std::vector<std::size_t>& out) -> bool {
      for (std::size_t k = 1; k < t.size(); ++k) {
        const auto v = parse_number<std::size_t>(t[k]);
        if (!v) return false;
        out.push_back(*v);
      }
      return true;
    };
    auto one = [&](std::optional<std::uint64_t>& out) -> bool {
      if (t.size() != 2) return false;
      out = parse_number<std::uint64_t>(t[1]);
      return out.has_value();
    };
    if (key == "VERSION") {
      version = t.size() > 1 ? std::string(t[1]) : "";
    } else if (key == "FIELDS" || key == "COLUMNS") {
      for (std::size_t k = 1; k < t.size(); ++k) names.emplace_back(t[k]);
    } else if (key == "SIZE") {
      if (!numbers(sizes)) return bad("SIZE values must be numbers");
    } else if (key == "COUNT") {
      if (!numbers(counts)) return bad("COUNT values must be numbers");
    } else if (key == "TYPE") {
      for (std::size_t k = 1; k < t.size(); ++k) {
        if (t[k].size() != 1) return bad("TYPE values are I, U or F");
        types.push_back(t[k][0]);
      }
    } else if (key == "WIDTH") {
      if (!one(width)) return bad("WIDTH needs one number");
    } else if (key == "HEIGHT") {
      if (!one(height)) return bad("HEIGHT needs one number");
    } else if (key == "POINTS") {
      if (!one(points)) return bad("POINTS needs one number");
    } else if (key == "VIEWPOINT") {
      viewpoint = std::string(line.substr(9));
    } else if (key == "DATA") {
      if (t.size() != 2) return bad("DATA needs one of ascii, binary, binary_compressed");
      if (t[1] == "ascii")
        kind = PcdData::Ascii;
      else if (t[1] == "binary")
        kind = PcdData::Binary;
      else if (t[1] == "binary_compressed")
        kind = PcdData::BinaryCompressed;
      else {
        return Error{ErrorCode::Unsupported,
                     name + ": PCD DATA \"" + std::string(t[1].substr(0, 40)) +
                         "\" is not supported (ascii, binary, binary_compressed)"};
      }
    } else {
      return bad("unknown keyword \"" + std::string(key.substr(0, 40)) + "\"");
    }
  }
  if (names.empty()) return bad("no FIELDS");
  if (counts.empty()) counts.assign(names.size(), 1);
  if (sizes.size() != names.size() || types.size() != names.size() ||
      counts.size() != names.size()) {
    return bad("FIELDS has " + std::to_string(names.size()) + " entries but SIZE " +
               std::to_string(sizes.size()) + ", TYPE " + std::to_string(types.size()) +
               ", COUNT " + std::to_string(counts.size()));
  }
  if (!width) return bad("no WIDTH");
  if (!height) height = 1;
  if (*height != 0 && *width > std::numeric_limits<std::uint64_t>::max() / *height) {
    return bad("WIDTH × HEIGHT overflows");
  }
  const std::uint64_t total = *width * *height;
  if (points && *points != total) {
    return bad("POINTS " + std::to_string(*points) +
               " disagrees with WIDTH × HEIGHT = " + std::to_string(*width) + " × " +
               std::to_string(*height) + " = " + std::to_string(total));
  }

  std::vector<PcdField> fields;
  std::size_t record_size = 0;
  auto layout = std::make_shared<ExtraLayout>();
  PointCloudInfo info;
  bool has_xyz[3] = {false, false, false};
  bool float32_xyz = false;
  for (std::size_t k = 0; k < names.size(); ++k) {
    PcdField f;
    f.name = names[k];
    f.size = sizes[k];
    f.type = types[k];
    f.count = counts[k];
    const auto type = pcd_type(f.type, f.size);
    if (!type) {
      return bad("field \"" + f.name + "\" has TYPE " + std::string(1, f.type) + " with SIZE " +
                 std::to_string(f.size) + " (I/U: 1, 2, 4, 8; F: 4, 8)");
    }
    if (f.count == 0 || f.count > 65536) {
      return bad("field \"" + f.name + "\" has COUNT " + std::to_string(f.count));
    }
    f.extra_type = *type;
    f.offset = record_size;
    record_size += f.size * f.count;
    if (record_size > (1u << 20)) return bad("records longer than 1 MiB");
    f.padding = f.name == "_";
    PointTarget target = f.count == 1 && !f.padding ? point_target(f.name) : PointTarget::None;
    if (target == PointTarget::Rgb && f.size != 4) target = PointTarget::None;
    if (target == PointTarget::X || target == PointTarget::Y || target == PointTarget::Z) {
      const int axis = static_cast<int>(target) - static_cast<int>(PointTarget::X);
      if (has_xyz[axis]) {
        target = PointTarget::None;
      } else {
        has_xyz[axis] = true;
        if (f.extra_type == ExtraType::F32) float32_xyz = true;
      }
    }
    f.target = target;
    if (target == PointTarget::None && !f.padding) {
      ExtraDimension d;
      d.name = f.name;
      d.type = f.extra_type;
      d.elements = static_cast<int>(f.count);
      d.byte_offset = layout->record_size;
      f.extra_offset = static_cast<int>(layout->record_size);
      layout->record_size += f.size * f.count;
      layout->dimensions.push_back(std::move(d));
    } else if (target != PointTarget::None) {
      mark_field(info.fields, target);
    }
    fields.push_back(std::move(f));
  }
  if (!(has_xyz[0] && has_xyz[1] && has_xyz[2])) {
    return Error{ErrorCode::CorruptData, name + ": PCD FIELDS lack x, y or z"};
  }
  if (!layout->dimensions.empty()) info.extra = std::move(layout);
  info.format = PointFileFormat::Pcd;
  info.description = "PCD " + (version.empty() ? std::string("?") : version) + " " +
                     (*kind == PcdData::Ascii    ? "ascii"
                      : *kind == PcdData::Binary ? "binary"
                                                 : "binary_compressed") +
                     ", " + std::to_string(*width) + " × " + std::to_string(*height);
  if (!viewpoint.empty() && split_fields(viewpoint) != split_fields("0 0 0 1 0 0 0")) {
    info.description += ", viewpoint " + std::string(trim(viewpoint));
  }
  info.point_count = total;

  std::uint64_t readable = total;
  std::vector<std::string> warnings;
  std::vector<std::uint8_t> decoded;
  if (*kind == PcdData::Binary) {
    if (total > data->remaining() / record_size) {
      const std::uint64_t complete = data->remaining() / record_size;
      const std::string what = "truncated: the header declares " + std::to_string(total) +
                               " points of " + std::to_string(record_size) +
                               " bytes, the file holds " + std::to_string(complete);
      if (!options.accept_truncated) return Error{ErrorCode::CorruptData, name + ": " + what};
      warnings.push_back(name + ": " + what + "; reading those");
      readable = complete;
    }
  } else if (*kind == PcdData::BinaryCompressed) {
    std::uint8_t sizes_bytes[8];
    if (auto st = data->read_exact(sizes_bytes); !st.ok()) {
      return Error{ErrorCode::CorruptData,
                   name + ": binary_compressed data ends before its two size fields"};
    }
    const std::uint32_t compressed = load_le<std::uint32_t>(sizes_bytes);
    const std::uint32_t uncompressed = load_le<std::uint32_t>(sizes_bytes + 4);
    if (compressed > data->remaining()) {
      return Error{ErrorCode::CorruptData, name + ": truncated: compressed size " +
                                               std::to_string(compressed) +
                                               " passes the end of the file (" +
                                               std::to_string(data->remaining()) + " bytes left)"};
    }
    if (total > 0 && record_size > std::numeric_limits<std::uint64_t>::max() / total) {
      return Error{ErrorCode::CorruptData, name + ": POINTS × record size overflows"};
    }
    if (std::uint64_t{uncompressed} != total * record_size) {
      return Error{ErrorCode::CorruptData,
                   name + ": uncompressed size " + std::to_string(uncompressed) +
                       " is not POINTS × record size = " + std::to_string(total) + " × " +
                       std::to_string(record_size) + " = " + std::to_string(total * record_size)};
    }
    // LZF produces at most 264 bytes per 3 input bytes: a larger claim is a lie, found
    // before allocating for it.
    if (std::uint64_t{uncompressed} > 88 * std::uint64_t{compressed}) {
      return Error{ErrorCode::CorruptData,
                   name + ": uncompressed size " + std::to_string(uncompressed) +
                       " cannot come from " + std::to_string(compressed) + " LZF-compressed bytes"};
    }
    std::vector<std::uint8_t> packed(compressed);
    if (auto st = data->read_exact(packed); !st.ok()) return st.error();
    decoded.resize(uncompressed);
    std::string error;
    const auto produced = lzf_decompress(packed, decoded, &error);
    if (!produced) {
      return Error{ErrorCode::CorruptData, name + ": binary_compressed data: " + error};
    }
    if (*produced != uncompressed) {
      return Error{ErrorCode::CorruptData,
                   name + ": binary_compressed data decodes to " + std::to_string(*produced) +
                       " bytes, the header says " + std::to_string(uncompressed)};
    }
  }
  auto reader = std::make_unique<PcdReader>(name, std::move(info), options, std::move(source),
                                            std::move(data), *kind, std::move(fields), record_size,
                                            readable, std::move(decoded), float32_xyz);
  reader->set_total(total);
  for (auto& w : warnings) reader->note(std::move(w));
  return std::unique_ptr<PointReader>(std::move(reader));
}

}  // namespace csgtile::geo::detail
