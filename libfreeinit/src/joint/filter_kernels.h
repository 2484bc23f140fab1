// The joint filter's and smoother's dense linear algebra at its fixed sizes, as vector code
// (doppler_inertial_filter.cpp): the Kalman update of a node's rows, the covariance's
// propagation between nodes, and the solve of the smoother's backward pass. Matrices are
// column-major with the leading dimension of the filter's 19-component error state; D is the
// number of components updated (15: the calibration declared exact, 16: the clock offset
// estimated, 19: the rotation too).
#pragma once

namespace freeinit::detail {

/// The Kalman update of the first D components of a state (covariance P, 19 x 19 column-major,
/// the D x D block at its top left) by R rows with unit noise: the measurement matrix H (R x D,
/// column-major) and the innovation. On return P holds P - P H^T S^-1 H P with S = H P H^T + I,
/// and dx (D values) has the gain times the innovation added. H's columns 3..5 (the position's)
/// must be zero: they are skipped (the caller checks). Computed in the square-root form: with
/// S = L L^T, Y = P H^T L^-T, the covariance loses Y Y^T (exactly symmetric: P stays symmetric
/// when it was) and dx gains Y L^-1 innovation. Defined for (D, R) = (15, 6), (16, 6), (19, 6):
/// the rest knowledge, with the calibration declared exact or not (dopplerUpdateKernel: the
/// Doppler rows).
template <int D, int R>
void kalmanUpdateKernel(double* P, const double* H, const double* innovation, double* dx);

/// The same update by the rows of a node's Doppler: H = W G (W 9 x 9, G 9 x 19, both
/// column-major; G's position columns zero) and the innovation -r0 - H dx (r0: 9 values). dx is
/// the prior mean on entry. Defined for D = 15, 16, 19.
template <int D>
void dopplerUpdateKernel(double* P, const double* W, const double* G, const double* r0, double* dx);

/// The transition between two nodes, F = I but for the rows of the attitude (0..2), position
/// (3..5) and velocity (6..8): their 3 x 3 blocks (column-major) against the attitude, the
/// biases (9..11, 12..14) and, for the position, the velocity (tau I).
struct TransitionBlocks {
  const double *th_th, *th_bg;
  const double *p_th, *p_bg, *p_ba;
  const double *v_th, *v_bg, *v_ba;
  double tau;
};
/// The process noise between two nodes, per block of three (each a multiple of the identity):
/// attitude, position, position-velocity, velocity, gyro bias, accelerometer bias.
struct ProcessNoiseBlocks {
  double theta, pos, pos_vel, vel, bg, ba;
};
/// out = F P F^T + Q on the first D components (symmetric to the last bit: the mean of the
/// product and its transpose), the other components of P copied; P and out 19 x 19, distinct.
/// Defined for D = 15, 16, 19.
template <int D>
void propagateCovarianceKernel(const TransitionBlocks& F, const ProcessNoiseBlocks& Q,
                               const double* P, double* out);

/// b := A^-1 b for the symmetric positive definite D x D block at the top left of A (19 x 19),
/// by its Cholesky factorization. Defined for D = 15, 16, 19.
template <int D>
void choleskySolveKernel(const double* A, double* b);

}  // namespace freeinit::detail
