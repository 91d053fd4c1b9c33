#pragma once
/// \file
/// Real roots of polynomials in one variable: the one home of the kernel's root finders, for
/// the Booleans' line–surface intersections and point classification and for geo's scan
/// simulator. Both recognise rounding noise: a root they cannot tell from a double root comes
/// back once, flagged `multiple`, instead of as two roots or none.

#include <array>
#include <vector>

namespace csgtile::kernel {

/// A real root of a polynomial on an interval.
struct PolynomialRoot {
  double x;
  /// The polynomial's value at a critical point x lies within its rounding noise: a double
  /// (or higher) root, or two roots too close to tell apart.
  bool multiple;
};

/// Real roots of c[0] + c[1]·x + … + c[degree]·x^degree in [lo, hi], ascending, appended to
/// `out`. `magnitude`, when given, bounds the absolute rounding error already present in each
/// coefficient (the size of the terms that were summed to make it); it widens the noise band
/// used to recognise multiple roots. Each monotone piece between the roots of the derivative
/// (found recursively) holds at most one root, isolated by safeguarded Newton iteration, so no
/// root is missed however close two roots are: close pairs come back as one `multiple` root.
/// Precondition: degree <= 8.
void polynomial_roots(const double* c, int degree, double lo, double hi,
                      std::vector<PolynomialRoot>& out, const double* magnitude = nullptr);

/// Roots of a·t² + 2·hb·t + c = 0 (note the half linear coefficient), without cancellation.
/// `c_magnitude` bounds the size of the terms summed into c (its rounding error is about
/// eps·c_magnitude). Returns the number of roots, ascending in `r`; a discriminant within
/// rounding of zero gives one root flagged `multiple`; a = 0 gives the linear root.
int solve_quadratic(double a, double hb, double c, double c_magnitude, std::array<double, 2>& r,
                    bool& multiple);

}  // namespace csgtile::kernel
