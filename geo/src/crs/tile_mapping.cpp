// Chebyshev interpolation of a tile's georeferencing, verified against the exact path.

#include "csgtile/geo/tile_mapping.h"

#include <array>
#include <cmath>
#include <numbers>
#include <string>

namespace csgtile::geo {

using kernel::BoundingBox;
using kernel::Error;
using kernel::ErrorCode;
using kernel::Result;
using kernel::Status;
using kernel::Vec3;

namespace {

constexpr int kMinDegree = 3;
constexpr int kMaxDegree = 12;
constexpr int kComponents = 6;  // local(x, y, z) = P(x, y) + z·Q(x, y)

// T_0(s) … T_d(s).
void chebyshev(double s, int degree, double* t) {
  t[0] = 1.0;
  if (degree >= 1) t[1] = s;
  for (int j = 2; j <= degree; ++j) t[j] = 2.0 * s * t[j - 1] - t[j - 2];
}

}  // namespace

Result<TileMapping> TileMapping::fit(const Georeferencer& georeferencer, const BoundingBox& box,
                                     double max_error_m) {
  if (box.empty() || !box.min.allFinite() || !box.max.allFinite()) {
    return Error{ErrorCode::InvalidArgument, "tile mapping: the box is empty or not finite"};
  }
  if (!(max_error_m > 0.0)) {
    return Error{ErrorCode::InvalidArgument, "tile mapping: the error bound must be > 0"};
  }
  TileMapping m(georeferencer);
  m.box_ = box;
  m.cx_ = 0.5 * (box.min.x() + box.max.x());
  m.cy_ = 0.5 * (box.min.y() + box.max.y());
  // A degenerate extent (one row of points) still gets a non-zero half-width.
  const double hx = std::max(0.5 * (box.max.x() - box.min.x()), 1e-9 * (1.0 + std::fabs(m.cx_)));
  const double hy = std::max(0.5 * (box.max.y() - box.min.y()), 1e-9 * (1.0 + std::fabs(m.cy_)));
  m.inv_hx_ = 1.0 / hx;
  m.inv_hy_ = 1.0 / hy;

  auto exact = [&](double x, double y, double z) -> Result<Vec3> {
    return georeferencer.to_local_checked(Vec3(x, y, z));
  };
  const double z0 = box.min.z();
  const double z1 = box.max.z() > z0 ? box.max.z() : z0 + 1.0;
  for (int degree = kMinDegree; degree <= kMaxDegree; ++degree) {
    const int n = degree + 1;
    // Values at the Chebyshev nodes.
    std::vector<double> nodes(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i)
      nodes[static_cast<std::size_t>(i)] = std::cos(std::numbers::pi * (i + 0.5) / n);
    std::vector<std::array<double, kComponents>> values(static_cast<std::size_t>(n * n));
    for (int l = 0; l < n; ++l) {
      for (int i = 0; i < n; ++i) {
        const double x = m.cx_ + hx * nodes[static_cast<std::size_t>(i)];
        const double y = m.cy_ + hy * nodes[static_cast<std::size_t>(l)];
        // P and Q from the two ends of the z range: rounding noise is not amplified by z.
        auto f0 = exact(x, y, z0);
        if (!f0.ok())
          return Error{ErrorCode::InvalidArgument, "tile mapping: " + f0.error().message};
        auto f1 = exact(x, y, z1);
        if (!f1.ok())
          return Error{ErrorCode::InvalidArgument, "tile mapping: " + f1.error().message};
        const Vec3 q = (f1.value() - f0.value()) / (z1 - z0);
        const Vec3 p = f0.value() - z0 * q;
        values[static_cast<std::size_t>(l * n + i)] = {p.x(), p.y(), p.z(), q.x(), q.y(), q.z()};
      }
    }
    // Discrete Chebyshev transform (separable).
    std::vector<double> tx(static_cast<std::size_t>(n * n));  // T_j(node_i) at [j * n + i]
    for (int i = 0; i < n; ++i) {
      std::vector<double> t(static_cast<std::size_t>(n));
      chebyshev(nodes[static_cast<std::size_t>(i)], degree, t.data());
      for (int j = 0; j < n; ++j)
        tx[static_cast<std::size_t>(j * n + i)] = t[static_cast<std::size_t>(j)];
    }
    m.degree_ = degree;
    m.coefficients_.assign(static_cast<std::size_t>(n * n * kComponents), 0.0);
    for (int k = 0; k < n; ++k) {
      for (int j = 0; j < n; ++j) {
        const double weight = (j == 0 ? 1.0 : 2.0) * (k == 0 ? 1.0 : 2.0) / (n * n);
        for (int c = 0; c < kComponents; ++c) {
          double sum = 0.0;
          for (int l = 0; l < n; ++l) {
            for (int i = 0; i < n; ++i) {
              sum += values[static_cast<std::size_t>(l * n + i)][static_cast<std::size_t>(c)] *
                     tx[static_cast<std::size_t>(j * n + i)] *
                     tx[static_cast<std::size_t>(k * n + l)];
            }
          }
          m.coefficients_[static_cast<std::size_t>((k * n + j) * kComponents + c)] = weight * sum;
        }
      }
    }
    // Verification on a denser regular grid (edges included), at both ends of the z range.
    const int g = 4 * n;
    double worst = 0.0;
    for (int b = 0; b <= g && worst <= max_error_m; ++b) {
      for (int a = 0; a <= g && worst <= max_error_m; ++a) {
        const double x = box.min.x() + (box.max.x() - box.min.x()) * a / g;
        const double y = box.min.y() + (box.max.y() - box.min.y()) * b / g;
        for (double z : {box.min.z(), box.max.z()}) {
          auto e = exact(x, y, z);
          if (!e.ok())
            return Error{ErrorCode::InvalidArgument, "tile mapping: " + e.error().message};
          worst = std::max(worst, (m.evaluate(Vec3(x, y, z)) - e.value()).norm());
        }
      }
    }
    if (worst <= max_error_m) {
      m.verified_error_m_ = worst;
      return m;
    }
  }
  return Error{ErrorCode::Unsupported, "tile mapping: degree " + std::to_string(kMaxDegree) +
                                           " does not reach " + std::to_string(max_error_m) +
                                           " m over this box; use smaller tiles"};
}

Vec3 TileMapping::evaluate(const Vec3& p) const {
  const int n = degree_ + 1;
  std::array<double, kMaxDegree + 1> ts{}, tt{};
  chebyshev((p.x() - cx_) * inv_hx_, degree_, ts.data());
  chebyshev((p.y() - cy_) * inv_hy_, degree_, tt.data());
  std::array<double, kComponents> acc{};
  const double* c = coefficients_.data();
  for (int k = 0; k < n; ++k) {
    std::array<double, kComponents> row{};
    for (int j = 0; j < n; ++j) {
      const double t = ts[static_cast<std::size_t>(j)];
      for (int q = 0; q < kComponents; ++q) row[static_cast<std::size_t>(q)] += c[q] * t;
      c += kComponents;
    }
    for (int q = 0; q < kComponents; ++q)
      acc[static_cast<std::size_t>(q)] +=
          row[static_cast<std::size_t>(q)] * tt[static_cast<std::size_t>(k)];
  }
  return Vec3(acc[0] + p.z() * acc[3], acc[1] + p.z() * acc[4], acc[2] + p.z() * acc[5]);
}

Vec3 TileMapping::to_local(const Vec3& p) const {
  if (p.x() >= box_.min.x() && p.x() <= box_.max.x() && p.y() >= box_.min.y() &&
      p.y() <= box_.max.y() && p.z() >= box_.min.z() && p.z() <= box_.max.z()) {
    return evaluate(p);
  }
  return georeferencer_.to_local(p);
}

Status TileMapping::to_local(std::span<const Vec3> in, std::span<Vec3> out) const {
  if (in.size() != out.size()) {
    return Status(ErrorCode::InvalidArgument, "to_local: input and output sizes differ (" +
                                                  std::to_string(in.size()) + " vs " +
                                                  std::to_string(out.size()) + ")");
  }
  for (std::size_t i = 0; i < in.size(); ++i) {
    out[i] = to_local(in[i]);
    if (!out[i].allFinite()) {
      auto checked = georeferencer_.to_local_checked(in[i]);
      return Status(ErrorCode::InvalidArgument, "point " + std::to_string(i) + ": " +
                                                    (checked.ok() ? std::string("non-finite result")
                                                                  : checked.error().message));
    }
  }
  return Status();
}

}  // namespace csgtile::geo
