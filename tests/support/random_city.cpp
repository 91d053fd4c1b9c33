#include "random_city.h"

#include <cmath>
#include <numbers>
#include <random>

namespace csgtile::test {

using kernel::Location;
using kernel::PrimitiveSpec;
using kernel::PrimitiveType;
using kernel::Vec2;
using kernel::Vec3;

namespace {

PrimitiveSpec box(double dx, double dy, double dz, const Location& at) {
  PrimitiveSpec s;
  s.type = PrimitiveType::Box;
  s.size = Vec3(dx, dy, dz);
  s.placement = at;
  return s;
}

PrimitiveSpec column(double r, double h, const Location& at) {
  PrimitiveSpec s;
  s.type = PrimitiveType::Cylinder;
  s.radius = r;
  s.height = h;
  s.placement = at;
  return s;
}

}  // namespace

std::vector<PrimitiveSpec> random_city(int n, std::uint64_t seed, const CityOptions& options) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<PrimitiveSpec> out;
  if (n <= 0) return out;
  const double lot = options.lot;
  const int side_blocks = std::max(1, static_cast<int>(std::ceil(std::sqrt(n / 1.3 / 16.0))));
  for (long long index = 0; static_cast<int>(out.size()) < n; ++index) {
    const long long b = index / 16, in_block = index % 16;
    const long long bx = b % side_blocks, by = b / side_blocks;
    // Blocks of 4 × 4 lots separated by 10 m streets.
    const Vec3 block_origin(static_cast<double>(bx) * (4 * lot + 10),
                            static_cast<double>(by) * (4 * lot + 10), 0);
    // One yaw per block (every other block turned), from its own generator.
    double yaw = 0;
    if (!options.axis_aligned_boxes_only && (bx + by) % 2 == 1) {
      std::mt19937_64 block_rng(seed ^ (0x9e3779b97f4a7c15ULL * static_cast<std::uint64_t>(b + 1)));
      yaw = std::uniform_real_distribution<double>(0.0, std::numbers::pi / 2)(block_rng);
    }
    const Location block = Location::translation(block_origin) *
                           Location::rotation(Vec3(2 * lot, 2 * lot, 0), Vec3::UnitZ(), yaw);
    const Location at_lot =
        block * Location::translation(Vec3(static_cast<double>(in_block % 4) * lot,
                                           static_cast<double>(in_block / 4) * lot, 0));
    auto push = [&](PrimitiveSpec s) {
      if (static_cast<int>(out.size()) < n) out.push_back(std::move(s));
    };
    const double w = 6 + 4 * u(rng), d = 6 + 4 * u(rng), h = 5 + 20 * u(rng);
    const Vec3 corner(1 + 1.5 * u(rng), 1 + 1.5 * u(rng), 0);  // footprint corner in the lot
    if (options.axis_aligned_boxes_only || u(rng) < 0.5) {
      push(box(w, d, h, at_lot * Location::translation(corner)));
    } else {
      // An L-shaped footprint, counter-clockwise.
      const double cx = w * (0.4 + 0.3 * u(rng)), cy = d * (0.4 + 0.3 * u(rng));
      PrimitiveSpec s;
      s.type = PrimitiveType::Extrusion;
      s.profile = {Vec2(0, 0), Vec2(w, 0), Vec2(w, cy), Vec2(cx, cy), Vec2(cx, d), Vec2(0, d)};
      s.height = h;
      s.placement = at_lot * Location::translation(corner);
      push(std::move(s));
    }
    const double r_wing = u(rng), r_roof = u(rng), r_col = u(rng), r_miss = u(rng);
    if (r_wing < 0.12) {
      // A wing from the front wall into the street side of the lot: overlaps the building.
      const double ww = 2 + 2 * u(rng), wd = 2 + 1.5 * u(rng), wh = 3 + 5 * u(rng);
      push(
          box(ww, wd, wh, at_lot * Location::translation(corner + Vec3(0.5 + u(rng), -wd + 1, 0))));
    }
    if (r_roof < 0.04) {
      // A roof box standing on the building's top: touches it along a face.
      push(box(2 + 2 * u(rng), 2 + 2 * u(rng), 2 + 2 * u(rng),
               at_lot * Location::translation(corner + Vec3(1, 1, h))));
    }
    if (!options.axis_aligned_boxes_only && r_col < 0.06) {
      const double r = 0.3 + 0.3 * u(rng);
      push(column(r, h + 2, at_lot * Location::translation(corner)));  // through the corner
    }
    if (!options.axis_aligned_boxes_only && r_miss < 0.04) {
      const double r = 0.2 + 0.2 * u(rng), gap = 0.05 + 0.25 * u(rng);
      push(column(r, 3 + 3 * u(rng),
                  at_lot * Location::translation(corner + Vec3(w / 2, -r - gap, 0))));
    }
  }
  return out;
}

std::vector<PrimitiveSpec> city_block(int n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<PrimitiveSpec> out;
  const int side = static_cast<int>(std::ceil(std::sqrt(n / 1.5)));
  for (int lot = 0; static_cast<int>(out.size()) < n; ++lot) {
    const double x0 = (lot % side) * 12.0, y0 = (lot / side) * 12.0;
    const double w = 6 + 3 * u(rng), d = 6 + 3 * u(rng), h = 5 + 20 * u(rng);
    out.push_back(box(w, d, h, Location::translation(Vec3(x0, y0, 0))));
    if (static_cast<int>(out.size()) < n && u(rng) < 0.3) {
      // A wing reaching into the gap and beyond the lot: overlaps the main box.
      const double ww = 3 + 4 * u(rng), wd = 2 + 2 * u(rng), wh = 3 + 6 * u(rng);
      out.push_back(box(ww, wd, wh, Location::translation(Vec3(x0 + w - 1, y0 + 1 + u(rng), 0))));
    }
    if (static_cast<int>(out.size()) < n && u(rng) < 0.2) {
      const double r = 0.3 + 0.3 * u(rng);
      out.push_back(column(r, h + 2, Location::translation(Vec3(x0 + w, y0 + d, 0))));
    }
  }
  return out;
}

}  // namespace csgtile::test
