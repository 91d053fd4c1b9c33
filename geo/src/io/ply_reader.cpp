// PLY (Turk, Stanford): "ply", "format ascii|binary_little_endian|binary_big_endian 1.0",
// element and property declarations, "end_header", then the elements in declared order. Only
// the "vertex" element is read; elements before it are skipped (checked), those after it are
// ignored. Vertex properties named after Point fields fill them; the others become extra
// dimensions of their own type.

#include <algorithm>
#include <cmath>
#include <cstring>

#include "io/endian.h"
#include "io/readers.h"

namespace csgtile::geo::detail {

namespace {

using kernel::Error;
using kernel::ErrorCode;

enum class PlyEncoding { Ascii, BinaryLittle, BinaryBig };

struct PlyType {
  ExtraType type = ExtraType::U8;
  std::size_t size = 1;
};

std::optional<PlyType> ply_type(std::string_view name) {
  struct Entry {
    const char* name;
    ExtraType type;
  };
  static constexpr Entry kTypes[] = {
      {"char", ExtraType::I8},     {"int8", ExtraType::I8},     {"uchar", ExtraType::U8},
      {"uint8", ExtraType::U8},    {"short", ExtraType::I16},   {"int16", ExtraType::I16},
      {"ushort", ExtraType::U16},  {"uint16", ExtraType::U16},  {"int", ExtraType::I32},
      {"int32", ExtraType::I32},   {"uint", ExtraType::U32},    {"uint32", ExtraType::U32},
      {"float", ExtraType::F32},   {"float32", ExtraType::F32}, {"double", ExtraType::F64},
      {"float64", ExtraType::F64},
  };
  for (const auto& e : kTypes) {
    if (name == e.name) return PlyType{e.type, extra_type_size(e.type)};
  }
  return std::nullopt;
}

struct PlyProperty {
  std::string name;
  PlyType type;
  bool is_list = false;
  PlyType count_type;
  std::size_t offset = 0;  // in a binary vertex record
  PointTarget target = PointTarget::None;
  int extra_offset = -1;  // in a point's extra bytes, or -1
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;
  bool has_list = false;
  std::size_t record_size = 0;  // fixed part (binary)
};

// A binary value as double (integers up to 32 bits are exact).
double binary_value(const std::uint8_t* p, ExtraType type, bool big) {
  auto load = [&](auto tag) {
    using T = decltype(tag);
    return static_cast<double>(big ? load_be<T>(p) : load_le<T>(p));
  };
  switch (type) {
    case ExtraType::I8:
      return static_cast<std::int8_t>(p[0]);
    case ExtraType::U8:
      return p[0];
    case ExtraType::I16:
      return load(std::int16_t{});
    case ExtraType::U16:
      return load(std::uint16_t{});
    case ExtraType::I32:
      return load(std::int32_t{});
    case ExtraType::U32:
      return load(std::uint32_t{});
    case ExtraType::F32:
      return load(float{});
    case ExtraType::F64:
      return load(double{});
    default:
      return 0;
  }
}

// Stores a text value in an extra slot of `type`, little-endian.
void store_extra(std::uint8_t* at, ExtraType type, double v) {
  switch (type) {
    case ExtraType::I8:
      at[0] = static_cast<std::uint8_t>(static_cast<std::int8_t>(v));
      break;
    case ExtraType::U8:
      at[0] = static_cast<std::uint8_t>(v);
      break;
    case ExtraType::I16:
      store_le<std::int16_t>(at, static_cast<std::int16_t>(v));
      break;
    case ExtraType::U16:
      store_le<std::uint16_t>(at, static_cast<std::uint16_t>(v));
      break;
    case ExtraType::I32:
      store_le<std::int32_t>(at, static_cast<std::int32_t>(v));
      break;
    case ExtraType::U32:
      store_le<std::uint32_t>(at, static_cast<std::uint32_t>(v));
      break;
    case ExtraType::F32:
      store_le<float>(at, static_cast<float>(v));
      break;
    case ExtraType::F64:
      store_le<double>(at, v);
      break;
    default:
      break;
  }
}

bool is_color(PointTarget t) {
  return t == PointTarget::Red || t == PointTarget::Green || t == PointTarget::Blue ||
         t == PointTarget::Nir;
}

class PlyReader final : public PointReader {
 public:
  PlyReader(std::string name, PointCloudInfo info, PointReadOptions options,
            std::unique_ptr<ByteSource> source, std::unique_ptr<SequentialReader> data,
            PlyEncoding encoding, PlyElement vertex, std::uint64_t readable, bool float32_xyz)
      : PointReader(std::move(name), std::move(info), options),
        source_(std::move(source)),
        data_(std::move(data)),
        encoding_(encoding),
        vertex_(std::move(vertex)),
        readable_(readable),
        float32_xyz_(float32_xyz) {}

