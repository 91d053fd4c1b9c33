#pragma once
/// \file
/// Small models for tests: axis-aligned primitives at a point, and CSG leaves.

#include <string>

#include "csgtile/kernel/csg.h"

namespace csgtile::test {

/// A box of `size` with its minimum corner at `at`.
kernel::PrimitiveSpec box_at(const kernel::Vec3& at, const kernel::Vec3& size);
/// A vertical cylinder of radius r and height h with its base centre at `at`.
kernel::PrimitiveSpec cylinder_at(const kernel::Vec3& at, double r, double h);
/// csg_primitive(spec, label), failing the test on error.
kernel::CsgModel leaf(const kernel::PrimitiveSpec& spec, const std::string& label);

}  // namespace csgtile::test
