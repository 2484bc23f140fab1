// The filter's and smoother's Kalman update of a few rows into a state of up to 20 components,
// as vector code (doppler_inertial_filter.cpp: every node's Doppler rows, the rest knowledge).
#pragma once

#include <cstddef>

namespace freeinit::detail {

/// Largest sizes kalmanUpdateKernel() takes.
constexpr int kKalmanMaxStates = 20;
constexpr int kKalmanMaxRows = 12;

/// The Kalman update of the first `d` components of a state (covariance P, column-major with
/// leading dimension ld, the d x d block at its top left) by `r` rows with unit noise: the
/// measurement matrix H (r x d, column-major, leading dimension r) and the innovation. On return
/// P holds P - P H^T S^-1 H P with S = H P H^T + I, and dx (d values) has the gain times the
/// innovation added. Columns [skip_begin, skip_end) of H must be zero: they are skipped (the
/// caller checks). Computed in the square-root form: with S = L L^T, Y = P H^T L^-T, the
/// covariance loses Y Y^T (exactly symmetric: P stays symmetric when it was) and dx gains
/// Y L^-1 innovation. d <= kKalmanMaxStates, r <= kKalmanMaxRows.
void kalmanUpdateKernel(int d, int r, double* P, int ld, const double* H, const double* innovation,
                        double* dx, int skip_begin, int skip_end);

}  // namespace freeinit::detail
