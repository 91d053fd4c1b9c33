// Points files and each object's model fit (model_fit.h).

#include "city/model_fit.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>

#include "csgtile/kernel/mesh_distance.h"
#include "csgtile/kernel/tessellation.h"
#include "little_endian.h"

namespace csgtile::worker::city::detail {

namespace {

constexpr std::string_view kMagic = "CSGTPTS1";

}  // namespace

std::string encode_points(std::span<const kernel::Vec3> points) {
  std::string out(kMagic);
  const auto n = static_cast<std::uint64_t>(points.size());
  put_u64(out, n);
  out.reserve(out.size() + points.size() * 12);
  for (const kernel::Vec3& p : points) {
    for (int k = 0; k < 3; ++k) put_f32(out, static_cast<float>(p[k]));
  }
  return out;
}

Failure decode_points(std::string_view bytes, const std::string& what,
                      std::vector<kernel::Vec3>& out) {
  out.clear();
  if (bytes.size() < kMagic.size() + 8 || bytes.substr(0, kMagic.size()) != kMagic) {
    return {ErrorCode::InputInvalid,
            what + ": not a points file (no " + std::string(kMagic) + " header)"};
  }
  const char* p = bytes.data() + kMagic.size();
  const std::uint64_t n = get_u64(p);
  const std::size_t body = bytes.size() - kMagic.size() - 8;
  if (n > body / 12 || n * 12 != body) {
    return {ErrorCode::InputInvalid, what + ": holds " + std::to_string(body) +
                                         " bytes of points where its header counts " +
                                         std::to_string(n) + " points of 12 bytes"};
  }
  out.resize(static_cast<std::size_t>(n));
  p += 8;
  for (std::size_t i = 0; i < out.size(); ++i, p += 12) {
    out[i] = kernel::Vec3(std::bit_cast<float>(get_u32(p)), std::bit_cast<float>(get_u32(p + 4)),
                          std::bit_cast<float>(get_u32(p + 8)));
  }
  return {};
}

std::vector<std::optional<ModelFit>> measure_model_fit(
    std::span<const kernel::Shape* const> shapes, std::span<const double> sigma,
    std::span<const kernel::Vec3> points, double chordal_tolerance, long long& over_none,
    std::span<const std::shared_ptr<const kernel::Mesh>> meshes) {
  std::vector<std::optional<ModelFit>> out(shapes.size());
  over_none = 0;
  // The points on an xy grid of about 16 points per cell (counting sort: ascending indices
  // within a cell).
  kernel::BoundingBox box;
  for (const kernel::Vec3& p : points) {
    if (p.allFinite()) box.add(p);
  }
  if (box.empty()) return out;
  const double area = std::max((box.max.x() - box.min.x()) * (box.max.y() - box.min.y()), 1.0);
  const double cell = std::max(
      0.5, std::sqrt(16.0 * area / static_cast<double>(std::max<std::size_t>(points.size(), 1))));
  const auto nx = static_cast<long long>((box.max.x() - box.min.x()) / cell) + 1;
  const auto ny = static_cast<long long>((box.max.y() - box.min.y()) / cell) + 1;
  const auto cell_x = [&](double x) {
    return std::clamp(static_cast<long long>(std::floor((x - box.min.x()) / cell)), 0LL, nx - 1);
  };
  const auto cell_y = [&](double y) {
    return std::clamp(static_cast<long long>(std::floor((y - box.min.y()) / cell)), 0LL, ny - 1);
  };
  std::vector<std::uint32_t> start(static_cast<std::size_t>(nx * ny) + 1, 0), items;
  for (const kernel::Vec3& p : points) {
    if (p.allFinite()) ++start[static_cast<std::size_t>(cell_y(p.y()) * nx + cell_x(p.x())) + 1];
  }
  for (std::size_t c = 1; c < start.size(); ++c) start[c] += start[c - 1];
  items.resize(start.back());
  {
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for (std::uint32_t i = 0; i < points.size(); ++i) {
      const kernel::Vec3& p = points[i];
      if (p.allFinite())
        items[fill[static_cast<std::size_t>(cell_y(p.y()) * nx + cell_x(p.x()))]++] = i;
    }
  }

  // Per shape, the points over it and their squared distances (in parallel: each shape alone).
  struct Near {
    std::uint32_t point;
    double d2;
  };
  std::vector<std::vector<Near>> near(shapes.size());
  tbb::parallel_for(std::size_t{0}, shapes.size(), [&](std::size_t k) {
    if (shapes[k] == nullptr || shapes[k]->is_null()) return;
    const auto mesh = kernel::shared_tessellation(*shapes[k], chordal_tolerance,
                                                  k < meshes.size() ? meshes[k] : nullptr);
    if (!mesh.ok() || mesh.value()->triangles.empty()) return;
    const kernel::MeshDistance model(*mesh.value());
    const kernel::BoundingBox& b = model.bounds();
    for (long long j = cell_y(b.min.y()); j <= cell_y(b.max.y()); ++j) {
      for (long long i = cell_x(b.min.x()); i <= cell_x(b.max.x()); ++i) {
        const std::size_t c = static_cast<std::size_t>(j * nx + i);
        for (std::uint32_t q = start[c]; q < start[c + 1]; ++q) {
          const kernel::Vec3& p = points[items[q]];
          if (model.covers(p.x(), p.y())) near[k].push_back({items[q], model.distance2(p)});
        }
      }
    }
  });

  // Each point to the nearest shape it stands over; sums in point order.
  std::vector<double> best(points.size(), std::numeric_limits<double>::infinity());
  std::vector<std::int32_t> owner(points.size(), -1);
  for (std::size_t k = 0; k < near.size(); ++k) {
    for (const Near& n : near[k]) {
      if (n.d2 < best[n.point]) {
        best[n.point] = n.d2;
        owner[n.point] = static_cast<std::int32_t>(k);
      }
    }
  }
  std::vector<double> sum(shapes.size(), 0.0);
  std::vector<long long> count(shapes.size(), 0), within(shapes.size(), 0);
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite()) continue;
    if (owner[i] < 0) {
      ++over_none;
      continue;
    }
    const auto k = static_cast<std::size_t>(owner[i]);
    sum[k] += best[i];
    ++count[k];
    const double s = k < sigma.size() ? sigma[k] : 0.0;
    if (s > 0.0 && best[i] <= 4.0 * s * s) ++within[k];
  }
  for (std::size_t k = 0; k < shapes.size(); ++k) {
    if (count[k] == 0) continue;
    ModelFit f;
    f.points = count[k];
    f.rmse = std::sqrt(sum[k] / static_cast<double>(count[k]));
    const double s = k < sigma.size() ? sigma[k] : 0.0;
    if (s > 0.0) {
      f.sigma = s;
      f.within_2sigma = static_cast<double>(within[k]) / static_cast<double>(count[k]);
    }
    out[k] = f;
  }
  return out;
}

