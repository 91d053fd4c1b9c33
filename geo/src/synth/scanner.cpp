// Scan patterns: airborne strips and terrestrial stations. Each pulse is a ray cast against the
// exact primitives and the ground plane (occlusion is the first hit); its return gets range
// noise, or becomes an outlier; intensity and colour follow the angle of incidence.

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "csgtile/geo/synth.h"
#include "synth/random.h"

namespace csgtile::geo {

namespace {

using kernel::Vec3;

constexpr double kPi = std::numbers::pi;
constexpr double kDegree = kPi / 180.0;
constexpr std::size_t kBatchSize = 1 << 16;
// Adjusted standard GPS time (GPS seconds − 1e9) of the first pulse: a day in 2022.
constexpr double kFirstPulseTime = 3.5e8;

// What one pulse knows besides its ray.
struct Pulse {
  double gps_time = 0.0;
  float scan_angle = 0.0F;
  bool scan_direction = false;
  bool edge_of_flight_line = false;
};

struct ClassLook {
  double reflectance;
  std::array<int, 3> rgb;
};

ClassLook look(std::uint8_t classification) {
  switch (classification) {
    case kClassGround:
      return {0.30, {158, 150, 120}};
    case kClassBuilding:
      return {0.55, {205, 110, 75}};
    case kClassLowNoise:
      return {0.10, {220, 40, 220}};
    case kClassHighNoise:
      return {0.10, {240, 220, 40}};
    default:
      return {0.45, {80, 140, 210}};
  }
}

// Turns pulses into points and hands them to the sink in batches.
class Recorder {
 public:
  Recorder(const SynthScene& scene, const SynthOptions& options, const RayCaster& caster,
           const PointSink& sink, SynthSummary& summary)
      : scene_(scene),
        options_(options),
        caster_(caster),
        sink_(sink),
        summary_(summary),
        random_(options.seed ^ 0x5eed5ca11ed5ca75ULL) {
    batch_.layout = synth_extra_layout();
    batch_.points.reserve(kBatchSize);
    batch_.extra_bytes.reserve(kBatchSize * 4);
  }

  bool failed() const { return !status_.ok(); }
  const kernel::Status& status() const { return status_; }
  void set_source(std::uint16_t id) { source_id_ = id; }

  void pulse(const Vec3& origin, const Vec3& direction, double max_range, const Pulse& info) {
    if (failed()) return;
    const auto hit = caster_.first_hit(origin, direction, max_range);
    if (!hit) return;  // nothing within range: no return
    std::uint8_t classification;
    std::int32_t truth = -1;
    double range;
    if (random_.uniform() < options_.outlier_fraction) {
      if (random_.uniform() < 0.5) {
        range = hit->t + random_.uniform(1.0, 12.0);  // multipath: below the surface
        classification = kClassLowNoise;
      } else {
        // A bird, dust: in the air, within 40 m of the surface so that tiles keep their height.
        range = std::max(0.5 * hit->t, hit->t - random_.uniform(1.0, 40.0));
        classification = kClassHighNoise;
      }
    } else {
      range = hit->t + options_.noise_sigma * random_.normal();
      truth = hit->primitive;
      classification = hit->primitive < 0
                           ? kClassGround
                           : scene_.classes[static_cast<std::size_t>(hit->primitive)];
    }
    const Vec3 local = origin + range * direction;
    const double incidence = std::abs(hit->normal.dot(direction));
    const ClassLook l = look(classification);
    Point p;
    p.x = options_.origin[0] + local.x();
    p.y = options_.origin[1] + local.y();
    p.z = options_.origin[2] + local.z();
    p.gps_time = info.gps_time;
    p.scan_angle = info.scan_angle;
    p.scan_direction = info.scan_direction;
    p.edge_of_flight_line = info.edge_of_flight_line;
    p.intensity = static_cast<std::uint16_t>(
        std::clamp(65535.0 * l.reflectance * (0.3 + 0.7 * incidence), 0.0, 65535.0));
    const double shade = 0.45 + 0.55 * incidence;
    p.red = static_cast<std::uint16_t>(std::lround(l.rgb[0] * shade) * 257);
    p.green = static_cast<std::uint16_t>(std::lround(l.rgb[1] * shade) * 257);
    p.blue = static_cast<std::uint16_t>(std::lround(l.rgb[2] * shade) * 257);
    p.point_source_id = source_id_;
    p.return_number = 1;
    p.number_of_returns = 1;
    p.classification = classification;
    std::array<std::uint8_t, 4> extra{};
    const auto bits = static_cast<std::uint32_t>(truth);
    for (std::size_t i = 0; i < 4; ++i) extra[i] = static_cast<std::uint8_t>(bits >> (8 * i));
    batch_.append(p, extra);
    ++summary_.points;
    ++summary_.points_per_class[classification];
    summary_.bounds.add(p.x, p.y, p.z);
    if (batch_.size() >= kBatchSize) flush();
  }