 protected:
  kernel::Result<std::size_t> read_records(PointBatch& batch, std::size_t max) override {
    const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(max, readable_ - next_));
    if (n == 0) return std::size_t{0};
    const std::size_t stride = batch.extra_record_size();
    batch.points.assign(n, Point{});
    batch.extra_bytes.assign(n * stride, 0);
    if (encoding_ == PlyEncoding::Ascii) {
      std::string_view line;
      for (std::size_t i = 0; i < n; ++i) {
        auto more = data_->next_line(line);
        if (!more.ok()) return more.error();
        if (!more.value()) {
          if (!options().accept_truncated) return truncated(next_ + i);
          warn(truncated(next_ + i).message + "; reading those");
          readable_ = next_ + i;
          batch.points.resize(i);
          batch.extra_bytes.resize(i * stride);
          next_ += i;
          return i;
        }
        const auto tokens = split_fields(line);
        if (tokens.size() != vertex_.properties.size()) {
          return Error{ErrorCode::CorruptData,
                       name() + ": vertex " + std::to_string(next_ + i) + " (line " +
                           std::to_string(data_->line_number()) + ") has " +
                           std::to_string(tokens.size()) + " values, the header declares " +
                           std::to_string(vertex_.properties.size()) + " properties"};
        }
        for (std::size_t k = 0; k < tokens.size(); ++k) {
          const auto v = parse_number<double>(tokens[k]);
          if (!v) {
            return Error{ErrorCode::CorruptData,
                         name() + ": vertex " + std::to_string(next_ + i) + ", property \"" +
                             vertex_.properties[k].name + "\": \"" +
                             std::string(tokens[k].substr(0, 40)) + "\" is not a number"};
          }
          store(batch, i, stride, vertex_.properties[k], *v, nullptr);
        }
      }
    } else {
      const bool big = encoding_ == PlyEncoding::BinaryBig;
      chunk_.resize(n * vertex_.record_size);
      if (auto st = data_->read_exact(chunk_); !st.ok()) return st.error();
      for (std::size_t i = 0; i < n; ++i) {
        const std::uint8_t* record = chunk_.data() + i * vertex_.record_size;
        for (const auto& prop : vertex_.properties) {
          const std::uint8_t* p = record + prop.offset;
          store(batch, i, stride, prop, binary_value(p, prop.type.type, big), p);
        }
      }
    }
    if (float32_xyz_) {
      for (const auto& p : batch.points) {
        precision_.add(std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)}));
      }
    }
    next_ += n;
    return n;
  }

 public:
  void note(std::string warning) { warn(std::move(warning)); }

 protected:
  void finish() override {
    if (auto w = precision_.warning(name())) warn(*w);
  }

 private:
  Error truncated(std::uint64_t got) const {
    return Error{ErrorCode::CorruptData,
                 name() + ": truncated: the header declares " + std::to_string(vertex_.count) +
                     " vertices, the data ends after " + std::to_string(got)};
  }

  void store(PointBatch& batch, std::size_t i, std::size_t stride, const PlyProperty& prop,
             double v, const std::uint8_t* raw) {
    if (prop.extra_offset >= 0) {
      std::uint8_t* at =
          batch.extra_bytes.data() + i * stride + static_cast<std::size_t>(prop.extra_offset);
      if (raw != nullptr) {
        std::memcpy(at, raw, prop.type.size);
        if (encoding_ == PlyEncoding::BinaryBig) std::reverse(at, at + prop.type.size);
      } else {
        store_extra(at, prop.type.type, v);
      }
      return;
    }
    const bool floating = prop.type.type == ExtraType::F32 || prop.type.type == ExtraType::F64;
    if (is_color(prop.target) && floating) v *= 65535.0;  // float colours are 0-1
    assign_target(batch.points[i], prop.target, v, prop.type.type == ExtraType::U8);
  }

  std::unique_ptr<ByteSource> source_;
  std::unique_ptr<SequentialReader> data_;
  PlyEncoding encoding_;
  PlyElement vertex_;
  std::uint64_t readable_;
  std::uint64_t next_ = 0;
  bool float32_xyz_;
  Float32PrecisionCheck precision_;
  std::vector<std::uint8_t> chunk_;
};

}  // namespace

