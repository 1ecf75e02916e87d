#pragma once
// Counting a real polynomial's roots in the open right half-plane from its Routh array, for the
// stability of the documents' closed loops (characteristic polynomials of low degree).

#include <span>

namespace haptic::engine {

/// The number of roots of a_0 sⁿ + a_1 sⁿ⁻¹ + … + a_n (coefficients highest power first, a_0 ≠ 0)
/// with Re s > 0: the sign changes down the first column of the Routh array. A zero met in the
/// first column is replaced by a small ε relative to the row's size (the count is then that of a
/// neighbouring polynomial, so a root on the imaginary axis may be counted either way). Degree at
/// most 16.
int routh_right_half_plane_roots(std::span<const double> coefficients);

/// routh_right_half_plane_roots() == 0 and no root on the imaginary axis that the ε would hide:
/// every coefficient > 0 (after scaling the leading one positive) is necessary and checked first.
bool routh_hurwitz_stable(std::span<const double> coefficients);

}  // namespace haptic::engine
