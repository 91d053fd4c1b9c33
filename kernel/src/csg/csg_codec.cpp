// The native format's CSG section (tag 13, layout in io/native_layout.h): the CSG tree with
// its primitive parameters as raw doubles, and the face sources of the root shape.

#include <limits>

#include "csgtile/kernel/explorer.h"
#include "csgtile/kernel/native_format.h"
#include "io/byte_stream.h"
#include "io/native_layout.h"

namespace csgtile::kernel {

namespace {

using detail::ByteReader;
using detail::ByteWriter;

constexpr std::size_t kMaxLabel = 1 << 16;
// A Primitive node whose primitive has clips is written with this bit set in its kind byte,
// the clips (count, 4 f64 each) after its holes: files without clips keep their bytes, and
// a reader that knows no clips refuses the kind rather than drop them.
constexpr std::uint8_t kClippedBit = 0x80;

void write_points(ByteWriter& out, const std::vector<Vec2>& points) {
  out.varint(points.size());
  for (const Vec2& p : points) {
    out.f64le(p.x());
    out.f64le(p.y());
  }
}

std::vector<Vec2> read_points(ByteReader& in) {
  const std::size_t n = in.count(16, "profile point");
  std::vector<Vec2> points;
  points.reserve(n);
  for (std::size_t i = 0; i < n && !in.failed(); ++i) {
    const double x = in.f64le();
    const double y = in.f64le();
    points.emplace_back(x, y);
  }
  return points;
}

void write_primitive(ByteWriter& out, const PrimitiveSpec& p) {
  out.byte(static_cast<std::uint8_t>(p.type));
  const Location& l = p.placement;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out.f64le(l.rotation()(r, c));
  }
  out.f64le(l.scale());
  for (int k = 0; k < 3; ++k) out.f64le(l.translation()[k]);
  for (int k = 0; k < 3; ++k) out.f64le(p.size[k]);
  out.f64le(p.radius);
  out.f64le(p.radius2);
  out.f64le(p.height);
  out.f64le(p.angle);
  write_points(out, p.profile);
  out.varint(p.holes.size());
  for (const auto& hole : p.holes) write_points(out, hole);
  if (!p.clips.empty()) {
    out.varint(p.clips.size());
    for (const auto& c : p.clips) {
      for (int k = 0; k < 4; ++k) out.f64le(c[k]);
    }
  }
}

PrimitiveSpec read_primitive(ByteReader& in, bool clipped) {
  PrimitiveSpec p;
  const std::uint8_t type = in.byte();
  if (!in.failed() && type >= kPrimitiveTypeCount) {
    in.fail("primitive type " + std::to_string(type) + " is unknown");
    return p;
  }
  p.type = static_cast<PrimitiveType>(type);
  Eigen::Matrix3d rotation;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) rotation(r, c) = in.f64le();
  }
  const double scale = in.f64le();
  Vec3 translation;
  for (int k = 0; k < 3; ++k) translation[k] = in.f64le();
  for (int k = 0; k < 3; ++k) p.size[k] = in.f64le();
  p.radius = in.f64le();
  p.radius2 = in.f64le();
  p.height = in.f64le();
  p.angle = in.f64le();
  if (in.failed()) return p;
  auto placement = Location::from_parts(rotation, scale, translation);
  if (!placement.ok()) {
    in.fail("primitive placement: " + placement.error().message);
    return p;
  }
  p.placement = placement.value();
  p.profile = read_points(in);
  const std::size_t holes = in.count(1, "hole");
  for (std::size_t h = 0; h < holes && !in.failed(); ++h) p.holes.push_back(read_points(in));
  if (clipped) {
    const std::size_t clips = in.count(32, "clip");
    if (clips == 0 && !in.failed()) in.fail("a clipped primitive has no clip");
    for (std::size_t c = 0; c < clips && !in.failed(); ++c) {
      Eigen::Vector4d v;
      for (int k = 0; k < 4; ++k) v[k] = in.f64le();
      p.clips.push_back(v);
    }
  }
  return p;
}

std::string encode(const CsgModel& m) {
  ByteWriter out;
  out.varint(m.nodes.size());
  for (std::size_t i = 0; i < m.nodes.size(); ++i) {
    const CsgNode& node = m.nodes[i];
    const bool clipped = node.kind == CsgNodeKind::Primitive && !node.primitive.clips.empty();
    out.byte(static_cast<std::uint8_t>(static_cast<std::uint8_t>(node.kind) |
                                       (clipped ? kClippedBit : 0)));
    out.varint(node.label.size());
    out.bytes(node.label);
    if (node.kind == CsgNodeKind::Primitive) {
      write_primitive(out, node.primitive);
    } else {
      out.varint(node.children.size());
      for (int c : node.children) out.varint(i - static_cast<std::size_t>(c));
    }
  }
  out.varint(m.face_sources.size());
  for (const auto& list : m.face_sources) {
    out.varint(list.size());
    for (const FaceSource& s : list) {
      out.varint(static_cast<std::uint64_t>(s.node));
      out.varint(static_cast<std::uint64_t>(s.face));
    }
  }
  return out.take();
}

