#include "csgtile/geo/point.h"

#include <algorithm>
#include <cstring>

#include "io/endian.h"

namespace csgtile::geo {

static_assert(sizeof(Point) == 72, "Point is documented as 72 bytes; update point.h");

void Bounds3::add(double x, double y, double z) {
  min[0] = std::min(min[0], x);
  min[1] = std::min(min[1], y);
  min[2] = std::min(min[2], z);
  max[0] = std::max(max[0], x);
  max[1] = std::max(max[1], y);
  max[2] = std::max(max[2], z);
}

void Bounds3::add(const Bounds3& other) {
  if (other.empty()) return;
  add(other.min[0], other.min[1], other.min[2]);
  add(other.max[0], other.max[1], other.max[2]);
}

bool Bounds3::contains(double x, double y, double z, const std::array<double, 3>& tolerance) const {
  const double v[3] = {x, y, z};
  for (int i = 0; i < 3; ++i) {
    if (!(v[i] >= min[i] - tolerance[i] && v[i] <= max[i] + tolerance[i])) return false;
  }
  return true;
}

std::size_t extra_type_size(ExtraType type) {
  switch (type) {
    case ExtraType::Raw:
    case ExtraType::U8:
    case ExtraType::I8:
      return 1;
    case ExtraType::U16:
    case ExtraType::I16:
      return 2;
    case ExtraType::U32:
    case ExtraType::I32:
    case ExtraType::F32:
      return 4;
    case ExtraType::U64:
    case ExtraType::I64:
    case ExtraType::F64:
      return 8;
  }
  return 1;
}

const char* extra_type_name(ExtraType type) {
  switch (type) {
    case ExtraType::Raw:
      return "raw";
    case ExtraType::U8:
      return "uint8";
    case ExtraType::I8:
      return "int8";
    case ExtraType::U16:
      return "uint16";
    case ExtraType::I16:
      return "int16";
    case ExtraType::U32:
      return "uint32";
    case ExtraType::I32:
      return "int32";
    case ExtraType::U64:
      return "uint64";
    case ExtraType::I64:
      return "int64";
    case ExtraType::F32:
      return "float32";
    case ExtraType::F64:
      return "float64";
  }
  return "raw";
}

const ExtraDimension* ExtraLayout::find(std::string_view name) const {
  for (const auto& d : dimensions) {
    if (d.name == name) return &d;
  }
  return nullptr;
}

std::size_t ExtraLayout::undescribed_bytes() const {
  std::size_t described = 0;
  for (const auto& d : dimensions) described += d.size();
  return described >= record_size ? 0 : record_size - described;
}

std::optional<ExtraValue> decode_extra(const ExtraDimension& dimension,
                                       std::span<const std::uint8_t> point_extra, int element) {
  if (dimension.type == ExtraType::Raw || element < 0 || element >= dimension.elements) {
    return std::nullopt;
  }
  const std::size_t width = extra_type_size(dimension.type);
  const std::size_t at = dimension.byte_offset + width * static_cast<std::size_t>(element);
  if (at + width > point_extra.size()) return std::nullopt;
  const std::uint8_t* p = point_extra.data() + at;
  using detail::load_le;
  switch (dimension.type) {
    case ExtraType::U8:
      return ExtraValue(std::uint64_t{p[0]});
    case ExtraType::I8:
      return ExtraValue(std::int64_t{static_cast<std::int8_t>(p[0])});
    case ExtraType::U16:
      return ExtraValue(std::uint64_t{load_le<std::uint16_t>(p)});
    case ExtraType::I16:
      return ExtraValue(std::int64_t{load_le<std::int16_t>(p)});
    case ExtraType::U32:
      return ExtraValue(std::uint64_t{load_le<std::uint32_t>(p)});
    case ExtraType::I32:
      return ExtraValue(std::int64_t{load_le<std::int32_t>(p)});
    case ExtraType::U64:
      return ExtraValue(load_le<std::uint64_t>(p));
    case ExtraType::I64:
      return ExtraValue(load_le<std::int64_t>(p));
    case ExtraType::F32:
      return ExtraValue(double{load_le<float>(p)});
    case ExtraType::F64:
      return ExtraValue(load_le<double>(p));
    case ExtraType::Raw:
      break;
  }
  return std::nullopt;
}

std::optional<double> decode_extra_scaled(const ExtraDimension& dimension,
                                          std::span<const std::uint8_t> point_extra, int element) {
  const auto raw = decode_extra(dimension, point_extra, element);
  if (!raw) return std::nullopt;
  const double value = std::visit([](auto v) { return static_cast<double>(v); }, *raw);
  return value * dimension.scale.value_or(1.0) + dimension.offset.value_or(0.0);
}

std::span<const std::uint8_t> PointBatch::extra(std::size_t index) const {
  const std::size_t size = extra_record_size();
  if (size == 0 || (index + 1) * size > extra_bytes.size()) return {};
  return std::span(extra_bytes.data() + index * size, size);
}

void PointBatch::append(const Point& point, std::span<const std::uint8_t> extra_record) {
  points.push_back(point);
  const std::size_t size = extra_record_size();
  if (size == 0) return;
  const std::size_t at = extra_bytes.size();
  extra_bytes.resize(at + size, 0);
  if (!extra_record.empty()) {
    std::memcpy(extra_bytes.data() + at, extra_record.data(), std::min(size, extra_record.size()));
  }
}

std::optional<double> PointBatch::extra_value(std::size_t index, std::string_view name,
                                              int element) const {
  const ExtraDimension* d = layout ? layout->find(name) : nullptr;
  if (d == nullptr) return std::nullopt;
  return decode_extra_scaled(*d, extra(index), element);
}

std::optional<ExtraValue> PointBatch::extra_raw(std::size_t index, std::string_view name,
                                                int element) const {
  const ExtraDimension* d = layout ? layout->find(name) : nullptr;
  if (d == nullptr) return std::nullopt;
  return decode_extra(*d, extra(index), element);
}

}  // namespace csgtile::geo