ordered_json model_fit_json(const std::optional<ModelFit>& fit) {
  if (!fit) return nullptr;
  ordered_json j;
  j["points"] = fit->points;
  j["rmse"] = fit->rmse;
  j["sigma"] = fit->sigma ? ordered_json(*fit->sigma) : ordered_json();
  j["within_2sigma"] = fit->within_2sigma ? ordered_json(*fit->within_2sigma) : ordered_json();
  return j;
}

Failure read_model_fit(const ordered_json& entry, std::optional<ModelFit>& out) {
  out.reset();
  if (!entry.contains("model_fit") || entry.at("model_fit").is_null()) return {};
  const ordered_json& j = entry.at("model_fit");
  if (!j.is_object() || !j.contains("points") || !j.at("points").is_number_integer() ||
      !j.contains("rmse") || !j.at("rmse").is_number()) {
    return {ErrorCode::Internal, "an object record's model_fit is malformed: " + j.dump()};
  }
  ModelFit f;
  f.points = j.at("points").get<long long>();
  f.rmse = j.at("rmse").get<double>();
  if (j.contains("sigma") && j.at("sigma").is_number()) f.sigma = j.at("sigma").get<double>();
  if (j.contains("within_2sigma") && j.at("within_2sigma").is_number()) {
    f.within_2sigma = j.at("within_2sigma").get<double>();
  }
  out = f;
  return {};
}

}  // namespace csgtile::worker::city::detail
