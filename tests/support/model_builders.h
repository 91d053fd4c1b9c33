#pragma once
/// \file
/// Small models for tests: primitives placed by a location or at a point, a fitted pair the
/// exact Booleans cannot fuse, and CSG leaves.

#include <array>
#include <string>
#include <utility>
#include <vector>

#include "csgtile/kernel/csg.h"

namespace csgtile::test {

/// A box of `size` placed by `at` (its minimum corner at the location's origin).
kernel::PrimitiveSpec box(const kernel::Vec3& size, const kernel::Location& at);
/// A cylinder of radius r and height h placed by `at` (its base centre at the location's
/// origin, its axis the location's z).
kernel::PrimitiveSpec cylinder(double r, double h, const kernel::Location& at);
/// A placement as the scene format writes it: the rows of [R | t].
kernel::Location placement_rows(const std::array<double, 12>& rows);
/// A column and a beam of the timber gate as a fit leaves them (cut out of a gate whose
/// primitives were moved by up to 2 mm): the column 0.7 mrad off vertical, the beam's top
/// 0.1 mm under the column's, the two planes crossing inside the column's top disc. Snapped
/// (kernel/snap.h) they fuse; the exact fuse holds too.
std::pair<kernel::PrimitiveSpec, kernel::PrimitiveSpec> fitted_column_and_beam();
/// A column fitted in two pieces and a beam at its top: the lower piece plumb (r 0.15 m, 4 m),
/// the upper (r 0.15 m, from 2.5 m up 3 m) 0.1 mrad off vertical, its axis 1 µm off the
/// lower's; the beam's top 0.1 mm under the upper piece's top. The two pieces' sides cross at
/// grazing angles and their exact fuse fails; snapped (one axis line, one direction, one top
/// plane) the three fuse.
std::vector<kernel::PrimitiveSpec> fitted_column_in_two_pieces();
/// A Boolean's result expected to be a valid shape (gtest failures naming `what` otherwise):
/// the shape, or a null shape when the operation failed.
kernel::Shape valid_solid(const kernel::Result<kernel::Shape>& r, const std::string& what);
/// A box of `size` with its minimum corner at `at`.
kernel::PrimitiveSpec box_at(const kernel::Vec3& at, const kernel::Vec3& size);
/// A vertical cylinder of radius r and height h with its base centre at `at`.
kernel::PrimitiveSpec cylinder_at(const kernel::Vec3& at, double r, double h);
/// A vertical extrusion of `profile` (x, y) from z = base up by `height`.
kernel::PrimitiveSpec extrusion_at(std::vector<kernel::Vec2> profile, double base, double height);
/// The rectangle [x0, x1] × [y0, y1], counter-clockwise.
std::vector<kernel::Vec2> rectangle(double x0, double y0, double x1, double y1);
/// A gable house 10 × 6 m on z = 0: eaves at 5 m, the ridge at 8 m along x over y = 3 (an
/// extrusion cut by its two roof planes). Its roof's height is spread evenly over its area:
/// the q-th percentile is 5 + 3q.
kernel::PrimitiveSpec gable_house();
/// csg_primitive(spec, label), failing the test on error.
kernel::CsgModel leaf(const kernel::PrimitiveSpec& spec, const std::string& label);

}  // namespace csgtile::test