kernel::Result<std::unique_ptr<PointReader>> open_ply(std::unique_ptr<ByteSource> source,
                                                      const PointReadOptions& options) {
  const std::string name = source->name();
  auto data = std::make_unique<SequentialReader>(*source, 0);
  auto bad = [&](const std::string& what) {
    return Error{ErrorCode::CorruptData,
                 name + ": PLY header line " + std::to_string(data->line_number()) + ": " + what};
  };
  constexpr std::size_t kMaxDeclarations = 10000;  // a header is small; refuse runaway ones
  std::string_view line;
  std::optional<PlyEncoding> encoding;
  std::vector<PlyElement> elements;
  std::size_t declarations = 0;
  bool ended = false;
  while (!ended) {
    auto more = data->next_line(line);
    if (!more.ok()) return more.error();
    if (!more.value()) return bad("the file ends before \"end_header\"");
    if (++declarations > kMaxDeclarations) return bad("more than 10000 header lines");
    const auto t = split_fields(line);
    if (data->line_number() == 1) {
      if (t.size() != 1 || t[0] != "ply") return bad("the first line is not \"ply\"");
      continue;
    }
    if (t.empty() || t[0] == "comment" || t[0] == "obj_info") continue;
    if (t[0] == "format") {
      if (t.size() != 3) return bad("\"format\" needs an encoding and a version");
      if (t[1] == "ascii")
        encoding = PlyEncoding::Ascii;
      else if (t[1] == "binary_little_endian")
        encoding = PlyEncoding::BinaryLittle;
      else if (t[1] == "binary_big_endian")
        encoding = PlyEncoding::BinaryBig;
      else
        return bad("unknown format \"" + std::string(t[1]) + "\"");
      if (t[2] != "1.0") return bad("PLY version " + std::string(t[2]) + " (1.0 expected)");
    } else if (t[0] == "element") {
      if (t.size() != 3) return bad("\"element\" needs a name and a count");
      const auto count = parse_number<std::uint64_t>(t[2]);
      if (!count) return bad("element count \"" + std::string(t[2]) + "\" is not a number");
      elements.push_back(PlyElement{std::string(t[1]), *count, {}, false, 0});
    } else if (t[0] == "property") {
      if (elements.empty()) return bad("a property before any element");
      PlyProperty prop;
      if (t.size() == 5 && t[1] == "list") {
        const auto count_type = ply_type(t[2]);
        const auto item_type = ply_type(t[3]);
        if (!count_type || !item_type || count_type->type == ExtraType::F32 ||
            count_type->type == ExtraType::F64) {
          return bad("bad list types \"" + std::string(t[2]) + " " + std::string(t[3]) + "\"");
        }
        prop.is_list = true;
        prop.count_type = *count_type;
        prop.type = *item_type;
        prop.name = std::string(t[4]);
        elements.back().has_list = true;
      } else if (t.size() == 3) {
        const auto type = ply_type(t[1]);
        if (!type) return bad("unknown property type \"" + std::string(t[1]) + "\"");
        prop.type = *type;
        prop.name = std::string(t[2]);
        prop.offset = elements.back().record_size;
        elements.back().record_size += type->size;
      } else {
        return bad("malformed property declaration");
      }
      elements.back().properties.push_back(std::move(prop));
    } else if (t[0] == "end_header") {
      ended = true;
    } else {
      return bad("unknown keyword \"" + std::string(t[0].substr(0, 40)) + "\"");
    }
  }
  if (!encoding) return bad("no \"format\" line");
  const auto vertex_it = std::find_if(elements.begin(), elements.end(),
                                      [](const PlyElement& e) { return e.name == "vertex"; });
  if (vertex_it == elements.end()) {
    return Error{ErrorCode::CorruptData, name + ": PLY has no \"vertex\" element"};
  }
  PlyElement vertex = *vertex_it;
  if (vertex.has_list) {
    return Error{ErrorCode::Unsupported,
                 name + ": PLY vertex element has a list property; not supported for points"};
  }

  // Skip the elements before the vertices, checking each against the data present.
  const bool binary = *encoding != PlyEncoding::Ascii;
  const bool big = *encoding == PlyEncoding::BinaryBig;
  for (auto it = elements.begin(); it != vertex_it; ++it) {
    const PlyElement& e = *it;
    auto short_of = [&](std::uint64_t index) {
      return Error{ErrorCode::CorruptData, name + ": truncated: element \"" + e.name +
                                               "\" declares " + std::to_string(e.count) +
                                               " records, the data ends in record " +
                                               std::to_string(index)};
    };
    if (!binary) {
      for (std::uint64_t i = 0; i < e.count; ++i) {
        auto more = data->next_line(line);
        if (!more.ok()) return more.error();
        if (!more.value()) return short_of(i);
      }
    } else if (!e.has_list) {
      if (e.record_size != 0 && e.count > data->remaining() / e.record_size)
        return short_of(data->remaining() / e.record_size);
      if (auto st = data->skip(e.count * e.record_size); !st.ok()) return st.error();
    } else {
      std::uint8_t value[8];
      for (std::uint64_t i = 0; i < e.count; ++i) {
        for (const auto& prop : e.properties) {
          if (!prop.is_list) {
            if (!data->skip(prop.type.size).ok()) return short_of(i);
            continue;
          }
          if (!data->read_exact(std::span(value, prop.count_type.size)).ok()) return short_of(i);
          const double items = binary_value(value, prop.count_type.type, big);
          if (items < 0) {
            return Error{ErrorCode::CorruptData, name + ": element \"" + e.name + "\" record " +
                                                     std::to_string(i) +
                                                     " has a negative list size"};
          }
          if (!data->skip(static_cast<std::uint64_t>(items) * prop.type.size).ok())
            return short_of(i);
        }
      }
    }
  }

  PointCloudInfo info;
  info.format = PointFileFormat::Ply;
  info.description =
      std::string("PLY ") + (*encoding == PlyEncoding::Ascii          ? "ascii"
                             : *encoding == PlyEncoding::BinaryLittle ? "binary_little_endian"
                                                                      : "binary_big_endian");
  info.point_count = vertex.count;
  auto layout = std::make_shared<ExtraLayout>();
  bool has_xyz[3] = {false, false, false};
  bool float32_xyz = false;
  for (auto& prop : vertex.properties) {
    PointTarget target = point_target(prop.name);
    if (target == PointTarget::Rgb) target = PointTarget::None;
    if (target == PointTarget::X || target == PointTarget::Y || target == PointTarget::Z) {
      const int axis = static_cast<int>(target) - static_cast<int>(PointTarget::X);
      if (has_xyz[axis]) {
        target = PointTarget::None;
      } else {
        has_xyz[axis] = true;
        if (prop.type.type == ExtraType::F32) float32_xyz = true;
      }
    }
    prop.target = target;
    if (target == PointTarget::None) {
      ExtraDimension d;
      d.name = prop.name;
      d.type = prop.type.type;
      d.byte_offset = layout->record_size;
      prop.extra_offset = static_cast<int>(layout->record_size);
      layout->record_size += prop.type.size;
      layout->dimensions.push_back(std::move(d));
    } else {
      mark_field(info.fields, target);
    }
  }
  if (!(has_xyz[0] && has_xyz[1] && has_xyz[2])) {
    return Error{ErrorCode::CorruptData, name + ": PLY vertex element lacks x, y or z"};
  }
  if (!layout->dimensions.empty()) info.extra = std::move(layout);

  std::uint64_t readable = vertex.count;
  std::vector<std::string> warnings;
  if (binary && vertex.record_size > 0 && vertex.count > data->remaining() / vertex.record_size) {
    const std::uint64_t complete = data->remaining() / vertex.record_size;
    const std::string what = "truncated: the header declares " + std::to_string(vertex.count) +
                             " vertices of " + std::to_string(vertex.record_size) +
                             " bytes, the file holds " + std::to_string(complete);
    if (!options.accept_truncated) return Error{ErrorCode::CorruptData, name + ": " + what};
    warnings.push_back(name + ": " + what + "; reading those");
    readable = complete;
  }
  auto reader = std::make_unique<PlyReader>(name, std::move(info), options, std::move(source),
                                            std::move(data), *encoding, std::move(vertex), readable,
                                            float32_xyz);
  for (auto& w : warnings) reader->note(std::move(w));
  return std::unique_ptr<PointReader>(std::move(reader));
}

}  // namespace csgtile::geo::detail
