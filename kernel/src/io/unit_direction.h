#pragma once
/// \file
/// How the native format stores unit directions so that they read back bit for bit. Not API.

#include "csgtile/kernel/location.h"

namespace csgtile::kernel::detail {

/// The vector the native format stores for the unit direction `d` of a LineCurve,
/// ExtrusionSurface or RevolutionSurface: one whose normalisation by those constructors
/// gives d exactly (normalising d itself moves a third of unit vectors by an ulp).
/// Deterministic and cheap (at most 27 probes). Falls back to d when no such vector is found
/// (never seen; see unit_direction.cpp); the reader then refuses the file rather than
/// returning a direction that differs.
Vec3 stored_unit_direction(const Vec3& d);

}  // namespace csgtile::kernel::detail
