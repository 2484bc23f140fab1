// Statistics shared by the tests: chi-square quantiles for NEES bounds, random unit vectors.
#pragma once

#include <freeinit/types.h>

#include <cmath>
#include <random>

namespace freeinit::test {

/// Chi-square quantile for `dof` degrees of freedom at the standard-normal quantile z
/// (Wilson-Hilferty approximation; z = +-3.29 gives the two-sided 0.999 interval).
inline double chi2Quantile(double dof, double z) {
  const double a = 2.0 / (9.0 * dof);
  return dof * std::pow(1.0 - a + z * std::sqrt(a), 3);
}

/// A direction uniformly distributed on the unit sphere.
inline Vec3 randomUnit(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Vec3(n(rng), n(rng), n(rng)).normalized();
}

}  // namespace freeinit::test
