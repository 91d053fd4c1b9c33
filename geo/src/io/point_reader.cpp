#include "csgtile/geo/point_reader.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "csgtile/geo/las.h"
#include "io/byte_source.h"
#include "io/readers.h"

namespace csgtile::geo {

namespace {

using kernel::ErrorCode;

std::string lower(std::string_view text) {
  std::string out(text);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

bool ends_with(std::string_view text, std::string_view suffix) {
  return text.size() >= suffix.size() && text.substr(text.size() - suffix.size()) == suffix;
}

// The format from the first bytes, falling back on the name's extension for text.
std::optional<PointFileFormat> sniff(std::span<const std::uint8_t> head, std::string_view name) {
  const std::string_view text(reinterpret_cast<const char*>(head.data()), head.size());
  if (text.starts_with("LASF")) return PointFileFormat::Las;
  if (text.starts_with("ply\n") || text.starts_with("ply\r")) return PointFileFormat::Ply;
  // PCD: optional comment lines, then the header keywords.
  std::string_view rest = text;
  while (!rest.empty()) {
    const auto eol = rest.find('\n');
    const std::string_view line = detail::trim(rest.substr(0, eol));
    if (line.starts_with("# .PCD") || line.starts_with("VERSION") || line.starts_with("FIELDS")) {
      return PointFileFormat::Pcd;
    }
    if (!line.empty() && line.front() != '#') break;
    if (eol == std::string_view::npos) break;
    rest.remove_prefix(eol + 1);
  }
  const std::string lname = lower(name);
  if (ends_with(lname, ".las") || ends_with(lname, ".laz")) return PointFileFormat::Las;
  if (ends_with(lname, ".ply")) return PointFileFormat::Ply;
  if (ends_with(lname, ".pcd")) return PointFileFormat::Pcd;
  for (const char* ext : {".xyz", ".txt", ".csv", ".pts", ".asc", ".xyzn", ".xyzrgb"}) {
    if (ends_with(lname, ext)) return PointFileFormat::Xyz;
  }
  return std::nullopt;
}

kernel::Result<std::unique_ptr<PointReader>> open_source(std::unique_ptr<detail::ByteSource> source,
                                                         PointFileFormat format,
                                                         const PointReadOptions& options) {
  switch (format) {
    case PointFileFormat::Ply:
      return detail::open_ply(std::move(source), options);
    case PointFileFormat::Pcd:
      return detail::open_pcd(std::move(source), options);
    case PointFileFormat::Xyz:
      return detail::open_xyz(std::move(source), options);
    case PointFileFormat::Las:
      break;
  }
  return kernel::Error{ErrorCode::Unsupported, source->name() + ": internal: LAS dispatch"};
}

std::string format_point(const Point& p) {
  char text[160];
  std::snprintf(text, sizeof text, "(%.10g, %.10g, %.10g)", p.x, p.y, p.z);
  return text;
}

}  // namespace

const char* point_file_format_name(PointFileFormat format) {
  switch (format) {
    case PointFileFormat::Las:
      return "las";
    case PointFileFormat::Ply:
      return "ply";
    case PointFileFormat::Pcd:
      return "pcd";
    case PointFileFormat::Xyz:
      return "xyz";
  }
  return "unknown";
}

PointReader::PointReader(std::string name, PointCloudInfo info, PointReadOptions options)
    : name_(std::move(name)), info_(std::move(info)), options_(options) {}

void PointReader::warn(std::string message) {
  // A hostile file must not grow memory through warnings: identical ones are kept once, and
  // their number is capped.
  constexpr std::size_t kMaxWarnings = 100;
  if (std::find(warnings_.begin(), warnings_.end(), message) != warnings_.end()) return;
  if (warnings_.size() == kMaxWarnings) {
    warnings_.push_back(name_ + ": further warnings suppressed");
    return;
  }
  if (warnings_.size() > kMaxWarnings) return;
  warnings_.push_back(std::move(message));
}

namespace {

// Keeps the batch's points for which `keep` holds (called once per point, in order), with
// their extra bytes, in order.
template <class Keep>
void keep_points(PointBatch& batch, Keep keep) {
  const std::size_t stride = batch.extra_record_size();
  std::size_t kept = 0;
  for (std::size_t i = 0; i < batch.points.size(); ++i) {
    const Point p = batch.points[i];
    if (!keep(p)) continue;
    if (kept != i) {
      batch.points[kept] = p;
      if (stride > 0) {
        std::memmove(batch.extra_bytes.data() + kept * stride,
                     batch.extra_bytes.data() + i * stride, stride);
      }
    }
    ++kept;
  }
  batch.points.resize(kept);
  batch.extra_bytes.resize(kept * stride);
}

}  // namespace

kernel::Result<std::size_t> PointReader::read(PointBatch& batch, std::size_t max) {
  if (failed_) return *failed_;
  if (at_end_) {
    batch.clear();
    batch.layout = info_.extra;
    return std::size_t{0};
  }
  if (max == 0) {
    return kernel::Error{ErrorCode::InvalidArgument, name_ + ": read() needs max >= 1"};
  }
  // Counts a finite point outside the header's bounds (beyond their tolerance), keeping the
  // first for the warning.
  const auto note_stray = [this](const Point& p) {
    if (info_.bounds && std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z) &&
        !info_.bounds->contains(p.x, p.y, p.z, info_.bounds_tolerance)) {
      if (outside_bounds_++ == 0) first_outside_ = p;
    }
  };
  for (;;) {
    // read_records sets the batch's size itself: a reused batch of the same size is not
    // re-initialised (that pass costs as much as decoding LAS records).
    batch.layout = info_.extra;
    auto records = read_records(batch, max);
    if (!records.ok()) {
      failed_ = records.error();
      batch.clear();
      return records.error();
    }
    if (records.value() == 0) {
      finish_reading();
      batch.clear();
      return std::size_t{0};
    }
    if (options_.region) {
      // Keep the points inside the region (a point with a NaN coordinate is inside none). One
      // it leaves out that lies outside the header's bounds is counted all the same: a region
      // of the file (a block of a large tile) must not hide the file's stray points.
      const Bounds3& r = *options_.region;
      keep_points(batch, [&](const Point& p) {
        const bool inside = p.x >= r.min[0] && p.x <= r.max[0] && p.y >= r.min[1] &&
                            p.y <= r.max[1] && p.z >= r.min[2] && p.z <= r.max[2];
        if (!inside) note_stray(p);
        return inside;
      });
    }
    // One pass for the common case: the batch's bounds and a non-finite detector (v·0 is 0
    // for finite v and NaN for NaN or infinity, so `poison` stays 0 exactly when all are
    // finite).
    Bounds3 batch_bounds;
    double poison = 0.0;
    for (const Point& p : batch.points) {
      poison += p.x * 0.0 + p.y * 0.0 + p.z * 0.0;
      batch_bounds.min[0] = std::min(batch_bounds.min[0], p.x);
      batch_bounds.min[1] = std::min(batch_bounds.min[1], p.y);
      batch_bounds.min[2] = std::min(batch_bounds.min[2], p.z);
      batch_bounds.max[0] = std::max(batch_bounds.max[0], p.x);
      batch_bounds.max[1] = std::max(batch_bounds.max[1], p.y);
      batch_bounds.max[2] = std::max(batch_bounds.max[2], p.z);
    }
    if (poison != 0.0) {
      // Some coordinate is NaN or infinite: drop those points (keeping order and their
      // extra bytes) unless asked to keep them, and recompute the bounds of the rest.
      batch_bounds = Bounds3{};
      keep_points(batch, [&](const Point& p) {
        const bool finite = std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
        if (!finite) ++non_finite_;
        if (finite) batch_bounds.add(p.x, p.y, p.z);
        return finite || !options_.skip_non_finite;
      });
    }
    bounds_read_.add(batch_bounds);
    // Per-point bounds checks only when the batch reaches outside the header's box.
    const auto& tol = info_.bounds_tolerance;
    if (info_.bounds && !batch_bounds.empty() &&
        !(info_.bounds->contains(batch_bounds.min[0], batch_bounds.min[1], batch_bounds.min[2],
                                 tol) &&
          info_.bounds->contains(batch_bounds.max[0], batch_bounds.max[1], batch_bounds.max[2],
                                 tol))) {
      for (const Point& p : batch.points) note_stray(p);
    }
    points_read_ += batch.points.size();
    if (!batch.points.empty()) return batch.points.size();
  }
}

void PointReader::finish_reading() {
  at_end_ = true;
  finish();
  if (non_finite_ > 0) {
    warn(name_ + ": " + std::to_string(non_finite_) + " points with NaN or infinite coordinates" +
         (options_.skip_non_finite ? " were dropped" : " were passed on"));
  }
  if (outside_bounds_ > 0 && info_.bounds) {
    char box[256];
    std::snprintf(box, sizeof box, "[%.10g, %.10g, %.10g] - [%.10g, %.10g, %.10g]",
                  info_.bounds->min[0], info_.bounds->min[1], info_.bounds->min[2],
                  info_.bounds->max[0], info_.bounds->max[1], info_.bounds->max[2]);
    warn(name_ + ": " + std::to_string(outside_bounds_) + " points lie outside the header bounds " +
         box + ", the first at " + format_point(*first_outside_));
  }
}

kernel::Result<PointFileFormat> detect_point_format(const std::filesystem::path& path) {
  auto source = detail::open_file_source(path);
  if (!source.ok()) return source.error();
  std::vector<std::uint8_t> head(
      static_cast<std::size_t>(std::min<std::uint64_t>(source.value()->size(), 4096)));
  auto status = source.value()->read_at(0, head);
  if (!status.ok()) return status.error();
  const auto format = sniff(head, path.filename().string());
  if (!format) {
    return kernel::Error{ErrorCode::Unsupported,
                         path.string() +
                             ": not a point-cloud format known here (LAS, PLY, "
                             "PCD, or XYZ text with a .xyz/.txt/.csv/.pts extension)"};
  }
  return *format;
}

kernel::Result<std::unique_ptr<PointReader>> open_point_file(const std::filesystem::path& path,
                                                             const PointReadOptions& options) {
  auto format = detect_point_format(path);
  if (!format.ok()) return format.error();
  if (format.value() == PointFileFormat::Las) {
    auto las = LasReader::open(path, options);
    if (!las.ok()) return las.error();
    return std::unique_ptr<PointReader>(std::move(las).value());
  }
  auto source = detail::open_file_source(path);
  if (!source.ok()) return source.error();
  return open_source(std::move(source).value(), format.value(), options);
}

kernel::Result<std::unique_ptr<PointReader>> open_point_memory(std::string name,
                                                               std::span<const std::uint8_t> bytes,
                                                               const PointReadOptions& options) {
  const auto format = sniff(bytes.first(std::min<std::size_t>(bytes.size(), 4096)), name);
  if (!format) {
    return kernel::Error{ErrorCode::Unsupported,
                         name + ": not a point-cloud format known here (LAS, PLY, PCD, XYZ)"};
  }
  if (*format == PointFileFormat::Las) {
    auto las = LasReader::open_memory(std::move(name), bytes, options);
    if (!las.ok()) return las.error();
    return std::unique_ptr<PointReader>(std::move(las).value());
  }
  return open_source(detail::memory_source(std::move(name), bytes), *format, options);
}

}  // namespace csgtile::geo