std::optional<Error> decode(ByteReader& in, CsgModel& m) {
  const std::size_t n = in.count(2, "CSG node");
  for (std::size_t i = 0; i < n && !in.failed(); ++i) {
    CsgNode node;
    std::uint8_t kind = in.byte();
    const bool clipped = (kind & kClippedBit) != 0 &&
                         (kind & ~kClippedBit) == static_cast<std::uint8_t>(CsgNodeKind::Primitive);
    if (clipped) kind = static_cast<std::uint8_t>(CsgNodeKind::Primitive);
    if (!in.failed() && kind > static_cast<std::uint8_t>(CsgNodeKind::Cut)) {
      in.fail("CSG node " + std::to_string(i) + " has unknown kind " + std::to_string(kind));
      break;
    }
    node.kind = static_cast<CsgNodeKind>(kind);
    const std::size_t label = in.count(1, "label byte");
    if (label > kMaxLabel) in.fail("CSG node label longer than 64 KiB");
    if (in.failed()) break;
    node.label.resize(label);
    for (std::size_t k = 0; k < label; ++k) node.label[k] = static_cast<char>(in.byte());
    if (node.kind == CsgNodeKind::Primitive) {
      node.primitive = read_primitive(in, clipped);
    } else {
      const std::size_t children = in.count(1, "CSG child");
      for (std::size_t k = 0; k < children && !in.failed(); ++k) {
        const std::uint64_t delta = in.varint();
        if (delta == 0 || delta > i) {
          in.fail("CSG node " + std::to_string(i) + " has a child delta " + std::to_string(delta) +
                  " that is not an earlier node");
          break;
        }
        node.children.push_back(static_cast<int>(i - delta));
      }
    }
    m.nodes.push_back(std::move(node));
  }
  const std::size_t faces = in.count(1, "face source list");
  m.face_sources.resize(faces);
  for (std::size_t f = 0; f < faces && !in.failed(); ++f) {
    const std::size_t k = in.count(2, "face source");
    for (std::size_t j = 0; j < k && !in.failed(); ++j) {
      const std::uint64_t node = in.varint();
      const std::uint64_t face = in.varint();
      if (node > static_cast<std::uint64_t>(std::numeric_limits<int>::max()) ||
          face > static_cast<std::uint64_t>(std::numeric_limits<int>::max())) {
        in.fail("face source index out of range");
        break;
      }
      m.face_sources[f].push_back({static_cast<int>(node), static_cast<int>(face)});
    }
  }
  if (in.failed())
    return Error{ErrorCode::CorruptData, "native format: csg section: " + in.error()};
  if (!in.at_end()) {
    return Error{
        ErrorCode::CorruptData,
        "native format: csg section: " + std::to_string(in.remaining()) + " bytes after its end"};
  }
  return std::nullopt;
}

}  // namespace

std::string write_native_model(const CsgModel& model) {
  if (model.nodes.empty() && model.face_sources.empty()) return write_native(model.shape);
  return detail::write_native_with(model.shape, detail::SectionTag::Csg, encode(model));
}

Result<CsgModel> read_native_model(std::string_view bytes) {
  detail::NativeExtra extra;
  extra.tag = static_cast<std::uint64_t>(detail::SectionTag::Csg);
  auto shape = detail::read_native_with(bytes, extra);
  if (!shape.ok()) return shape.error();
  CsgModel m;
  m.shape = shape.value();
  if (!extra.present) return m;
  ByteReader in(extra.payload, extra.offset);
  if (auto e = decode(in, m)) return *e;
  if (Status s = check_csg(m); !s.ok()) {
    return Error{ErrorCode::CorruptData, "native format: " + s.error().message};
  }
  return m;
}

Status write_native_model_file(const std::filesystem::path& path, const CsgModel& model) {
  return detail::write_file_atomically(path, write_native_model(model));
}

Result<CsgModel> read_native_model_file(const std::filesystem::path& path) {
  auto bytes = detail::read_whole_file(path);
  if (!bytes.ok()) return bytes.error();
  auto model = read_native_model(bytes.value());
  if (!model.ok()) return Error{model.error().code, path.string() + ": " + model.error().message};
  return model;
}

}  // namespace csgtile::kernel
