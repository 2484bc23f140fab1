// The filter's and smoother's Kalman update of a few rows into a state of 15 or 19 components,
// as vector code (doppler_inertial_filter.cpp: every node's Doppler rows, the rest knowledge).
#pragma once

namespace freeinit::detail {

/// The Kalman update of the first D components of a state (covariance P, 19 x 19 column-major,
/// the D x D block at its top left) by R rows with unit noise: the measurement matrix H (R x D,
/// column-major) and the innovation. On return P holds P - P H^T S^-1 H P with S = H P H^T + I,
/// and dx (D values) has the gain times the innovation added. H's columns 3..5 (the position's)
/// must be zero: they are skipped (the caller checks). Computed in the square-root form: with
/// S = L L^T, Y = P H^T L^-T, the covariance loses Y Y^T (exactly symmetric: P stays symmetric
/// when it was) and dx gains Y L^-1 innovation. Defined for (D, R) = (15, 9), (19, 9), (15, 6),
/// (19, 6): the Doppler rows and the rest knowledge, with the calibration declared exact or not.
template <int D, int R>
void kalmanUpdateKernel(double* P, const double* H, const double* innovation, double* dx);

}  // namespace freeinit::detail
