// Helpers shared by the PLY, PCD and XYZ readers.

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <limits>

#include "io/readers.h"

namespace csgtile::geo::detail {

std::vector<std::string_view> split_fields(std::string_view text, bool commas) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  auto separator = [&](char c) { return c == ' ' || c == '\t' || (commas && c == ','); };
  while (i < text.size()) {
    while (i < text.size() && separator(text[i])) ++i;
    const std::size_t start = i;
    while (i < text.size() && !separator(text[i])) ++i;
    if (i > start) out.push_back(text.substr(start, i - start));
  }
  return out;
}

std::string_view trim(std::string_view text) {
  auto blank = [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; };
  while (!text.empty() && blank(text.front())) text.remove_prefix(1);
  while (!text.empty() && blank(text.back())) text.remove_suffix(1);
  return text;
}

std::optional<std::string> Float32PrecisionCheck::warning(const std::string& file) const {
  // float32 keeps a 24-bit significand: at magnitude m the step is 2^(floor(log2 m) - 23).
  // From 65536 on that step is 7.8 mm or more, too coarse for building geometry.
  if (!(largest_ >= 65536.0) || !std::isfinite(largest_)) return std::nullopt;
  const double step = std::ldexp(1.0, std::ilogb(largest_) - 23);
  char text[320];
  std::snprintf(text, sizeof text,
                ": coordinates are stored as float32 and reach %.7g, where float32 resolves "
                "only steps of %g: positions are quantised (precision trap); store doubles or "
                "coordinates relative to a local origin",
                largest_, step);
  return file + text;
}

PointTarget point_target(std::string_view raw) {
  std::string name(raw);
  for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  struct Entry {
    const char* name;
    PointTarget target;
  };
  static constexpr Entry kNames[] = {
      {"x", PointTarget::X},
      {"y", PointTarget::Y},
      {"z", PointTarget::Z},
      {"nx", PointTarget::NormalX},
      {"ny", PointTarget::NormalY},
      {"nz", PointTarget::NormalZ},
      {"normal_x", PointTarget::NormalX},
      {"normal_y", PointTarget::NormalY},
      {"normal_z", PointTarget::NormalZ},
      {"red", PointTarget::Red},
      {"green", PointTarget::Green},
      {"blue", PointTarget::Blue},
      {"r", PointTarget::Red},
      {"g", PointTarget::Green},
      {"b", PointTarget::Blue},
      {"diffuse_red", PointTarget::Red},
      {"diffuse_green", PointTarget::Green},
      {"diffuse_blue", PointTarget::Blue},
      {"rgb", PointTarget::Rgb},
      {"rgba", PointTarget::Rgb},
      {"intensity", PointTarget::Intensity},
      {"scalar_intensity", PointTarget::Intensity},
      {"classification", PointTarget::Classification},
      {"gps_time", PointTarget::GpsTime},
      {"gpstime", PointTarget::GpsTime},
      {"return_number", PointTarget::ReturnNumber},
      {"number_of_returns", PointTarget::NumberOfReturns},
      {"point_source_id", PointTarget::PointSourceId},
      {"user_data", PointTarget::UserData},
      {"scan_angle", PointTarget::ScanAngle},
      {"scan_angle_rank", PointTarget::ScanAngle},
      {"nir", PointTarget::Nir},
  };
  for (const auto& e : kNames) {
    if (name == e.name) return e.target;
  }
  return PointTarget::None;
}

namespace {

template <class T>
T clamp_round(double v) {
  if (!(v == v)) return T{0};
  const double lo = static_cast<double>(std::numeric_limits<T>::min());
  const double hi = static_cast<double>(std::numeric_limits<T>::max());
  return static_cast<T>(std::clamp(std::round(v), lo, hi));
}

std::uint16_t color(double v, bool eight_bit) {
  return eight_bit ? static_cast<std::uint16_t>(clamp_round<std::uint8_t>(v) * 257)
                   : clamp_round<std::uint16_t>(v);
}

}  // namespace

void assign_target(Point& p, PointTarget target, double v, bool eight_bit_color) {
  switch (target) {
    case PointTarget::None:
      break;
    case PointTarget::X:
      p.x = v;
      break;
    case PointTarget::Y:
      p.y = v;
      break;
    case PointTarget::Z:
      p.z = v;
      break;
    case PointTarget::NormalX:
      p.normal[0] = static_cast<float>(v);
      break;
    case PointTarget::NormalY:
      p.normal[1] = static_cast<float>(v);
      break;
    case PointTarget::NormalZ:
      p.normal[2] = static_cast<float>(v);
      break;
    case PointTarget::Red:
      p.red = color(v, eight_bit_color);
      break;
    case PointTarget::Green:
      p.green = color(v, eight_bit_color);
      break;
    case PointTarget::Blue:
      p.blue = color(v, eight_bit_color);
      break;
    case PointTarget::Rgb: {
      // PCL packs 8-bit colours as 0x00RRGGBB (alpha in the top byte for rgba).
      const auto packed = static_cast<std::uint32_t>(clamp_round<std::uint32_t>(v));
      p.red = static_cast<std::uint16_t>(((packed >> 16) & 0xFF) * 257);
      p.green = static_cast<std::uint16_t>(((packed >> 8) & 0xFF) * 257);
      p.blue = static_cast<std::uint16_t>((packed & 0xFF) * 257);
      break;
    }
    case PointTarget::Intensity:
      p.intensity = clamp_round<std::uint16_t>(v);
      break;
    case PointTarget::Classification:
      p.classification = clamp_round<std::uint8_t>(v);
      break;
    case PointTarget::GpsTime:
      p.gps_time = v;
      break;
    case PointTarget::ReturnNumber:
      p.return_number = clamp_round<std::uint8_t>(v);
      break;
    case PointTarget::NumberOfReturns:
      p.number_of_returns = clamp_round<std::uint8_t>(v);
      break;
    case PointTarget::PointSourceId:
      p.point_source_id = clamp_round<std::uint16_t>(v);
      break;
    case PointTarget::UserData:
      p.user_data = clamp_round<std::uint8_t>(v);
      break;
    case PointTarget::ScanAngle:
      p.scan_angle = static_cast<float>(v);
      break;
    case PointTarget::Nir:
      p.nir = color(v, eight_bit_color);
      break;
  }
}

void mark_field(PointFields& f, PointTarget target) {
  switch (target) {
    case PointTarget::NormalX:
    case PointTarget::NormalY:
    case PointTarget::NormalZ:
      f.normals = true;
      break;
    case PointTarget::Red:
    case PointTarget::Green:
    case PointTarget::Blue:
    case PointTarget::Rgb:
      f.color = true;
      break;
    case PointTarget::Intensity:
      f.intensity = true;
      break;
    case PointTarget::Classification:
      f.classification = true;
      break;
    case PointTarget::GpsTime:
      f.gps_time = true;
      break;
    case PointTarget::ReturnNumber:
    case PointTarget::NumberOfReturns:
      f.returns = true;
      break;
    case PointTarget::PointSourceId:
      f.point_source_id = true;
      break;
    case PointTarget::UserData:
      f.user_data = true;
      break;
    case PointTarget::ScanAngle:
      f.scan_angle = true;
      break;
    case PointTarget::Nir:
      f.nir = true;
      break;
    default:
      break;
  }
}

}  // namespace csgtile::geo::detail