  void flush() {
    if (failed() || batch_.empty()) return;
    status_ = sink_(batch_);
    batch_.clear();
  }

 private:
  const SynthScene& scene_;
  const SynthOptions& options_;
  const RayCaster& caster_;
  const PointSink& sink_;
  SynthSummary& summary_;
  detail::Random random_;
  PointBatch batch_;
  kernel::Status status_;
  std::uint16_t source_id_ = 0;
};

// The scanned area: the scene extent grown by the margin (x0, y0, x1, y1).
std::array<double, 4> scan_area(const SynthScene& scene, double margin) {
  if (scene.extent.empty()) return {-margin, -margin, margin, margin};
  return {scene.extent.min.x() - margin, scene.extent.min.y() - margin,
          scene.extent.max.x() + margin, scene.extent.max.y() + margin};
}

// Parallel strips flown along x at options.altitude, alternating direction. The mirror sweeps
// across the track (zig-zag) within ±scan_angle, limited to rays whose footprint on the ground
// lies in the scanned area. Angular and along-track steps are chosen for options.points.
int scan_airborne(const SynthScene& scene, const SynthOptions& o, Recorder& recorder,
                  detail::Random& random) {
  const auto [x0, y0, x1, y1] = scan_area(scene, o.margin);
  const double height = o.altitude;
  const double max_angle = o.scan_angle_deg * kDegree;
  const double swath = 2.0 * height * std::tan(max_angle);
  const double width = y1 - y0;
  const double length = x1 - x0;
  const double middle = 0.5 * (y0 + y1);
  std::vector<double> lines;  // strip centre lines (y)
  if (swath >= width) {
    // Every strip sees the whole area; spread them for different viewing angles.
    const int n = o.strips;
    const double spread = 0.9 * (swath - width);
    for (int k = 0; k < n; ++k) {
      lines.push_back(n == 1 ? middle : middle - spread / 2 + spread * k / (n - 1));
    }
  } else {
    // Side overlap of at least 30 %.
    const int n =
        std::max(o.strips, static_cast<int>(std::ceil((width - swath) / (0.7 * swath))) + 1);
    for (int k = 0; k < n; ++k) {
      lines.push_back(y0 + swath / 2 + (width - swath) * k / std::max(1, n - 1));
    }
  }
  struct Strip {
    double y = 0.0, right = 0.0, angle_lo = 0.0, angle_hi = 0.0;
    int samples = 0;
  };
  std::vector<Strip> strips;
  double angle_sum = 0.0;
  for (std::size_t k = 0; k < lines.size(); ++k) {
    Strip s;
    s.y = lines[k];
    s.right = (k % 2 == 0) ? -1.0 : 1.0;  // flying +x, the right is −y
    double a = std::atan((y0 - s.y) / (height * s.right));
    double b = std::atan((y1 - s.y) / (height * s.right));
    if (a > b) std::swap(a, b);
    s.angle_lo = std::max(a, -max_angle);
    s.angle_hi = std::min(b, max_angle);
    if (!(s.angle_lo < s.angle_hi)) continue;
    angle_sum += s.angle_hi - s.angle_lo;
    strips.push_back(s);
  }
  // Square footprint spacing at nadir: along-track step = height × angular step.
  const double step = std::sqrt(length * angle_sum / (height * static_cast<double>(o.points)));
  std::uint64_t per_line = 0;
  for (Strip& s : strips) {
    s.samples = static_cast<int>(std::floor((s.angle_hi - s.angle_lo) / step)) + 1;
    per_line += static_cast<std::uint64_t>(s.samples);
  }
  if (per_line == 0) return 0;
  const auto n_lines = std::max<std::uint64_t>(1, (o.points + per_line / 2) / per_line);
  const double dx = length / static_cast<double>(n_lines);
  constexpr double kSpeed = 60.0;  // m/s
  constexpr double kTurn = 120.0;  // s between strips
  double strip_start = kFirstPulseTime;
  for (std::size_t k = 0; k < strips.size(); ++k) {
    const Strip& s = strips[k];
    recorder.set_source(static_cast<std::uint16_t>(k + 1));
    const bool forward = s.right < 0.0;
    const Vec3 right(0.0, s.right, 0.0);
    const double angle_step = (s.angle_hi - s.angle_lo) / s.samples;
    // Strips are flown independently: their scan lines do not line up.
    const double phase = random.uniform(-0.5, 0.5);
    for (std::uint64_t line = 0; line < n_lines; ++line) {
      const bool sweep_up = line % 2 == 0;
      for (int j = 0; j < s.samples; ++j) {
        const double progress = static_cast<double>(line) + phase + (j + 0.5) / s.samples;
        const double along = progress * dx;
        const int slot = sweep_up ? j : s.samples - 1 - j;
        const double angle = s.angle_lo + (slot + 0.5 + random.uniform(-0.25, 0.25)) * angle_step;
        const Vec3 origin(forward ? x0 + along : x1 - along, s.y, height);
        const Vec3 direction = std::sin(angle) * right - std::cos(angle) * Vec3::UnitZ();
        Pulse info;
        info.gps_time = strip_start + along / kSpeed;
        info.scan_angle = static_cast<float>(angle / kDegree);
        info.scan_direction = sweep_up;
        info.edge_of_flight_line = j == s.samples - 1;
        recorder.pulse(origin, direction, std::numeric_limits<double>::infinity(), info);
      }
      if (recorder.failed()) return 0;
    }
    strip_start += length / kSpeed + kTurn;
  }
  return static_cast<int>(strips.size());
}

// True when a tripod at (x, y) stands about a metre clear of every primitive (closer, a
// column beside the scanner would shadow a wide wedge).
bool clear_spot(const RayCaster& caster, double x, double y, double height) {
  for (double z : {0.1, 0.5 * height, height}) {
    if (caster.inside(Vec3(x, y, z))) return false;
    for (double r : {0.5, 1.0}) {
      for (int k = 0; k < 16; ++k) {
        const double a = k * kPi / 8;
        if (caster.inside(Vec3(x + r * std::cos(a), y + r * std::sin(a), z))) return false;
      }
    }
  }
  return true;
}

// Station positions: the corners of the area around the scene, the middle, the middles of the
// sides, then random spots; each moved to the nearest clear spot found on a spiral.
std::vector<Vec3> station_positions(const SynthScene& scene, const SynthOptions& o,
                                    const RayCaster& caster, detail::Random& random) {
  const auto [x0, y0, x1, y1] = scan_area(scene, 0.0);
  const double stand_off = std::clamp(0.15 * std::max(x1 - x0, y1 - y0), 4.0, 15.0);
  const double ax0 = x0 - stand_off, ax1 = x1 + stand_off;
  const double ay0 = y0 - stand_off, ay1 = y1 + stand_off;
  const double mx = 0.5 * (x0 + x1), my = 0.5 * (y0 + y1);
  std::vector<std::array<double, 2>> wanted{{ax0, ay0}, {ax1, ay0}, {ax1, ay1},
                                            {ax0, ay1}, {mx, my},   {mx, ay0},
                                            {ax1, my},  {mx, ay1},  {ax0, my}};
  std::vector<Vec3> out;
  for (int i = 0; i < o.stations; ++i) {
    std::array<double, 2> q =
        i < static_cast<int>(wanted.size())
            ? wanted[static_cast<std::size_t>(i)]
            : std::array<double, 2>{random.uniform(ax0, ax1), random.uniform(ay0, ay1)};
    bool found = false;
    for (int ring = 0; ring <= 40 && !found; ++ring) {
      const double r = 0.5 * ring;
      const int steps = ring == 0 ? 1 : 8 * ring;
      for (int k = 0; k < steps && !found; ++k) {
        const double a = 2 * kPi * k / steps;
        const double x = q[0] + r * std::cos(a), y = q[1] + r * std::sin(a);
        if (clear_spot(caster, x, y, o.station_height)) {
          out.emplace_back(x, y, o.station_height);
          found = true;
        }
      }
    }
  }
  return out;
}

Vec3 spherical(double azimuth, double elevation) {
  return Vec3(std::cos(elevation) * std::cos(azimuth), std::cos(elevation) * std::sin(azimuth),
              std::sin(elevation));
}

// Stations scanning the full circle in vertical profiles from min_elevation to the zenith with
// equal angular steps, sized from a coarse pilot scan so that the returns add up to about
// options.points (rays into the sky or beyond max_range return nothing).
int scan_terrestrial(const SynthScene& scene, const SynthOptions& o, const RayCaster& caster,
                     Recorder& recorder, detail::Random& random) {
  const std::vector<Vec3> stations = station_positions(scene, o, caster, random);
  if (stations.empty()) return 0;
  const double low = o.min_elevation_deg * kDegree;
  const double span = kPi / 2 - low;
  constexpr double kPulseRate = 1e6;  // Hz
  for (std::size_t s = 0; s < stations.size(); ++s) {
    const Vec3& station = stations[s];
    // Pilot: the share of rays that return.
    constexpr int kPilot = 64;
    int returns = 0;
    for (int a = 0; a < kPilot; ++a) {
      for (int e = 0; e < kPilot; ++e) {
        const Vec3 d = spherical(2 * kPi * (a + 0.5) / kPilot, low + span * (e + 0.5) / kPilot);
        if (caster.first_hit(station, d, o.max_range)) ++returns;
      }
    }
    const double share = std::max(0.01, static_cast<double>(returns) / (kPilot * kPilot));
    const std::uint64_t wanted = o.points / stations.size() + (s < o.points % stations.size());
    const double rays = static_cast<double>(wanted) / share;
    const double step = std::sqrt(2 * kPi * span / rays);
    const int n_azimuth = std::max(4, static_cast<int>(std::lround(2 * kPi / step)));
    const int n_elevation = std::max(2, static_cast<int>(std::lround(span / step)));
    recorder.set_source(static_cast<std::uint16_t>(s + 1));
    const double start = kFirstPulseTime + 3600.0 * static_cast<double>(s);
    std::uint64_t index = 0;
    for (int a = 0; a < n_azimuth; ++a) {
      const double azimuth = 2 * kPi * (a + 0.5 + random.uniform(-0.1, 0.1)) / n_azimuth;
      for (int e = 0; e < n_elevation; ++e) {
        const double elevation = low + span * (e + 0.5 + random.uniform(-0.1, 0.1)) / n_elevation;
        Pulse info;
        info.gps_time = start + static_cast<double>(index++) / kPulseRate;
        info.scan_angle = static_cast<float>(elevation / kDegree);
        info.scan_direction = true;
        info.edge_of_flight_line = e == n_elevation - 1;
        recorder.pulse(station, spherical(azimuth, elevation), o.max_range, info);
      }
      if (recorder.failed()) return 0;
    }
  }
  return static_cast<int>(stations.size());
}

}  // namespace

const char* scan_mode_name(ScanMode mode) {
  return mode == ScanMode::Airborne ? "airborne" : "terrestrial";
}

std::shared_ptr<const ExtraLayout> synth_extra_layout() {
  static const std::shared_ptr<const ExtraLayout> layout_of_points = [] {
    auto layout = std::make_shared<ExtraLayout>();
    ExtraDimension d;
    d.name = "truth_index";
    d.description = "index of truth primitive, or -1";
    d.type = ExtraType::I32;
    d.byte_offset = 0;
    layout->dimensions.push_back(d);
    layout->record_size = 4;
    return std::shared_ptr<const ExtraLayout>(std::move(layout));
  }();
  return layout_of_points;
}

kernel::Result<SynthSummary> scan_scene(const SynthScene& scene, const SynthOptions& options,
                                        const PointSink& sink) {
  if (auto status = options.validate(); !status.ok()) return status.error();
  SynthSummary summary;
  for (const auto& p : scene.scene.primitives) {
    ++summary.primitives_per_type[static_cast<std::size_t>(p.spec.type)];
  }
  std::vector<kernel::PrimitiveSpec> specs;
  specs.reserve(scene.scene.primitives.size());
  for (const auto& p : scene.scene.primitives) specs.push_back(p.spec);
  const RayCaster caster(specs, 0.0);
  detail::Random pattern_random(options.seed);
  Recorder recorder(scene, options, caster, sink, summary);
  summary.passes = options.mode == ScanMode::Airborne
                       ? scan_airborne(scene, options, recorder, pattern_random)
                       : scan_terrestrial(scene, options, caster, recorder, pattern_random);
  recorder.flush();
  if (recorder.failed()) return recorder.status().error();
  return summary;
}

}  // namespace csgtile::geo
