#include "joint/doppler_inertial_filter.h"

#include <freeinit/rotation.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <stdexcept>
#include <string>

#include "joint/filter_kernels.h"
#include "joint/vector_clones.h"

namespace freeinit {
namespace {

const Vec3 kGravityW(0, 0, -kGravity);
// A preintegration made at biases b0 is applied at b to first order in b - b0 while that change
// over its span tau stays within these (chainHolds() says why): [rad], [m/s].
constexpr double kMostGyroBiasStep = 1e-3, kMostAccelBiasStep = 1e-2;
/// Step of the central differences of the numerical Jacobians (state units: rad, m, m/s, rad/s,
/// m/s^2; the functions are smooth and O(1-100) in these units).
constexpr double kJacobianStep = 1e-6;

/// Right Jacobian of SO(3) from K = [phi]x, t2 = |phi|^2 and, where the series does not serve
/// (t2 >= 1e-8), t = |phi| with its sine and cosine.
Mat3 rightJacobianOf(const Mat3& K, double t2, double t, double sin_t, double cos_t) {
  if (t2 < 1e-8) return Mat3::Identity() - 0.5 * K + (1.0 / 6.0) * K * K;
  return Mat3::Identity() - (1.0 - cos_t) / t2 * K + (t - sin_t) / (t2 * t) * K * K;
}

/// Right Jacobian of SO(3): Exp(phi + dphi) = Exp(phi) Exp(J_r(phi) dphi) to first order.
Mat3 rightJacobian(const Vec3& phi) {
  const double t2 = phi.squaredNorm();
  if (t2 < 1e-8) return rightJacobianOf(skew(phi), t2, 0.0, 0.0, 1.0);
  const double t = std::sqrt(t2);
  return rightJacobianOf(skew(phi), t2, t, std::sin(t), std::cos(t));
}

/// Exp(phi) and J_r(phi) with one sine and cosine: the same operations as Exp() and
/// rightJacobian() (and so the same values).
void expAndRightJacobian(const Vec3& phi, Mat3& E, Mat3& Jr) {
  const double t2 = phi.squaredNorm();
  const Mat3 K = skew(phi);
  double t = 0, sin_t = 0, cos_t = 1;
  if (t2 >= 1e-10) {
    t = std::sqrt(t2);
    sin_t = std::sin(t);
    cos_t = std::cos(t);
  }
  const double a = t2 < 1e-10 ? 1.0 - t2 / 6.0 : sin_t / t;
  const double b = t2 < 1e-10 ? 0.5 - t2 / 24.0 : (1.0 - cos_t) / t2;
  E = Mat3::Identity() + a * K + b * (K * K);
  Jr = rightJacobianOf(K, t2, t, sin_t, cos_t);
}

/// d phi / d b_g of the rotation vector (w0 + w1) tau / 2 + (w0 x w1) tau^2 / 12 (both rates are
/// gyro - b_g; Simpson's middle weights change the first term's form, not its derivative).
Mat3 incrementBiasJacobian(const Vec3& w0, const Vec3& w1, double tau) {
  return -tau * Mat3::Identity() - (tau * tau / 12.0) * skew(Vec3(w0 - w1));
}

/// X := Y^-1 X for a 9 x 9 Y, by Gaussian elimination with partial pivoting (as
/// Eigen::PartialPivLU, whose blocked triangular solves cost more than the whole at this size).
template <int C>
void solveInPlace(Eigen::Matrix<double, 9, 9> Y, Eigen::Matrix<double, 9, C>& X) {
  for (int j = 0; j < 9; ++j) {
    int p = j;
    for (int i = j + 1; i < 9; ++i)
      if (std::abs(Y(i, j)) > std::abs(Y(p, j))) p = i;
    if (p != j) {
      Y.row(j).swap(Y.row(p));
      X.row(j).swap(X.row(p));
    }
    for (int i = j + 1; i < 9; ++i) {
      const double f = Y(i, j) / Y(j, j);
      for (int k = j + 1; k < 9; ++k) Y(i, k) -= f * Y(j, k);
      X.row(i) -= f * X.row(j);
    }
  }
  for (int j = 8; j >= 0; --j) {
    X.row(j) /= Y(j, j);
    for (int i = 0; i < j; ++i) X.row(i) -= Y(i, j) * X.row(j);
  }
}

/// The largest block of a Gauss-Newton step in units of its tolerance
/// (DopplerInertialFilterParams::convergence).
double stepInTolerances(const DopplerInertialFilter::VecS& dx) {
  DopplerInertialFilter::VecS tol;
  tol << Vec3::Constant(1e-4), Vec3::Constant(1e-3), Vec3::Constant(1e-4), Vec3::Constant(1e-5),
      Vec3::Constant(1e-3), 1e-4, Vec3::Constant(1e-4);
  return dx.cwiseAbs().cwiseQuotient(tol).maxCoeff();
}

/// A return's unit direction from its position in the LiDAR frame (float, as the sensor gives it),
/// in double: one division (inverseNorm), then the position times it. Every computation of a
/// return's direction in the filter is this one (the first gate multiplies by the inverse norm
/// itself and keeps it; the second gate and the returns it drops reuse it), so that a return
/// taken out of a node's sums (removePoint) takes out exactly what it added.
inline double inverseNorm(double x, double y, double z) {
  return 1.0 / std::sqrt(x * x + y * y + z * z);
}
inline void unitDirection(double x, double y, double z, double& dx, double& dy, double& dz) {
  const double inv_norm = inverseNorm(x, y, z);
  dx = x * inv_norm;
  dy = y * inv_norm;
  dz = z * inv_norm;
}

/// The velocity polynomial Q = [q0; q1; q2] and the covariance M of q0 that a node's returns
/// are gated with, as scalars for the per-return loops.
struct GatePrediction {
  double q[9] = {};
  double mxx = 0, myy = 0, mzz = 0, mxy = 0, mxz = 0, myz = 0;  ///< d^T M d's coefficients
  double inv_h = 1, r_doppler = 0, speed = 0, gate_min2 = 0, gate_k2 = 0;
  void setCovariance(const Mat3& M) {
    mxx = M(0, 0);
    myy = M(1, 1);
    mzz = M(2, 2);
    mxy = M(0, 1) + M(1, 0);
    mxz = M(0, 2) + M(2, 0);
    myz = M(1, 2) + M(2, 1);
  }
  /// A return's residual against the prediction (r = z + d . v(s), v a quadratic in s = tau /
  /// h) and the residual's variance (d^T M d + the Doppler noise), d its unit direction: the
  /// numbers both gates test. Called on a local copy of the prediction, so that the compiler
  /// keeps its coefficients in registers across a vectorized loop.
  void residual(double s, double dx, double dy, double dz, double z, double& r, double& var) const {
    const double vx = q[0] + s * (q[3] + s * q[6]), vy = q[1] + s * (q[4] + s * q[7]),
                 vz = q[2] + s * (q[5] + s * q[8]);
    r = z + (dx * vx + dy * vy + dz * vz);
    var = dx * (mxx * dx + mxy * dy + mxz * dz) + dy * (myy * dy + myz * dz) + dz * (mzz * dz) +
          r_doppler;
  }
};

// The per-return loops: without branches and over arrays that do not overlap (__restrict), so
// that the compiler vectorizes them; built for several instruction sets (vector_clones.h).

typedef double V4 __attribute__((vector_size(32)));

/// The Doppler sums: S (6 x 5, column-major: the upper triangle of s^m d d^T, m = 0..4), bz
/// (3 x 3, column-major: s^m z d, m = 0..2), c (z^2).
constexpr int kSumCount = 40;

/// The first gate of m returns (LiDAR time from the node, position, Doppler: as the sensor gives
/// them, in float) against the prediction, and the sums of those it accepts: per return the
/// residual and whether |r| <= sqrt(max(gate_min^2, gate_sigma^2 S)) + gate_rel |v_l| (without
/// the root); a rejected return adds its terms times zero (exact zeros). Block by block: the gate
/// in a loop the compiler vectorizes, its directions kept in the block's arrays (in the first-level
/// cache), then the sums over them, each in four partial sums (return i in lane i % 4) added at
/// the end: the lanes are independent and fixed by the vector type, so the vector code reorders
/// no sum within a lane, whatever the instruction set.
FREEINIT_VECTOR_CLONES
std::size_t gateAndSumReturns(std::size_t m, const GatePrediction& g, const float* __restrict tau,
                              const float* __restrict px, const float* __restrict py,
                              const float* __restrict pz, const float* __restrict z,
                              double* __restrict res_out, std::int64_t* __restrict acc_out,
                              double* __restrict inv_norm_out, double* __restrict total) {
  const GatePrediction c = g;
  const double inv_h = c.inv_h, speed = c.speed, gate_min2 = c.gate_min2, gate_k2 = c.gate_k2;
  constexpr std::size_t kBlock = 128;
  alignas(32) double bs[kBlock], bx[kBlock], by[kBlock], bz[kBlock], bzi[kBlock], bw[kBlock];
  V4 acc[kSumCount];
  for (V4& a : acc) a = V4{0, 0, 0, 0};
  std::size_t accepted = 0;
  for (std::size_t b = 0; b < m; b += kBlock) {
    const std::size_t n = std::min(kBlock, m - b);
    for (std::size_t j = 0; j < n; ++j) {
      const std::size_t i = b + j;
      const double x = px[i], y = py[i], w = pz[i], zi = z[i];
      const double inv_norm = inverseNorm(x, y, w);
      const double dx = x * inv_norm, dy = y * inv_norm, dz = w * inv_norm;
      const double s = static_cast<double>(tau[i]) * inv_h;
      double r, S;
      c.residual(s, dx, dy, dz, zi, r, S);
      const double e = std::abs(r) - speed;
      const double kS = gate_k2 * S;
      const double bound = kS > gate_min2 ? kS : gate_min2;
      const bool accept = (e <= 0) | (e * e <= bound);
      res_out[i] = r;
      acc_out[i] = accept;
      inv_norm_out[i] = inv_norm;
      accepted += accept;
      bs[j] = s;
      bx[j] = dx;
      by[j] = dy;
      bz[j] = dz;
      bzi[j] = zi;
      bw[j] = accept ? 1.0 : 0.0;
    }
    for (std::size_t j = n; j % 4 != 0; ++j)  // the last lanes add zeros
      bs[j] = bx[j] = by[j] = bz[j] = bzi[j] = bw[j] = 0.0;
    for (std::size_t j = 0; j < n; j += 4) {
      V4 s, x, y, u, zi, w;
      std::memcpy(&s, bs + j, sizeof s);
      std::memcpy(&x, bx + j, sizeof x);
      std::memcpy(&y, by + j, sizeof y);
      std::memcpy(&u, bz + j, sizeof u);
      std::memcpy(&zi, bzi + j, sizeof zi);
      std::memcpy(&w, bw + j, sizeof w);
      // Each term times the weight (x w = x exactly for an accepted return).
      const V4 xw = x * w, yw = y * w, uw = u * w;
      const V4 s2 = s * s, s3 = s2 * s, s4 = s2 * s2;
      const V4 dd[6] = {xw * x, xw * y, xw * u, yw * y, yw * u, uw * u};
      for (int k = 0; k < 6; ++k) {
        acc[k] += dd[k];
        acc[6 + k] += dd[k] * s;
        acc[12 + k] += dd[k] * s2;
        acc[18 + k] += dd[k] * s3;
        acc[24 + k] += dd[k] * s4;
      }
      const V4 zd[3] = {zi * xw, zi * yw, zi * uw};
      for (int k = 0; k < 3; ++k) {
        acc[30 + k] += zd[k];
        acc[33 + k] += zd[k] * s;
        acc[36 + k] += zd[k] * s2;
      }
      acc[39] += (zi * w) * zi;
    }
  }
  for (int k = 0; k < kSumCount; ++k) total[k] = (acc[k][0] + acc[k][1]) + (acc[k][2] + acc[k][3]);
  return accepted;
}

/// act(i), in order, for each i < n whose flag(i) (an integer) is not zero, where those are
/// few: the flags are first tested sixteen at a time, in a loop the compiler vectorizes, and a
/// block without one is passed over. act(i) may change flag(i) but no other flag.
template <class Flag, class Act>
void forEachFlagged(std::size_t n, const Flag& flag, const Act& act) {
  constexpr std::size_t kBlock = 16;
  std::size_t i = 0;
  for (; i + kBlock <= n; i += kBlock) {
    std::int64_t any = 0;
    for (std::size_t l = 0; l < kBlock; ++l) any |= flag(i + l);
    if (any == 0) continue;
    for (std::size_t l = 0; l < kBlock; ++l)
      if (flag(i + l) != 0) act(i + l);
  }
  for (; i < n; ++i)
    if (flag(i) != 0) act(i);
}

/// The coherence test of n returns from the prefix sums of their residuals (cum_r) and of the
/// residuals' variances (cum_v), n + 1 values each: whether the neighbourhood [j - half,
/// j + half] (cut at the ends, tested only if it holds at least min_count returns) has
/// sum^2 > c2 var.
FREEINIT_VECTOR_CLONES
void coherenceTest(std::size_t n, std::size_t half, std::size_t min_count, double c2,
                   const double* __restrict cum_r, const double* __restrict cum_v,
                   std::int64_t* __restrict coherent) {
  auto test = [&](std::size_t j, std::size_t lo, std::size_t hi) {
    const double sum = cum_r[hi] - cum_r[lo];
    const double var = cum_v[hi] - cum_v[lo];  // of the sum
    coherent[j] = (hi - lo >= min_count) & (sum * sum > c2 * var);
  };
  // The ends, where the neighbourhood is cut, then the inside (no cut: a loop the compiler
  // vectorizes).
  const std::size_t inside_begin = std::min(half, n), inside_end = n > half ? n - half : 0;
  for (std::size_t j = 0; j < inside_begin; ++j) test(j, 0, std::min(n, j + half + 1));
  for (std::size_t j = inside_begin; j < inside_end; ++j) {
    const double sum = cum_r[j + half + 1] - cum_r[j - half];
    const double var = cum_v[j + half + 1] - cum_v[j - half];
    coherent[j] = (2 * half + 1 >= min_count) & (sum * sum > c2 * var);
  }
  for (std::size_t j = std::max(inside_begin, inside_end); j < n; ++j)
    test(j, j >= half ? j - half : 0, std::min(n, j + half + 1));
}

/// The second gate of the m returns the first accepted (acc), against the update: residual, its
/// variance, and whether r^2 <= k2 var (never for a return the first gate rejected, whose
/// residual stays the first gate's). The direction as gateAndSumReturns computes it, from the
/// inverse norms it kept (a square root and a division per return, the most of such a loop).
FREEINIT_VECTOR_CLONES
void regateReturns(std::size_t m, const GatePrediction& g, double k2, const float* __restrict tau,
                   const float* __restrict px, const float* __restrict py,
                   const float* __restrict pz, const float* __restrict z,
                   const double* __restrict inv_norm, const std::int64_t* __restrict acc,
                   double* __restrict res, double* __restrict res2_out, double* __restrict var_out,
                   std::int64_t* __restrict pass_out) {
  const GatePrediction c = g;
  const double inv_h = c.inv_h;
  for (std::size_t i = 0; i < m; ++i) {
    const double x = px[i], y = py[i], w = pz[i], zi = z[i];
    const double dx = x * inv_norm[i], dy = y * inv_norm[i], dz = w * inv_norm[i];
    const double s = static_cast<double>(tau[i]) * inv_h;
    double r, var;
    c.residual(s, dx, dy, dz, zi, r, var);
    const bool first = acc[i] != 0;
    res[i] = first ? r : res[i];
    res2_out[i] = r;
    var_out[i] = var;
    pass_out[i] = first & (r * r <= k2 * var);
  }
}

}  // namespace

DopplerInertialFilter::DopplerInertialFilter(const DopplerInertialFilterParams& params,
                                             const Extrinsics& extrinsics)
    : params_(params), R_bl_(extrinsics.R_bl), p_bl_(extrinsics.p_bl) {
  gate_min2_ = params.gate_min * params.gate_min;
  gate_k2_ = params.gate_sigma * params.gate_sigma;
  // The gyro's white noise n_g moves the LiDAR velocity of a node by R_bl^T (n_g x p_bl), alike
  // for all the node's returns (marginalizeLeverNoise()).
  lever_noise_ = R_bl_.transpose() * skew(p_bl_);
  noiseChanged();
}

void DopplerInertialFilter::noiseChanged() {
  r_doppler_ = params_.doppler_sigma * params_.doppler_sigma;
  const double var_lever = params_.gyro_sigma * params_.gyro_sigma * p_bl_.squaredNorm();
  lever_ratio_ = params_.lever_arm_gyro_noise && var_lever > 0
                     ? r_doppler_ / (params_.gyro_sigma * params_.gyro_sigma)
                     : 0.0;
}

void DopplerInertialFilter::setNoise(double doppler_sigma, double gyro_sigma, double accel_sigma) {
  const DopplerInertialFilterParams before = params_;
  if (doppler_sigma > 0) params_.doppler_sigma = doppler_sigma;
  if (gyro_sigma > 0) params_.gyro_sigma = gyro_sigma;
  if (accel_sigma > 0) params_.accel_sigma = accel_sigma;
  if (params_.doppler_sigma == before.doppler_sigma && params_.gyro_sigma == before.gyro_sigma &&
      params_.accel_sigma == before.accel_sigma)
    return;
  noiseChanged();
  const bool rows = params_.doppler_sigma != before.doppler_sigma ||
                    (lever_ratio_ > 0 && params_.gyro_sigma != before.gyro_sigma);
  for (Node& n : nodes_) {
    if (rows) n.rows_stale = true;
    if (n.rest_rate_sigma > 0) n.rest_rate_sigma = params_.gyro_sigma;
  }
  nodeChanged(0);
}

FilterState DopplerInertialFilter::boxplus(const FilterState& x, const VecS& dx) {
  FilterState y = x;
  y.R_wb = x.R_wb * Exp(Vec3(dx.segment<3>(0)));
  y.p_w += dx.segment<3>(3);
  y.v_w += dx.segment<3>(6);
  y.b_g += dx.segment<3>(9);
  y.b_a += dx.segment<3>(12);
  y.phi_bl += dx.segment<3>(kRot);
  y.dt_l += dx(kTime);
  return y;
}

DopplerInertialFilter::VecS DopplerInertialFilter::boxminus(const FilterState& a,
                                                            const FilterState& b) {
  VecS d;
  d.segment<3>(0) = Log(b.R_wb.transpose() * a.R_wb);
  d.segment<3>(3) = a.p_w - b.p_w;
  d.segment<3>(6) = a.v_w - b.v_w;
  d.segment<3>(9) = a.b_g - b.b_g;
  d.segment<3>(12) = a.b_a - b.b_a;
  d.segment<3>(kRot) = a.phi_bl - b.phi_bl;
  d(kTime) = a.dt_l - b.dt_l;
  return d;
}

void DopplerInertialFilter::interpolateImu(const std::vector<ImuSample>& imu, double t, Vec3& gyro,
                                           Vec3& accel, std::size_t hint, Vec3* gyro_rate) {
  std::size_t lo = 0;
  const std::size_t hi = interpolationSpan(imu, t, hint, lo);
  gyro.setZero();
  accel.setZero();
  if (gyro_rate != nullptr) gyro_rate->setZero();
  double w[4], dw[4];
  lagrangeWeights(imu, t, lo, hi, w, dw);
  for (std::size_t i = lo; i <= hi; ++i) {
    gyro += w[i - lo] * imu[i].gyro;
    accel += w[i - lo] * imu[i].accel;
    if (gyro_rate != nullptr) *gyro_rate += dw[i - lo] * imu[i].gyro;
  }
}

bool DopplerInertialFilter::motionAt(const std::vector<ImuSample>& imu, double t, std::size_t hint,
                                     double gyro_sigma, double accel_sigma, Vec3& accel,
                                     Vec3& gyro_rate, bool* complete,
                                     const std::vector<RunningSums>* running) {
  Vec3 gyro;
  interpolateImu(imu, t, gyro, accel, hint, &gyro_rate);
  std::size_t lo = 0;
  std::size_t hi = interpolationSpan(imu, t, hint, lo);
  const std::size_t hi_interpolant = hi;
  // The widest span (kMotionHalfSpan, then a half, then a quarter of it) over which a line holds,
  // for each sensor: a car's vibration or a hand's tremor bends the motion within 25 ms, and a
  // fast IMU's many samples tell the bend from the noise (at 1.4 kHz on a car the accelerometer's
  // line held at 0.3 % of the instants, and the interpolant's noise, read as the column, held the
  // offset near its reference: -2.9 +- 0.03 ms against -9.0).
  // Least squares of c0 + c1 d per axis (d = t_i - t) over each span: the normal equations'
  // sums, and the sums of squares for the residuals (RSS = sum |y|^2 - c0 . sum y - c1 . sum d y),
  // from the running sums, or gathered in one pass over the widest span (each sample added, in
  // order, to the spans that hold it).
  struct Sums {
    double s0 = 0, s1 = 0, s2 = 0, aa = 0, gg = 0;
    Vec3 a0 = Vec3::Zero(), a1 = Vec3::Zero(), g0 = Vec3::Zero(), g1 = Vec3::Zero();
  };
  constexpr int kSpans = 3;
  std::array<Sums, kSpans> sums;
  while (lo > 0 && imu[lo - 1].t >= t - kMotionHalfSpan) --lo;
  while (lo < hi && imu[lo].t < t - kMotionHalfSpan) ++lo;
  while (hi + 1 < imu.size() && imu[hi + 1].t <= t + kMotionHalfSpan) ++hi;
  while (hi > lo && imu[hi].t > t + kMotionHalfSpan) --hi;
  // The sample after the span, read, lies beyond it (the loop above): later ones do too.
  if (complete != nullptr) *complete = std::max(hi, hi_interpolant) + 1 < imu.size();
  const bool from_running = running != nullptr && running->size() == imu.size() + 1;
  if (from_running && lo <= hi) {
    // Samples i with |t_i - t| <= span: [b, e), found by bisection within the widest span's.
    auto time = [](const ImuSample& x, double v) { return x.t < v; };
    const auto first = imu.begin() + static_cast<std::ptrdiff_t>(lo);
    const auto end = imu.begin() + static_cast<std::ptrdiff_t>(hi) + 1;
    const double tau = t - imu.front().t;  // in the running sums' time
    double span = kMotionHalfSpan;
    for (int r = 0; r < kSpans; ++r, span *= 0.5) {
      const auto b = std::lower_bound(first, end, t - span, time);
      const auto e =
          std::upper_bound(b, end, t + span, [](double v, const ImuSample& x) { return v < x.t; });
      const RunningSums& A = (*running)[static_cast<std::size_t>(b - imu.begin())];
      const RunningSums& B = (*running)[static_cast<std::size_t>(e - imu.begin())];
      Sums& S = sums[static_cast<std::size_t>(r)];
      S.s0 = static_cast<double>(e - b);
      const double U = B.u - A.u;
      S.s1 = U - S.s0 * tau;
      S.s2 = (B.uu - A.uu) - 2.0 * tau * U + S.s0 * tau * tau;
      S.a0 = B.a - A.a;
      S.a1 = (B.ua - A.ua) - tau * S.a0;
      S.aa = B.aa - A.aa;
      S.g0 = B.g - A.g;
      S.g1 = (B.ug - A.ug) - tau * S.g0;
      S.gg = B.gg - A.gg;
    }
  }
  for (std::size_t i = lo; i <= hi && !from_running; ++i) {
    const double d = imu[i].t - t;
    double span = kMotionHalfSpan;
    for (int r = 0; r < kSpans && std::abs(d) <= span; ++r, span *= 0.5) {
      Sums& S = sums[static_cast<std::size_t>(r)];
      S.s0 += 1;
      S.s1 += d;
      S.s2 += d * d;
      S.a0 += imu[i].accel;
      S.a1 += d * imu[i].accel;
      S.aa += imu[i].accel.squaredNorm();
      S.g0 += imu[i].gyro;
      S.g1 += d * imu[i].gyro;
      S.gg += imu[i].gyro.squaredNorm();
    }
  }
  bool accel_line = false, gyro_line = false;
  for (int r = 0; r < kSpans && !(accel_line && gyro_line); ++r) {
    const Sums& S = sums[static_cast<std::size_t>(r)];
    // A shorter span only with samples enough to average their noise (from 320 Hz for the half,
    // 640 Hz for the quarter: slower IMUs keep the one span).
    constexpr double kFewestShortFit = 8;
    const double det = S.s0 * S.s2 - S.s1 * S.s1;
    if (S.s0 < (r == 0 ? 3 : kFewestShortFit) || !(det > 1e-6 * S.s0 * S.s2)) break;
    // The residuals' degrees of freedom (three axes, two parameters each) and the 99.9 %
    // quantile of their chi-square (Wilson-Hilferty).
    const double dof = 3 * (S.s0 - 2);
    const double w = 2.0 / (9.0 * dof);
    const double q = dof * std::pow(1.0 - w + 3.09 * std::sqrt(w), 3);
    const Vec3 ca0 = (S.s2 * S.a0 - S.s1 * S.a1) / det, ca1 = (S.s0 * S.a1 - S.s1 * S.a0) / det;
    if (!accel_line && S.aa - ca0.dot(S.a0) - ca1.dot(S.a1) <= q * accel_sigma * accel_sigma) {
      accel = ca0;
      accel_line = true;
    }
    const Vec3 cg0 = (S.s2 * S.g0 - S.s1 * S.g1) / det, cg1 = (S.s0 * S.g1 - S.s1 * S.g0) / det;
    if (!gyro_line && S.gg - cg0.dot(S.g0) - cg1.dot(S.g1) <= q * gyro_sigma * gyro_sigma) {
      gyro_rate = cg1;
      gyro_line = true;
    }
  }
  return gyro_line;
}

void DopplerInertialFilter::extendRunningSums(const std::vector<ImuSample>& imu,
                                              std::vector<RunningSums>& sums) {
  if (sums.empty()) sums.emplace_back();
  while (sums.size() < imu.size() + 1) {
    const ImuSample& s = imu[sums.size() - 1];
    RunningSums next = sums.back();
    const double u = s.t - imu.front().t;
    next.u += u;
    next.uu += u * u;
    next.a += s.accel;
    next.ua += u * s.accel;
    next.aa += s.accel.squaredNorm();
    next.g += s.gyro;
    next.ug += u * s.gyro;
    next.gg += s.gyro.squaredNorm();
    sums.push_back(next);
  }
}

std::size_t DopplerInertialFilter::interpolationSpan(const std::vector<ImuSample>& imu, double t,
                                                     std::size_t hint, std::size_t& lo) {
  // The interval of samples that holds t, then up to one more sample on each side.
  const std::size_t n = imu.size();
  std::size_t j = 0;  // imu[j].t <= t < imu[j + 1].t (clamped)
  if (n >= 2) {
    if (hint < n) {
      // A few steps from the hint (the callers' times lie within an interval of it).
      j = hint;
      while (j + 1 < n && imu[j + 1].t <= t) ++j;
      while (j > 0 && imu[j].t > t) --j;
    } else {
      const auto it = std::upper_bound(imu.begin(), imu.end(), t,
                                       [](double x, const ImuSample& s) { return x < s.t; });
      j = static_cast<std::size_t>(std::max<std::ptrdiff_t>(0, (it - imu.begin()) - 1));
    }
    j = std::min(j, n - 2);
  }
  lo = j > 0 ? j - 1 : 0;
  return std::min(n - 1, j + 2);
}

void DopplerInertialFilter::lagrangeWeights(const std::vector<ImuSample>& imu, double t,
                                            std::size_t lo, std::size_t hi, double* w, double* dw) {
  constexpr std::size_t kMaxSpan = 4;  // what interpolationSpan() gives
  const std::size_t span = hi - lo + 1;
  if (span <= kMaxSpan) {
    // The same operations as the general loop below, each difference and inverse once: t - t_m
    // is alike for every i, and 1 / (t_m - t_i) = -(1 / (t_i - t_m)) exactly (IEEE rounding is
    // symmetric), so the inverses of the pairs i > m are the negated ones of i < m.
    double dt[kMaxSpan], inv[kMaxSpan][kMaxSpan];
    for (std::size_t a = 0; a < span; ++a) dt[a] = t - imu[lo + a].t;
    for (std::size_t a = 0; a < span; ++a)
      for (std::size_t b = a + 1; b < span; ++b) {
        inv[a][b] = 1.0 / (imu[lo + a].t - imu[lo + b].t);
        inv[b][a] = -inv[a][b];
      }
    for (std::size_t a = 0; a < span; ++a) {
      double wi = 1.0, dwi = 0.0;
      for (std::size_t b = 0; b < span; ++b) {
        if (b == a) continue;
        const double f = dt[b] * inv[a][b];
        dwi = dwi * f + wi * inv[a][b];
        wi *= f;
      }
      w[a] = wi;
      dw[a] = dwi;
    }
    return;
  }
  for (std::size_t i = lo; i <= hi; ++i) {
    // Lagrange basis polynomial of node i at t, and its derivative (product rule).
    double wi = 1.0, dwi = 0.0;
    for (std::size_t m = lo; m <= hi; ++m) {
      if (m == i) continue;
      const double inv = 1.0 / (imu[i].t - imu[m].t);
      const double f = (t - imu[m].t) * inv;
      dwi = dwi * f + wi * inv;
      wi *= f;
    }
    w[i - lo] = wi;
    dw[i - lo] = dwi;
  }
}

FilterState DopplerInertialFilter::integrate(const FilterState& x,
                                             const std::vector<ImuSample>& imu, std::size_t k,
                                             double tau, MatS* J) {
  ImuAlong along;
  if (tau != 0) sampleImu(imu, k, tau, along);
  IntegrationJacobian blocks;
  const FilterState y = integrate(x, imu, k, tau, J != nullptr ? &blocks : nullptr, along);
  if (J != nullptr) *J = blocks.matrix();
  return y;
}

DopplerInertialFilter::MatS DopplerInertialFilter::IntegrationJacobian::matrix() const {
  MatS J = MatS::Identity();  // the biases and the calibration do not change between samples
  J.block<3, 3>(kTheta, kTheta) = th_th;
  J.block<3, 3>(kTheta, kBg) = th_bg;
  J.block<3, 3>(kVel, kTheta) = v_th;
  J.block<3, 3>(kVel, kBg) = v_bg;
  J.block<3, 3>(kVel, kBa) = v_ba;
  J.block<3, 3>(kPos, kVel) = tau * Mat3::Identity();
  J.block<3, 3>(kPos, kTheta) = p_th;
  J.block<3, 3>(kPos, kBg) = p_bg;
  J.block<3, 3>(kPos, kBa) = p_ba;
  return J;
}

void DopplerInertialFilter::sampleImu(const std::vector<ImuSample>& imu, std::size_t k, double tau,
                                      ImuAlong& along) {
  const double t = imu[k].t;
  const std::array<double, 3> s = {0.25 * tau, 0.5 * tau, tau};
  for (std::size_t i = 0; i < 3; ++i)
    interpolateImu(imu, t + s[i], along.gyro[i], along.accel[i], k);
  along.tau = tau;
  along.samples = imu.size();
  // The span read at the latest instant (the spans grow with the time) ends before the last
  // sample: samples added later are not read.
  std::size_t lo = 0;
  along.complete = interpolationSpan(imu, t + std::max(0.25 * tau, tau), k, lo) + 1 < imu.size();
}

const DopplerInertialFilter::ImuAlong& DopplerInertialFilter::imuAlong(
    const std::vector<ImuSample>& imu, std::size_t k, double tau, ImuAlong& cache) {
  if (!(cache.tau == tau && (cache.samples == imu.size() || cache.complete)))
    sampleImu(imu, k, tau, cache);
  return cache;
}

FilterState DopplerInertialFilter::integrate(const FilterState& x,
                                             const std::vector<ImuSample>& imu, std::size_t k,
                                             double tau, IntegrationJacobian* J,
                                             const ImuAlong& along) {
  if (tau == 0) {  // what the formulas below give exactly, without their work
    FilterState y = x;
    y.t = imu[k].t;
    if (J != nullptr) *J = IntegrationJacobian{};
    return y;
  }
  // Rates at s = 0, tau/4, tau/2, tau (the node's own sample at s = 0).
  const double t = imu[k].t;
  std::array<Vec3, 4> w, f;
  w[0] = imu[k].gyro;
  f[0] = imu[k].accel;
  for (std::size_t i = 1; i < 4; ++i) {
    w[i] = along.gyro[i - 1];
    f[i] = along.accel[i - 1];
  }
  for (int i = 0; i < 4; ++i) {
    w[static_cast<std::size_t>(i)] -= x.b_g;
    f[static_cast<std::size_t>(i)] -= x.b_a;
  }
  // Rotation vectors over [0, tau/2] and [0, tau] (Simpson, plus the coning correction).
  const Vec3 phi_h =
      (0.5 * tau / 6.0) * (w[0] + 4.0 * w[1] + w[2]) + w[0].cross(w[2]) * (0.25 * tau * tau / 12.0);
  const Vec3 phi = (tau / 6.0) * (w[0] + 4.0 * w[2] + w[3]) + w[0].cross(w[3]) * (tau * tau / 12.0);
  Mat3 E_h, E, Jr_h, Jr_1;
  if (J != nullptr) {
    expAndRightJacobian(phi_h, E_h, Jr_h);
    expAndRightJacobian(phi, E, Jr_1);
  } else {
    E_h = Exp(phi_h);
    E = Exp(phi);
  }
  const Mat3 R_h = x.R_wb * E_h, R_1 = x.R_wb * E;
  const Vec3 a0 = x.R_wb * f[0] + kGravityW, ah = R_h * f[2] + kGravityW,
             a1 = R_1 * f[3] + kGravityW;
  FilterState y = x;
  y.t = t + tau;
  y.R_wb = R_1;
  y.v_w = x.v_w + (tau / 6.0) * (a0 + 4.0 * ah + a1);
  y.p_w = x.p_w + x.v_w * tau + (tau * tau / 6.0) * (a0 + 2.0 * ah);
  if (J != nullptr) {
    // dtheta_s = E_s^T dtheta + J_r(phi_s) dphi_s/db_g db_g
    // da_s = -R_s [f_s]x dtheta_s - R_s db_a;  dv' = dv + tau/6 (da_0 + 4 da_h + da_1)
    // dp' = dp + tau dv + tau^2/6 (da_0 + 2 da_h)
    const Mat3 th_h = E_h.transpose(), th_1 = E.transpose();
    const Mat3 bg_h = Jr_h * incrementBiasJacobian(w[0], w[2], 0.5 * tau);
    const Mat3 bg_1 = Jr_1 * incrementBiasJacobian(w[0], w[3], tau);
    const Mat3 a0_th = -x.R_wb * skew(f[0]), a0_ba = -x.R_wb;
    const Mat3 ah_th = -R_h * skew(f[2]) * th_h, ah_bg = -R_h * skew(f[2]) * bg_h, ah_ba = -R_h;
    const Mat3 a1_th = -R_1 * skew(f[3]) * th_1, a1_bg = -R_1 * skew(f[3]) * bg_1, a1_ba = -R_1;
    J->tau = tau;
    J->th_th = th_1;
    J->th_bg = bg_1;
    const double cv = tau / 6.0, cp = tau * tau / 6.0;
    J->v_th = cv * (a0_th + 4.0 * ah_th + a1_th);
    J->v_bg = cv * (4.0 * ah_bg + a1_bg);
    J->v_ba = cv * (a0_ba + 4.0 * ah_ba + a1_ba);
    J->p_th = cp * (a0_th + 2.0 * ah_th);
    J->p_bg = cp * 2.0 * ah_bg;
    J->p_ba = cp * (a0_ba + 2.0 * ah_ba);
  }
  return y;
}

FilterState DopplerInertialFilter::propagate(const FilterState& x,
                                             const std::vector<ImuSample>& imu, std::size_t k,
                                             MatS* F) {
  FilterState y = integrate(x, imu, k, imu[k + 1].t - imu[k].t, F);
  y.t = imu[k + 1].t;
  return y;
}

FilterState DopplerInertialFilter::propagate(const Node& n, const FilterState& x,
                                             IntegrationJacobian* F, IntervalNoise* noise) const {
  if (n.k_next == n.k + 1) {
    const double tau = imu_[n.k + 1].t - imu_[n.k].t;
    FilterState y = applyPreintegration(increment(x, imu_, n.k, tau, n.step).pre, imu_, x, F);
    y.t = imu_[n.k + 1].t;
    return y;
  }
  // Across the samples to the next node: through the interval's preintegration (the chain of the
  // node's integrations forward, made once at the biases of the first pass that needs it).
  const FilterState y = applyPreintegration(
      preintegrated(imu_, n.k, n.k_next, x, n.ahead, n.behind, n.pre.ahead), imu_, x, F);
  if (noise != nullptr) intervalNoise(n, x.R_wb, *noise);
  return y;
}

void DopplerInertialFilter::intervalNoise(const Node& n, const Mat3& R, IntervalNoise& N) const {
  // Each step's noise (as a single step's, propagateCovariance: qg on the attitude, qa on the
  // velocity and the position integrating it) carried to the interval's end by the transition
  // from the step's end a to it, which the chain's prefixes give in the node's body frame (as
  // applyPreintegration's blocks): theta' = dR_ae^T theta, p' = p + tau_ae v + C theta, v' = v + B
  // theta, with C = -[dp_e - dp_a - dv_a tau_ae]x dR_a and B = -[dv_e - dv_a]x dR_a. The white
  // noises are isotropic on each block, so the attitude's stays qg I whatever the rotation, and
  // the world's frame is the body's at the node turned by R on position and velocity.
  const std::vector<Preintegration>& c = n.pre.ahead.prefix;
  const std::size_t steps = n.k_next - n.k;
  const Preintegration& e = c[steps - 1];
  N.has_extra = !imu_extra_var_.empty();
  Mat3 g_tp = Mat3::Zero(), g_tv = Mat3::Zero(), g_pp = Mat3::Zero(), g_pv = Mat3::Zero(),
       g_vv = Mat3::Zero();                       // per unit gyro variance
  double g_tt = 0, a_pp = 0, a_pv = 0, a_vv = 0;  // isotropic parts
  Mat3 x_tp = Mat3::Zero(), x_tv = Mat3::Zero(), x_pp = Mat3::Zero(), x_pv = Mat3::Zero(),
       x_vv = Mat3::Zero();  // the synthetic samples' extra, absolute
  double x_tt = 0, xa_pp = 0, xa_pv = 0, xa_vv = 0;
  for (std::size_t i = 0; i < steps; ++i) {
    const std::size_t j = n.k + i;  // the step from j to a = j + 1
    const double tau = imu_[j + 1].t - imu_[j].t;
    const double t_ae = imu_[n.k_next].t - imu_[j + 1].t;
    const double qg = tau * tau, qa_pp = qg * tau * tau / 4.0, qa_pv = qg * tau / 2.0, qa_vv = qg;
    // Accelerometer: [I t_ae I; 0 I] on (p, v), isotropic.
    const double s_pp = qa_pp + 2.0 * t_ae * qa_pv + t_ae * t_ae * qa_vv;
    const double s_pv = qa_pv + t_ae * qa_vv;
    double vg = 0.0, va = 0.0;
    if (N.has_extra) stepExtraVariances(j, vg, va);
    a_pp += s_pp;
    a_pv += s_pv;
    a_vv += qa_vv;
    xa_pp += va * s_pp;
    xa_pv += va * s_pv;
    xa_vv += va * qa_vv;
    g_tt += qg;
    x_tt += vg * qg;
    if (i + 1 == steps) {  // the last step ends at the node: no transition
      continue;
    }
    const Preintegration& a = c[i];
    const Mat3 A = a.dR.transpose() * e.dR;  // dR_ae; theta' = A^T theta
    const Mat3 B = -skew(Vec3(e.dv - a.dv)) * a.dR;
    const Mat3 C = -skew(Vec3(e.dp - a.dp - a.dv * t_ae)) * a.dR;
    const Mat3 At = A.transpose();
    // Phi Qg Phi^T with Qg = qg I on theta: theta' theta'^T = qg I (A orthogonal).
    const Mat3 tp = At * C.transpose(), tv = At * B.transpose();
    const Mat3 pp = C * C.transpose(), pv = C * B.transpose(), vv = B * B.transpose();
    g_tp += qg * tp;
    g_tv += qg * tv;
    g_pp += qg * pp;
    g_pv += qg * pv;
    g_vv += qg * vv;
    if (vg > 0) {
      x_tp += vg * qg * tp;
      x_tv += vg * qg * tv;
      x_pp += vg * qg * pp;
      x_pv += vg * qg * pv;
      x_vv += vg * qg * vv;
    }
  }
  // In the world's frame: T N T^T with T = diag(I, R, R).
  auto fill = [&](Mat9& M, double tt, const Mat3& tp, const Mat3& tv, const Mat3& pp, double spp,
                  const Mat3& pv, double spv, const Mat3& vv, double svv) {
    const Mat3 Rt = R.transpose();
    M.block<3, 3>(kTheta, kTheta) = tt * Mat3::Identity();
    M.block<3, 3>(kTheta, kPos) = tp * Rt;
    M.block<3, 3>(kTheta, kVel) = tv * Rt;
    M.block<3, 3>(kPos, kTheta) = M.block<3, 3>(kTheta, kPos).transpose();
    M.block<3, 3>(kVel, kTheta) = M.block<3, 3>(kTheta, kVel).transpose();
    M.block<3, 3>(kPos, kPos) = R * pp * Rt + spp * Mat3::Identity();
    M.block<3, 3>(kPos, kVel) = R * pv * Rt + spv * Mat3::Identity();
    M.block<3, 3>(kVel, kPos) = M.block<3, 3>(kPos, kVel).transpose();
    M.block<3, 3>(kVel, kVel) = R * vv * Rt + svv * Mat3::Identity();
  };
  const Mat3 Z = Mat3::Zero();
  fill(N.g, g_tt, g_tp, g_tv, g_pp, 0.0, g_pv, 0.0, g_vv, 0.0);
  fill(N.a, 0.0, Z, Z, Z, a_pp, Z, a_pv, Z, a_vv);
  if (N.has_extra)
    fill(N.extra, x_tt, x_tp, x_tv, x_pp, xa_pp, x_pv, xa_pv, x_vv, xa_vv);
  else
    N.extra.setZero();
}

void DopplerInertialFilter::compose(const IntegrationJacobian& later, IntegrationJacobian& J) {
  // later after J, block by block (th' = th_th th + th_bg b_g; p' = p + tau v + p_th th + p_bg
  // b_g + p_ba b_a; v' = v + v_th th + v_bg b_g + v_ba b_a; the rest unchanged).
  // In place: each row block before the blocks it reads are overwritten (p reads v and th, v
  // reads th; the products are evaluated into temporaries).
  const IntegrationJacobian& L = later;
  J.p_th = J.p_th + L.tau * J.v_th + L.p_th * J.th_th;
  J.p_bg = J.p_bg + L.tau * J.v_bg + L.p_th * J.th_bg + L.p_bg;
  J.p_ba = J.p_ba + L.tau * J.v_ba + L.p_ba;
  J.v_th = J.v_th + L.v_th * J.th_th;
  J.v_bg = J.v_bg + L.v_th * J.th_bg + L.v_bg;
  J.v_ba = J.v_ba + L.v_ba;
  J.th_bg = L.th_th * J.th_bg + L.th_bg;
  J.th_th = L.th_th * J.th_th;
  J.tau = J.tau + L.tau;
}

FilterState DopplerInertialFilter::integrateAcross(
    const FilterState& x, const std::vector<ImuSample>& imu, std::size_t k, double tau,
    IntegrationJacobian* J, std::vector<ImuAlong>& ahead, std::vector<ImuAlong>& behind,
    ImuAlong& partial, const ImuAlong** last, PreintegrationChains* pre, const Node* before) {
  // Whole sample intervals while the end lies at or beyond the next sample (in the direction of
  // tau), then what is left from the sample reached.
  const double t_end = imu[k].t + tau;
  const bool forward = tau > 0;
  IntegrationJacobian total, step;
  FilterState y = x;
  const ImuAlong* along = nullptr;
  std::size_t j = k;
  if (pre != nullptr) {
    // The whole intervals to the sample nearest the end at once, preintegrated, then the rest
    // (either way): an end near a sample (a fit instant there, moved by the clock offset's
    // estimate) keeps its preintegration whichever side of the sample it falls.
    while (forward ? j + 1 < imu.size() && imu[j + 1].t - t_end <= t_end - imu[j].t
                   : j > 0 && t_end - imu[j - 1].t <= imu[j].t - t_end)
      j = forward ? j + 1 : j - 1;
    const std::size_t steps = forward ? j - k : k - j;
    // Back towards the node before: through its chain forward (which reaches this node), so
    // every sample is integrated once; else (its chain made at biases too far from x's) this
    // node's own chain backward.
    if (j != k && !forward && before != nullptr && before->k_next == k && j >= before->k &&
        backwardThrough(imu, *before, *pre, j, x)) {
      y = applyPreintegration(pre->back, imu, x, J != nullptr ? &total : nullptr);
      // The IMU at the end, as the backward chain's last step samples it (read with no rest).
      if (t_end == imu[j].t) {
        if (behind.size() < steps) behind.resize(steps);
        along = &imuAlong(imu, j + 1, imu[j].t - imu[j + 1].t, behind[steps - 1]);
      }
    } else if (j != k) {
      const Preintegration& P =
          preintegrated(imu, k, j, x, ahead, behind, forward ? pre->ahead : pre->behind);
      y = applyPreintegration(P, imu, x, J != nullptr ? &total : nullptr);
      along = &(forward ? ahead : behind)[steps - 1];
    }
  }
  for (std::size_t i = 0; pre == nullptr; ++i) {
    const bool more =
        forward ? j + 1 < imu.size() && imu[j + 1].t <= t_end : j > 0 && imu[j - 1].t >= t_end;
    if (!more) break;
    const std::size_t to = forward ? j + 1 : j - 1;
    std::vector<ImuAlong>& cache = forward ? ahead : behind;
    if (cache.size() <= i) cache.resize(i + 1);
    const double h = imu[to].t - imu[j].t;
    along = &imuAlong(imu, j, h, cache[i]);
    y = integrate(y, imu, j, h, J != nullptr ? &step : nullptr, *along);
    y.t = imu[to].t;
    if (J != nullptr) compose(step, total);
    j = to;
  }
  const double rest = t_end - imu[j].t;
  if (rest != 0) {
    along = &imuAlong(imu, j, rest, partial);
    y = integrate(y, imu, j, rest, J != nullptr ? &step : nullptr, *along);
    if (J != nullptr) compose(step, total);
  }
  if (J != nullptr) *J = total;
  if (last != nullptr) *last = along;
  return y;
}

bool DopplerInertialFilter::chainHolds(const PreintegrationChain& chain, std::size_t from,
                                       bool forward, double span, const FilterState& x) {
  // Made again when the biases moved by more than db_g tau = 1e-3 rad or db_a tau = 1e-2 m/s
  // over the preintegration's span tau: the first order's error, of the order of the products of
  // (db tau) (db_g tau with itself, 1e-6 rad; with db_a tau, 5e-6 m/s: a hundredth or less of
  // what a window resolves), whatever the span. With limits ten times smaller, the smoother's
  // first steps remade a chain for every second sample on dyna_05 at 1 kHz (nodes at 200 Hz),
  // a third of the integrations.
  const std::vector<Preintegration>& c = chain.prefix;
  return !c.empty() && c.front().from == from && (c.front().to > from) == forward &&
         (x.b_g - c.front().b_g).cwiseAbs().maxCoeff() * span <= kMostGyroBiasStep &&
         (x.b_a - c.front().b_a).cwiseAbs().maxCoeff() * span <= kMostAccelBiasStep;
}

const DopplerInertialFilter::Increment& DopplerInertialFilter::increment(
    const FilterState& x, const std::vector<ImuSample>& imu, std::size_t k, double tau,
    Increment& cache, const Node* chain, PreintegrationChains* pre, const Node* before) {
  // At x's biases rounded to a grid whose half cell is the change chainHolds() allows over the
  // span: so the increment, and all that reads it, depends on the data and x only, not on the
  // order of the calls that made it (at a 200 Hz IMU the cells are 0.4 rad/s and 4 m/s^2 wide:
  // made once, at zero biases).
  FilterState at;
  if (tau != 0) {
    const double g = 2.0 * kMostGyroBiasStep / std::abs(tau),
                 a = 2.0 * kMostAccelBiasStep / std::abs(tau);
    at.b_g = (x.b_g / g).array().round() * g;
    at.b_a = (x.b_a / a).array().round() * a;
  }
  const Preintegration& P = cache.pre;
  if (!(cache.tau == tau && (P.samples == imu.size() || P.complete) && P.b_g == at.b_g &&
        P.b_a == at.b_a))
    makeIncrement(at, imu, k, tau, cache, chain, pre, before);
  return cache;
}

void DopplerInertialFilter::makeIncrement(const FilterState& x, const std::vector<ImuSample>& imu,
                                          std::size_t k, double tau, Increment& cache,
                                          const Node* chain, PreintegrationChains* pre,
                                          const Node* before) {
  Preintegration& P = cache.pre;
  // From R = I, v = p = 0 at x's biases (tau = 0: the identity, the sample's gyro); gravity
  // taken out as preintegrated() does.
  FilterState origin;
  origin.b_g = x.b_g;
  origin.b_a = x.b_a;
  origin.t = imu[k].t;
  const ImuAlong* along = nullptr;
  FilterState y;
  if (tau == 0) {
    y = origin;
    P.J = IntegrationJacobian{};
  } else if (chain != nullptr) {
    y = integrateAcross(origin, imu, k, tau, &P.J, chain->ahead, chain->behind, cache.along, &along,
                        pre, before);
  } else {
    along = &imuAlong(imu, k, tau, cache.along);
    y = integrate(origin, imu, k, tau, &P.J, *along);
  }
  cache.tau = tau;
  cache.gyro = along != nullptr ? along->gyro[2] : imu[k].gyro;
  P.from = P.to = k;
  P.samples = imu.size();
  // Every interpolation it read (those of the steps back from sample k reach k + 2) had a
  // sample after its span.
  std::size_t lo = 0;
  P.complete = interpolationSpan(imu, imu[k].t + std::max(0.0, tau), k, lo) + 1 < imu.size();
  P.b_g = x.b_g;
  P.b_a = x.b_a;
  P.endAt(y, tau);
}

void DopplerInertialFilter::Preintegration::at(const FilterState& x, Mat3& E, Vec3& dv_x) const {
  const Vec3 dbg = x.b_g - b_g;
  E = dR * Exp(Vec3(J.th_bg * dbg));
  dv_x = dv + J.v_bg * dbg + J.v_ba * (x.b_a - b_a);
}

void DopplerInertialFilter::Preintegration::endAt(const FilterState& y, double tau) {
  dR = y.R_wb;
  dv = y.v_w - kGravityW * tau;
  dp = y.p_w - 0.5 * kGravityW * (tau * tau);
}

bool DopplerInertialFilter::backwardThrough(const std::vector<ImuSample>& imu, const Node& before,
                                            std::size_t j, const FilterState& x,
                                            Preintegration& D) {
  // A = before.k -> k (the next node's sample) and B = before.k -> j, both from the chain of the
  // node before, in its body frame at its biases b0; from sample k back to sample j:
  //   dR = dR_A^T dR_B,  tau = tau_B - tau_A (< 0),  dv = dR_A^T (dv_B - dv_A),
  //   dp = dR_A^T (dp_B - dp_A - dv_A tau)
  // (gravity's terms cancel: each increment holds it out). At b = b0 + db, dR_A Exp(J_A db)
  // turned back is Exp(-J_A db) dR_A^T, and Exp(-phi) w = w + [w]x phi to first order:
  //   th_bg = J_B.th_bg - dR^T J_A.th_bg,
  //   v_bg = dR_A^T (J_B.v_bg - J_A.v_bg) + [dv]x J_A.th_bg,  v_ba = dR_A^T (J_B.v_ba - J_A.v_ba),
  //   p_bg = dR_A^T (J_B.p_bg - J_A.p_bg - J_A.v_bg tau) + [dp]x J_A.th_bg,
  //   p_ba = dR_A^T (J_B.p_ba - J_A.p_ba - J_A.v_ba tau).
  const std::size_t k = before.k_next, from = before.k;
  if (!chainHolds(before.pre.ahead, from, true, imu[k].t - imu[from].t, x)) return false;
  // The chain reaches k after the first call, so the second reads it as it is.
  preintegrated(imu, from, k, x, before.ahead, before.behind, before.pre.ahead);
  Preintegration identity;  // j = from: nothing
  const std::vector<Preintegration>& c = before.pre.ahead.prefix;
  const Preintegration& A = c[k - from - 1];
  identity.b_g = A.b_g;
  identity.b_a = A.b_a;
  const Preintegration& B =
      j > from ? preintegrated(imu, from, j, x, before.ahead, before.behind, before.pre.ahead)
               : identity;
  const Mat3 At = A.dR.transpose();
  const double tau = B.J.tau - A.J.tau;
  D.from = k;
  D.to = j;
  D.samples = A.samples;
  D.complete = A.complete;
  D.b_g = A.b_g;
  D.b_a = A.b_a;
  D.dR = At * B.dR;
  D.dv = At * (B.dv - A.dv);
  D.dp = At * (B.dp - A.dp - A.dv * tau);
  IntegrationJacobian& J = D.J;
  const Mat3 S_v = skew(D.dv), S_p = skew(D.dp);
  J.tau = tau;
  J.th_th = D.dR.transpose();
  J.th_bg = B.J.th_bg - D.dR.transpose() * A.J.th_bg;
  J.v_th = -S_v;
  J.v_bg = At * (B.J.v_bg - A.J.v_bg) + S_v * A.J.th_bg;
  J.v_ba = At * (B.J.v_ba - A.J.v_ba);
  J.p_th = -S_p;
  J.p_bg = At * (B.J.p_bg - A.J.p_bg - A.J.v_bg * tau) + S_p * A.J.th_bg;
  J.p_ba = At * (B.J.p_ba - A.J.p_ba - A.J.v_ba * tau);
  return true;
}

bool DopplerInertialFilter::backwardThrough(const std::vector<ImuSample>& imu, const Node& before,
                                            PreintegrationChains& pre, std::size_t j,
                                            const FilterState& x) {
  Preintegration& back = pre.back;
  const PreintegrationChain& chain = before.pre.ahead;
  const std::size_t k = before.k_next, from = before.k;
  const bool kept = pre.back_changes == chain.changes && back.to == j && back.from == k &&
                    chain.prefix.size() >= k - from &&
                    chainHolds(chain, from, true, imu[k].t - imu[from].t, x);
  if (kept) return true;
  if (!backwardThrough(imu, before, j, x, back)) return false;
  pre.back_changes = chain.changes;
  return true;
}

const DopplerInertialFilter::Preintegration& DopplerInertialFilter::preintegrated(
    const std::vector<ImuSample>& imu, std::size_t from, std::size_t to, const FilterState& x,
    std::vector<ImuAlong>& ahead, std::vector<ImuAlong>& behind, PreintegrationChain& chain) {
  const bool forward = to > from;
  const std::size_t steps = forward ? to - from : from - to;
  const double span = std::abs(imu[to].t - imu[from].t);
  std::vector<Preintegration>& c = chain.prefix;
  if (chainHolds(chain, from, forward, span, x)) {
    // Those made before samples they read had arrived go (the last ones: they read the most).
    while (!c.empty() && !(c.back().samples == imu.size() || c.back().complete)) {
      c.pop_back();
      ++chain.changes;
    }
    if (c.size() >= steps) return c[steps - 1];
  } else {
    if (!c.empty()) ++chain.changes;
    c.clear();
  }
  // The steps from R = I, v = p = 0 at the chain's biases (x's for a new chain), from the last
  // prefix on: gravity enters as g tau and g tau^2 / 2 (every step adds it in the world frame),
  // taken out to leave the body frame's increments.
  FilterState y;
  IntegrationJacobian total, step;
  std::size_t j = from;
  y.b_g = c.empty() ? x.b_g : c.front().b_g;
  y.b_a = c.empty() ? x.b_a : c.front().b_a;
  y.t = imu[from].t;
  if (!c.empty()) {
    const Preintegration& P = c.back();
    j = P.to;
    const double tau = imu[j].t - imu[from].t;
    y.R_wb = P.dR;
    y.v_w = P.dv + kGravityW * tau;
    y.p_w = P.dp + 0.5 * kGravityW * (tau * tau);
    y.t = imu[j].t;
    total = P.J;
  }
  c.reserve(steps);
  std::vector<ImuAlong>& along = forward ? ahead : behind;
  while (j != to) {
    const std::size_t i = forward ? j - from : from - j;  // the step's index from `from`
    const std::size_t next = forward ? j + 1 : j - 1;
    if (along.size() <= i) along.resize(i + 1);
    const double h = imu[next].t - imu[j].t;
    y = integrate(y, imu, j, h, &step, imuAlong(imu, j, h, along[i]));
    y.t = imu[next].t;
    compose(step, total);
    j = next;
    Preintegration P;
    P.from = from;
    P.to = j;
    P.samples = imu.size();
    // Its steps read samples up to max(from, to) + 2 (the cubic interpolation at each step's end).
    P.complete = std::max(from, j) + 3 < imu.size();
    P.b_g = y.b_g;
    P.b_a = y.b_a;
    P.endAt(y, imu[j].t - imu[from].t);
    P.J = total;
    c.push_back(P);
  }
  return c[steps - 1];
}

FilterState DopplerInertialFilter::applyPreintegration(const Preintegration& P,
                                                       const std::vector<ImuSample>& imu,
                                                       const FilterState& x,
                                                       IntegrationJacobian* J) {
  const Vec3 dbg = x.b_g - P.b_g, dba = x.b_a - P.b_a;
  const double tau = P.J.tau;
  Mat3 E;
  Vec3 dv;
  P.at(x, E, dv);
  const Vec3 dp = P.dp + P.J.p_bg * dbg + P.J.p_ba * dba;
  FilterState y = x;
  y.t = imu[P.to].t;
  y.R_wb = x.R_wb * E;
  y.v_w = x.v_w + kGravityW * tau + x.R_wb * dv;
  y.p_w = x.p_w + x.v_w * tau + 0.5 * kGravityW * (tau * tau) + x.R_wb * dp;
  if (J != nullptr) {
    // R Exp(dtheta) d = R d + R [dtheta]x d = R d - R [d]x dtheta; the bias blocks rotated by R
    // (to first order in the bias change, as the increments).
    J->tau = tau;
    J->th_th = E.transpose();
    J->th_bg = P.J.th_bg;
    J->v_th = -x.R_wb * skew(dv);
    J->v_bg = x.R_wb * P.J.v_bg;
    J->v_ba = x.R_wb * P.J.v_ba;
    J->p_th = -x.R_wb * skew(dp);
    J->p_bg = x.R_wb * P.J.p_bg;
    J->p_ba = x.R_wb * P.J.p_ba;
  }
  return y;
}

FilterState DopplerInertialFilter::integrateAcross(const FilterState& x,
                                                   const std::vector<ImuSample>& imu, std::size_t k,
                                                   double tau, MatS* J) {
  std::vector<ImuAlong> ahead, behind;
  ImuAlong partial;
  IntegrationJacobian blocks;
  const FilterState y = integrateAcross(x, imu, k, tau, J != nullptr ? &blocks : nullptr, ahead,
                                        behind, partial, nullptr);
  if (J != nullptr) *J = blocks.matrix();
  return y;
}

FilterState DopplerInertialFilter::integrateBackThrough(const FilterState& x,
                                                        const std::vector<ImuSample>& imu,
                                                        std::size_t k_before, std::size_t k,
                                                        double tau, const FilterState& x_before,
                                                        MatS* J, bool* through) {
  if (!(k_before < k && k < imu.size() && tau < 0 && imu[k].t + tau >= imu[k_before].t))
    throw std::invalid_argument("DopplerInertialFilter::integrateBackThrough: out of the interval");
  Node before, n;
  before.k = k_before;
  before.k_next = n.k = k;
  n.k_prev = k_before;
  preintegrated(imu, k_before, k, x_before, before.ahead, before.behind, before.pre.ahead);
  if (through != nullptr)
    *through = chainHolds(before.pre.ahead, k_before, true, imu[k].t - imu[k_before].t, x);
  ImuAlong partial;
  IntegrationJacobian blocks;
  const FilterState y = integrateAcross(x, imu, k, tau, J != nullptr ? &blocks : nullptr, n.ahead,
                                        n.behind, partial, nullptr, &n.pre, &before);
  if (J != nullptr) *J = blocks.matrix();
  return y;
}

DopplerInertialFilter::VecS DopplerInertialFilter::IntegrationJacobian::times(
    const VecS& dx) const {
  const auto th = dx.segment<3>(kTheta), v = dx.segment<3>(kVel), bg = dx.segment<3>(kBg),
             ba = dx.segment<3>(kBa);
  VecS y = dx;
  y.segment<3>(kTheta) = th_th * th + th_bg * bg;
  y.segment<3>(kPos) += tau * v + p_th * th + p_bg * bg + p_ba * ba;
  y.segment<3>(kVel) += v_th * th + v_bg * bg + v_ba * ba;
  return y;
}

DopplerInertialFilter::VecS DopplerInertialFilter::IntegrationJacobian::transposeTimes(
    const VecS& y) const {
  const auto th = y.segment<3>(kTheta), p = y.segment<3>(kPos), v = y.segment<3>(kVel);
  VecS z = y;
  z.segment<3>(kTheta) = th_th.transpose() * th + p_th.transpose() * p + v_th.transpose() * v;
  z.segment<3>(kVel) += tau * p;
  z.segment<3>(kBg) += th_bg.transpose() * th + p_bg.transpose() * p + v_bg.transpose() * v;
  z.segment<3>(kBa) += p_ba.transpose() * p + v_ba.transpose() * v;
  return z;
}

void DopplerInertialFilter::stepExtraVariances(std::size_t k, double& vg, double& va) const {
  vg = va = 0.0;
  if (k + 1 < imu_extra_var_.size()) {
    const Eigen::Vector2f v = imu_extra_var_[k].cwiseMax(imu_extra_var_[k + 1]);
    vg = static_cast<double>(v(0));
    va = static_cast<double>(v(1));
  }
}

DopplerInertialFilter::MatS DopplerInertialFilter::propagateCovariance(const IntegrationJacobian& F,
                                                                       const MatS& P, const Node& n,
                                                                       bool full) const {
  const std::size_t k = n.k;
  const double dt = imu_[n.k_next].t - imu_[n.k].t;
  const detail::TransitionBlocks blocks{F.th_th.data(), F.th_bg.data(), F.p_th.data(),
                                        F.p_bg.data(),  F.p_ba.data(),  F.v_th.data(),
                                        F.v_bg.data(),  F.v_ba.data(),  F.tau};
  // The IMU white noises are the process noise (sigma^2 dt^2 per step for the per-sample noise
  // sigma at the IMU rate): velocity qa, the position integrating it (dt/2 per step, fully
  // correlated within the step); the biases may walk.
  // A sample interpolated in place of a fault or a gap adds its interpolation's error: the step
  // takes the larger of its two samples'.
  // Across several samples: the noise propagate() accumulated step by step (Node::noise), added
  // after F P F^T.
  const bool across = n.k_next > k + 1;
  double vg = 0.0, va = 0.0;
  if (!across) stepExtraVariances(k, vg, va);
  const double white_g = across ? 0.0 : params_.gyro_sigma * params_.gyro_sigma;
  const double white_a = across ? 0.0 : params_.accel_sigma * params_.accel_sigma;
  const double qg = (white_g + vg) * dt * dt;
  const double qa = (white_a + va) * dt * dt;
  const detail::ProcessNoiseBlocks Q{
      qg,
      qa * dt * dt / 4.0,
      qa * dt / 2.0,
      qa,
      params_.gyro_bias_random_walk * params_.gyro_bias_random_walk * dt,
      params_.accel_bias_random_walk * params_.accel_bias_random_walk * dt};
  MatS out;
  switch (full ? kStateDim : active_) {
    case kStateDim:
      detail::propagateCovarianceKernel<kStateDim>(blocks, Q, P.data(), out.data());
      break;
    case kTimeDim:
      detail::propagateCovarianceKernel<kTimeDim>(blocks, Q, P.data(), out.data());
      break;
    default:
      detail::propagateCovarianceKernel<kCoreDim>(blocks, Q, P.data(), out.data());
  }
  if (across) {
    Mat9 N = params_.gyro_sigma * params_.gyro_sigma * n.noise.g +
             params_.accel_sigma * params_.accel_sigma * n.noise.a;
    if (n.noise.has_extra) N += n.noise.extra;
    out.topLeftCorner<9, 9>() += 0.5 * (N + N.transpose());
  }
  return out;
}

DopplerInertialFilter::MatS DopplerInertialFilter::transitionJacobian(
    const FilterState& x, const std::vector<ImuSample>& imu, std::size_t k) {
  MatS F;
  integrate(x, imu, k, imu[k + 1].t - imu[k].t, &F);
  return F;
}

DopplerInertialFilter::MatS DopplerInertialFilter::numericalTransitionJacobian(
    const FilterState& x, const std::vector<ImuSample>& imu, std::size_t k) {
  const FilterState y = propagate(x, imu, k);
  MatS F;
  for (int i = 0; i < kStateDim; ++i) {
    VecS e = VecS::Zero();
    e(i) = kJacobianStep;
    const VecS plus = boxminus(propagate(boxplus(x, e), imu, k), y);
    const VecS minus = boxminus(propagate(boxplus(x, -e), imu, k), y);
    F.col(i) = (plus - minus) / (2.0 * kJacobianStep);
  }
  return F;
}

const DopplerInertialFilter::Node* DopplerInertialFilter::nodeBefore(const Node& n) const {
  const std::less<const Node*> less;
  const Node* first = nodes_.data();
  if (nodes_.empty() || less(&n, first) || !less(&n, first + nodes_.size())) return nullptr;
  const std::size_t i = static_cast<std::size_t>(&n - first);
  return i > 0 && nodes_[i - 1].k_next == n.k ? &nodes_[i - 1] : nullptr;
}

Vec3 DopplerInertialFilter::lidarVelocity(const FilterState& x, const std::vector<ImuSample>& imu,
                                          std::size_t k, double tau,
                                          Eigen::Matrix<double, 3, kStateDim>* J) const {
  const Mat3 R_bl = R_bl_ * Exp(x.phi_bl);
  if (J == nullptr)
    return lidarVelocity(x, imu, k, tau, x.dt_l, true, R_bl, nullptr, nullptr, nullptr);
  const Mat3 Jr_phi = rightJacobian(x.phi_bl);
  return lidarVelocity(x, imu, k, tau, x.dt_l, true, R_bl, &Jr_phi, J, nullptr);
}

Vec3 DopplerInertialFilter::lidarVelocity(const FilterState& x, const std::vector<ImuSample>& imu,
                                          std::size_t k, double tau, double dt_ref,
                                          bool offset_moves, const Mat3& R_bl, const Mat3* Jr_phi,
                                          Eigen::Matrix<double, 3, kStateDim>* J, FitInstant* cache,
                                          const Node* chain, PreintegrationChains* pre) const {
  const double tau_true = tau - dt_ref;
  // The integration to the LiDAR time as an increment from the node's sample (without a cache
  // made at x's biases: exact), applied at x's biases: the attitude there R E, the body
  // velocity E^T (u + dv) with u = R^T (v + g tau) the start's velocity and gravity's share in
  // its body frame. The IMU's gyro there: the node's sample at tau_true = 0, otherwise the
  // integration's own interpolation at its end.
  Increment made;
  const Increment* inc = &made;
  if (cache != nullptr)
    inc = &increment(x, imu, k, tau_true, cache->increment, chain, pre,
                     chain != nullptr && tau_true < 0 ? nodeBefore(*chain) : nullptr);
  else
    makeIncrement(x, imu, k, tau_true, made);
  const Preintegration& P = inc->pre;
  Mat3 E;
  Vec3 dv;
  P.at(x, E, dv);
  const Mat3 Rt0 = x.R_wb.transpose();
  const Vec3 u = Rt0 * (x.v_w + kGravityW * tau_true);
  const Vec3 v_b = E.transpose() * (u + dv);
  Vec3 gyro = inc->gyro;
  if (chain != nullptr) {
    // The lever arm's gyro: the node's fit (gyroFit); the offset's column reads the motion's
    // rate (motionAt()) as for a node per sample, or this fit's where no line holds.
    const double s = tau * chain->inv_h;  // the returns' time, as gyroFit() fits
    const std::array<Vec3, 3>& c = chain->gyro_fit;
    gyro = c[0] + s * (c[1] + s * c[2]);
  }
  const Vec3 omega = gyro - x.b_g;
  const Mat3 Rlb = R_bl.transpose();
  Vec3 v_l = Rlb * (v_b + omega.cross(p_bl_));
  // The offset's share: dv_l/d(dt_l) = -dv_l/dt = -R_bl^T (a_b - omega x v_b + alpha x p_bl),
  // a_b = f - b_a + R^T g, with the rates the motion's (motionAt()), not the samples': where
  // the motion is gentle those are mostly the IMU's noise (sigma_a per sample against a few
  // 0.1 m/s^2; the gyro's slope sqrt(2) sigma_g / dt through the lever arm), and a column of
  // noise reads as knowledge of the offset: a start 0.2 m/s^2 strong claimed 3 ms against a
  // 15 ms error. The model is linear in the offset about dt_ref with this column, so that its
  // derivative is the column (with the samples' interpolant there, Gauss-Newton diverged).
  Vec3 column = Vec3::Zero();
  if (offset_moves && (J != nullptr || x.dt_l != dt_ref)) {
    const double t = imu[k].t + tau_true;
    MotionCache fitted;
    MotionCache& m = cache != nullptr ? cache->motion : fitted;
    if (!(m.t == t && m.gyro_sigma == params_.gyro_sigma && m.accel_sigma == params_.accel_sigma &&
          (m.samples == imu.size() || m.complete))) {
      m.gyro_line = motionAt(imu, t, k, params_.gyro_sigma, params_.accel_sigma, m.accel,
                             m.gyro_rate, &m.complete, &imu == &imu_ ? &imu_sums_ : nullptr);
      m.t = t;
      m.gyro_sigma = params_.gyro_sigma;
      m.accel_sigma = params_.accel_sigma;
      m.samples = imu.size();
    }
    const bool gyro_line = m.gyro_line;
    Vec3 alpha = m.gyro_rate;
    const Vec3& accel = m.accel;
    if (chain != nullptr && !gyro_line) {
      // No line holds: the rate of the gyro the prediction reads (the node's fit), not the
      // interpolant's, so that the column is the prediction's derivative (a handheld start at
      // 597 Hz, nodes at 200 Hz and a 9 ms offset: the offset 8 sigma off with the interpolant's).
      const std::array<Vec3, 3>& c = chain->gyro_fit;
      alpha = (c[1] + 2.0 * (tau * chain->inv_h) * c[2]) * chain->inv_h;
    }
    const Vec3 a_b = accel - x.b_a + E.transpose() * (Rt0 * kGravityW);
    column = -Rlb * (a_b - omega.cross(v_b) + alpha.cross(p_bl_));
    v_l += column * (x.dt_l - dt_ref);
  }
  if (J != nullptr) {
    // The start's attitude R Exp(dtheta) moves u by [u]x dtheta, so v_b = E^T (u + dv) by
    // E^T [u]x dtheta; v by E^T R^T dv; the biases through dv's blocks, E^T J.v_b, and E's,
    // [v_b]x J.th_bg. dv_l = R_bl^T (dv_b + [p_bl]x db_g) + [v_l]x dphi_bl ((R_bl Exp(dphi))^T
    // = Exp(-dphi) R_bl^T). The Doppler does not depend on the position.
    const Mat3 M = Rlb * E.transpose();
    J->block<3, 3>(0, kPos).setZero();
    J->block<3, 3>(0, kTheta) = M * skew(u);
    J->block<3, 3>(0, kVel) = M * Rt0;
    J->block<3, 3>(0, kBg) = M * P.J.v_bg + Rlb * Mat3(skew(v_b) * P.J.th_bg + skew(p_bl_));
    J->block<3, 3>(0, kBa) = M * P.J.v_ba;
    // The correction is additive (phi_bl + dphi): Exp(phi + dphi) = Exp(phi) Exp(J_r(phi) dphi).
    J->block<3, 3>(0, kRot) = skew(v_l) * *Jr_phi;
    J->col(kTime) = column;
  }
  return v_l;
}

DopplerInertialFilter::Vec9 DopplerInertialFilter::velocityPolynomial(const Node& n,
                                                                      const FilterState& x,
                                                                      Mat9xS* G) const {
  // Values at the three fit instants, then the quadratic through them: Q_m = sum_i Vinv(m, i) v_i.
  const Mat3& Vinv = n.V_inv;
  Vec9 Q = Vec9::Zero();
  if (G != nullptr) G->setZero();
  Eigen::Matrix<double, 3, kStateDim> J;
  // The corrected extrinsic rotation and its right Jacobian, alike at the three instants.
  const Mat3 R_bl = R_bl_ * Exp(x.phi_bl);
  Mat3 Jr_phi;
  if (G != nullptr) Jr_phi = rightJacobian(x.phi_bl);
  for (int i = 0; i < 3; ++i) {
    const Vec3 v =
        lidarVelocity(x, imu_, n.k, n.s_fit[i] * n.h, n.dt_ref, !n.still(), R_bl,
                      G != nullptr ? &Jr_phi : nullptr, G != nullptr ? &J : nullptr,
                      &n.fit_imu[static_cast<std::size_t>(i)], n.spansSamples() ? &n : nullptr,
                      n.spansSamples() ? &n.pre : nullptr);
    for (int m = 0; m < 3; ++m) {
      Q.segment<3>(3 * m) += Vinv(m, i) * v;
      if (G != nullptr) G->middleRows<3>(3 * m) += Vinv(m, i) * J;
    }
  }
  return Q;
}

void DopplerInertialFilter::addImu(const ImuSample& s, double gyro_var, double accel_var) {
  if (!imu_.empty() && !(s.t > imu_.back().t))
    throw std::invalid_argument("DopplerInertialFilter::addImu: time does not increase");
  const bool measured = gyro_var == 0.0 && accel_var == 0.0;
  if (!measured && imu_extra_var_.empty()) imu_extra_var_.assign(imu_.size(), {0.0f, 0.0f});
  if (!imu_extra_var_.empty())
    imu_extra_var_.emplace_back(static_cast<float>(gyro_var), static_cast<float>(accel_var));
  imu_.push_back(s);
  extendRunningSums(imu_, imu_sums_);
}

DopplerInertialFilter::MatS DopplerInertialFilter::priorCovariance(const FilterState& x,
                                                                   double v_scale) const {
  const StartPrior& p = prior_;
  // (dtheta, dv_b): roll and pitch in the world, yaw held (the gauge); the body velocity.
  Mat3 tilt_w = Mat3::Zero();
  tilt_w(0, 0) = tilt_w(1, 1) = p.tilt_sigma * p.tilt_sigma;
  tilt_w(2, 2) = 1e-12;
  const Mat3& R = x.R_wb;
  const Mat3 C_th = R.transpose() * tilt_w * R;
  const Mat3 C_vb = p.cov_v_b * v_scale;
  // v_w = R v_b: dv_w = R dv_b - R [v_b]x dtheta.
  const Vec3 v_b = R.transpose() * x.v_w;
  const Mat3 J_th = -R * skew(v_b);
  MatS P = MatS::Zero();
  P.block<3, 3>(kTheta, kTheta) = C_th;
  P.block<3, 3>(kVel, kTheta) = J_th * C_th;
  P.block<3, 3>(kTheta, kVel) = P.block<3, 3>(kVel, kTheta).transpose();
  P.block<3, 3>(kVel, kVel) = J_th * C_th * J_th.transpose() + R * C_vb * R.transpose();
  P.block<3, 3>(kPos, kPos).diagonal().setConstant(1e-12);  // the origin: the gauge
  P.block<3, 3>(kBg, kBg).diagonal().setConstant(p.gyro_bias_sigma * p.gyro_bias_sigma);
  P.block<3, 3>(kBa, kBa).diagonal().setConstant(p.accel_bias_sigma * p.accel_bias_sigma);
  // A tiny variance where the calibration is exact keeps the covariance invertible.
  P.block<3, 3>(kRot, kRot)
      .diagonal()
      .setConstant(std::max(p.rotation_sigma * p.rotation_sigma, 1e-14));
  P(kTime, kTime) = std::max(p.time_sigma * p.time_sigma, 1e-14);
  return 0.5 * (P + P.transpose());
}

DopplerInertialFilter::VecS DopplerInertialFilter::priorMean(const FilterState& x) const {
  // The start knows the body velocity v_b0 = R0^T v_w0 (its returns, in the body frame), not the
  // world one: linearized at x, v_b0 = v_b + [v_b]x dtheta + R^T dv_w, so the velocity's mean is
  // R (v_b0 - v_b - [v_b]x dtheta) at the attitude's mean dtheta (the covariance's coupling,
  // priorCovariance). Taking v_w0 - v_w instead differs by |v| |dtheta|^2 / 2: at 20 m/s and a
  // tilt correction of 2 deg, 12 mm/s, which the smoother's steps kept chasing.
  VecS d = boxminus(x0_prior_, x);
  const Vec3 v_b0 = x0_prior_.R_wb.transpose() * x0_prior_.v_w;
  const Vec3 v_b = x.R_wb.transpose() * x.v_w;
  d.segment<3>(kVel) = x.R_wb * (v_b0 - v_b - skew(v_b) * d.segment<3>(kTheta));
  return d;
}

void DopplerInertialFilter::start(const FilterState& x0, const StartPrior& prior) {
  if (imu_.empty()) throw std::logic_error("DopplerInertialFilter::start before addImu");
  prior_ = prior;
  // A calibration declared exact stays at its prior, uncorrelated with the rest: the filter and
  // the smoother then work on the first 15 components only, or 16 when the clock offset alone is
  // estimated (the calibration test on all 19).
  active_ = prior.rotation_sigma > 0 ? kStateDim : prior.time_sigma > 0 ? kTimeDim : kCoreDim;
  nodes_.clear();
  smoothed_ = 0;
  linearized_ = 0;
  forward_kept_ = 0;
  test_kept_.nodes = 0;
  forward_rss_ = 0;
  forward_returns_ = 0;
  x0_prior_ = x0;
  x0_prior_.t = imu_.front().t;
  Node n;
  n.k = 0;
  n.x_pred = x0_prior_;
  n.x = n.xs = x0_prior_;
  n.P = priorCovariance(x0_prior_);
  nodes_.push_back(n);
}

void DopplerInertialFilter::predict() {
  if (nodes_.empty()) throw std::logic_error("DopplerInertialFilter::predict before start");
  const Node& cur = nodes_.back();
  if (cur.k_next >= imu_.size() || cur.k_next <= cur.k)
    throw std::logic_error("DopplerInertialFilter::predict: no IMU sample for the next node");
  Node n;
  n.k = cur.k_next;
  n.k_prev = cur.k;
  n.k_next = n.k + 1;
  IntegrationJacobian F;
  // Across several samples, the process noise is carried through the steps at the state
  // integrated here (its dependence on the state is of second order), and kept for the
  // smoother's passes.
  Node& c = nodes_.back();
  const bool across = c.k_next > c.k + 1;
  n.x_pred = propagate(c, c.x, &F, across ? &c.noise : nullptr);
  n.P = propagateCovariance(F, c.P, c);
  n.x = n.xs = n.x_pred;
  nodes_.push_back(n);
}

void DopplerInertialFilter::beginNode(bool last, std::size_t next) {
  Node& n = nodes_.back();
  nodeChanged(nodes_.size() - 1);
  // The prior's offset until a smoothing, then the last smoothing's: not the forward filter's own
  // estimate, which a reference following it feeds its errors back into (at a 1.3 kHz IMU, the
  // first nodes of a standing start read the offset from the state's uncertain acceleration, and
  // the reference ran to 37 ms against a 6 ms truth within 15 ms, the returns' acceptance
  // collapsing).
  n.dt_ref = smoothed_ > 0 ? nodes_[smoothed_ - 1].xs.dt_l : x0_prior_.dt_l;
  if (nodes_.size() >= 2) {
    // The previous node's rest is decided; this one's is not until after its update.
    Node& previous = nodes_[nodes_.size() - 2];
    if (previous.after_rest) nodeChanged(nodes_.size() - 2);
    previous.after_rest = false;
    n.after_rest = previous.rest_velocity_sigma > 0;
  }
  n.last = last;
  node_open_ = true;
  n.k_next = last ? n.k : next == 0 ? n.k + 1 : next;
  if (!last && (n.k_next <= n.k || n.k_next >= imu_.size()))
    throw std::logic_error("DopplerInertialFilter::beginNode: no IMU sample for the next node");
  before_ = n.k > 0 ? 0.5 * (imu_[n.k].t - imu_[n.k_prev].t) : 0.0;
  after_ = last ? 0.0 : 0.5 * (imu_[n.k_next].t - imu_[n.k].t);
  n.h = std::max({before_, after_, 1e-6});
  if (before_ > 0 && after_ > 0)
    n.s_fit = {-before_ / n.h, 0.0, after_ / n.h};
  else if (after_ > 0)
    n.s_fit = {0.0, 0.5 * after_ / n.h, after_ / n.h};
  else
    n.s_fit = {-before_ / n.h, -0.5 * before_ / n.h, 0.0};
  if (before_ == 0 && after_ == 0) n.s_fit = {-1.0, 0.0, 1.0};  // a lone node: any three
  Mat3 V;
  for (int i = 0; i < 3; ++i) V.row(i) << 1.0, n.s_fit[i], n.s_fit[i] * n.s_fit[i];
  n.V_inv = V.inverse();
  n.inv_h = 1.0 / n.h;
  if (n.spansSamples()) gyroFit(n, &n.gyro_fit, &n.gyro_fit_cov, &n.gyro_fit_complete);
  n.sums = DopplerSums{};
  open_.clear();
  q_open_ = velocityPolynomial(n, n.x_pred, &G_open_);
  const Eigen::Matrix<double, 3, kStateDim> G0 = G_open_.topRows<3>();
  const MatS& P_gate =
      nodes_.size() == 1 ? priorCovariance(n.x_pred, prior_.gate_velocity_scale) : n.P;
  M_open_ = G0.lazyProduct(P_gate).lazyProduct(G0.transpose());
  gate_speed_open_ = params_.gate_rel * q_open_.head<3>().norm();
}

void DopplerInertialFilter::setReturns(const OpenArrays& returns) {
  OpenReturns& o = open_;
  if (o.given > 0)
    throw std::logic_error("DopplerInertialFilter::setReturns: the node has its returns already");
  o.reserve(returns.count);
  o.in = returns;
  o.given = returns.count;
}

void DopplerInertialFilter::OpenReturns::reserve(std::size_t n) {
  if (n <= residual.size()) return;
  const std::size_t size = std::max(n, 2 * residual.size());
  for (std::vector<double>* v : {&residual, &residual2, &variance2, &inv_norm}) v->resize(size);
  cum_r.resize(size + 1);
  cum_v.resize(size + 1);
  accepted.resize(size);
  passed.resize(size);
  coherent.resize(size);
  index.resize(size);
}

void DopplerInertialFilter::gateAndSum(Node& n) {
  OpenReturns& o = open_;
  const std::size_t m = o.given;
  GatePrediction g;
  for (int i = 0; i < 9; ++i) g.q[i] = q_open_(i);
  g.setCovariance(M_open_);
  g.inv_h = n.inv_h;
  g.r_doppler = r_doppler_;
  g.speed = gate_speed_open_;
  g.gate_min2 = gate_min2_;
  g.gate_k2 = gate_k2_;
  double total[kSumCount];
  const std::size_t used =
      gateAndSumReturns(m, g, o.in.tau, o.in.x, o.in.y, o.in.z, o.in.doppler, o.residual.data(),
                        o.accepted.data(), o.inv_norm.data(), total);
  o.used = used;
  DopplerSums& sums = n.sums;
  for (int c = 0; c < 5; ++c)
    for (int r = 0; r < 6; ++r) sums.S(r, c) += total[6 * c + r];
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) sums.bz(r, c) += total[30 + 3 * c + r];
  sums.c += total[39];
  sums.n += used;
}

void DopplerInertialFilter::removePoint(std::size_t k, double tau, const Eigen::Vector3f& p_l,
                                        double doppler) {
  if (k + 1 == nodes_.size() && node_open_)
    throw std::logic_error("DopplerInertialFilter::removePoint: the node is still open");
  Node& n = nodes_.at(k);
  if (n.sums.n == 0)
    throw std::logic_error("DopplerInertialFilter::removePoint: the node has no point left");
  const Vec3 p = p_l.cast<double>();
  Vec3 d;
  unitDirection(p.x(), p.y(), p.z(), d.x(), d.y(), d.z());
  accumulate(n.sums, normalizedTime(k, tau), d, doppler, -1.0);
  n.rows_stale = true;
  nodeChanged(k);
}

void DopplerInertialFilter::accumulate(DopplerSums& sums, double s, const Vec3& d, double z,
                                       double w) {
  Eigen::Matrix<double, 6, 1> dd;
  dd << d.x() * d.x(), d.x() * d.y(), d.x() * d.z(), d.y() * d.y(), d.y() * d.z(), d.z() * d.z();
  const double s2 = s * s;
  const Eigen::Matrix<double, 5, 1> powers(w, w * s, w * s2, w * s2 * s, w * s2 * s2);
  sums.S.noalias() += dd * powers.transpose();
  sums.bz.noalias() += (z * d) * powers.head<3>().transpose();
  sums.c += w * z * z;
  if (w > 0) {
    ++sums.n;
  } else if (--sums.n == 0) {
    sums = DopplerSums{};  // nothing left: no rounding residue either
  }
}

Mat3 DopplerInertialFilter::DopplerSums::moment(int m) const {
  const auto u = S.col(m);
  Mat3 M;
  M << u(0), u(1), u(2), u(1), u(3), u(4), u(2), u(4), u(5);
  return M;
}

void DopplerInertialFilter::buildRows(Node& n) const {
  n.rows.W.resize(0, 9);
  n.rows.y0.resize(0);
  if (n.sums.n == 0) return;
  Mat9 A;
  Vec9 b;
  for (int m = 0; m < 3; ++m) {
    b.segment<3>(3 * m) = n.sums.bz.col(m);
    for (int k = 0; k < 3; ++k) A.block<3, 3>(3 * m, 3 * k) = n.sums.moment(m + k);
  }
  if (lever_ratio_ > 0) marginalizeLeverNoise(n, A, b);
  const double inv_sigma = 1.0 / params_.doppler_sigma;
  // Well conditioned (the usual case: returns spread over the view and the interval): the
  // Cholesky factor, A = L L^T, gives W = L^T / sigma and y0 = L^-1 b / sigma. Otherwise the
  // eigen-decomposition below keeps the directions the points resolve.
  const Eigen::LLT<Eigen::Matrix<double, 9, 9>> llt(A);
  if (llt.info() == Eigen::Success) {
    const auto L = llt.matrixL();
    const Vec9 pivots = llt.matrixLLT().diagonal();
    constexpr double kMinPivotRatio = 1e-4;  // pivot^2 >= 1e-8 of the largest diagonal of A
    if (pivots.minCoeff() > kMinPivotRatio * std::sqrt(A.diagonal().maxCoeff())) {
      n.rows.W = Eigen::Matrix<double, 9, 9>(L.transpose()) * inv_sigma;
      n.rows.y0 = L.solve(b) * inv_sigma;
      return;
    }
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 9, 9>> es(A);
  const double max_ev = es.eigenvalues().maxCoeff();
  int rows = 0;
  for (int i = 0; i < 9; ++i)
    if (es.eigenvalues()(i) > 1e-10 * max_ev && es.eigenvalues()(i) > 1e-12) ++rows;
  n.rows.W.resize(rows, 9);
  n.rows.y0.resize(rows);
  int r = 0;
  for (int i = 0; i < 9; ++i) {
    const double ev = es.eigenvalues()(i);
    if (!(ev > 1e-10 * max_ev && ev > 1e-12)) continue;
    const Vec9 u = es.eigenvectors().col(i);
    n.rows.W.row(r) = std::sqrt(ev) * inv_sigma * u.transpose();
    n.rows.y0(r) = u.dot(b) / std::sqrt(ev) * inv_sigma;
    ++r;
  }
}

DopplerInertialFilter::LeverNoise DopplerInertialFilter::leverNoise(const Node& n) const {
  // The gyro in the lever-arm term at a return's time is the cubic through the samples around
  // it, so the noise of samples k - 2 .. k + 2 reaches node k's polynomial: at the fit instant i
  // with weight w_j(t_i) for sample j, and Q_m = sum_i V_inv(m, i) v_i.
  LeverNoise E = LeverNoise::Zero();
  const std::size_t first = n.k >= 2 ? n.k - 2 : 0;
  for (int i = 0; i < 3; ++i) {
    const double t = imu_[n.k].t + n.s_fit[static_cast<std::size_t>(i)] * n.h;
    std::size_t lo = 0;
    const std::size_t hi = interpolationSpan(imu_, t, n.k, lo);
    double w[4], dw[4];
    lagrangeWeights(imu_, t, lo, hi, w, dw);
    for (std::size_t j = lo; j <= hi; ++j) {
      const std::size_t col = j - first;
      if (col >= kLeverSamples) continue;  // not reached: the span lies within k -+ 2
      // Its noise relative to gyro_sigma (C below is sigma_g^2 E E^T).
      const double scale = j < imu_extra_var_.size()
                               ? std::sqrt(1.0 + static_cast<double>(imu_extra_var_[j](0)) /
                                                     (params_.gyro_sigma * params_.gyro_sigma))
                               : 1.0;
      for (int m = 0; m < 3; ++m)
        E.block<3, 3>(3 * m, 3 * static_cast<int>(col)) +=
            n.V_inv(m, i) * w[j - lo] * scale * lever_noise_;
    }
  }
  return E;
}

void DopplerInertialFilter::gyroFit(const Node& n, std::array<Vec3, 3>* coef, Mat3* cov,
                                    bool* complete) const {
  // The node's samples: those in its interval of returns taken to the IMU's clock (shifted by
  // dt_ref, where lidarVelocity() reads the fit: a fit through the node's own samples would be
  // extrapolated there, by two node intervals at a 9 ms offset with nodes at 200 Hz, and a
  // brisk rotation's lever-arm term with it), or the one nearest the interval's centre where
  // none is inside, and the sample on either side of them: a quadratic through the interval's
  // samples alone is a line at two nodes per sample interval (a 386 Hz IMU with nodes at 200 Hz),
  // and a hand's tremor curves the rate within it (bounded nodes, seed 45400135 of the Fast IMUs
  // set: node chi2/dof 1.31 against 1.00 with a node per sample, the accelerometer bias 0.118
  // m/s^2 off with a NEES of 22; 0.012 and 0.2 with the samples either side, as a node per sample
  // reads four around each return). In the returns' own time (s = tau / h, tau from the node's
  // LiDAR time, sample j at tau_j = t_j - t_k + dt_ref): the coefficients are then those of the
  // velocity polynomial's lever-arm term, and their covariance its own (leverCovariance()).
  // Times relative to the node's sample, a boundary within a thousandth of a sample interval
  // (absolute stamps carry 1e-7 s of rounding).
  const double t_k = imu_[n.k].t;
  const double before = 0.5 * (t_k - imu_[n.k_prev].t);
  const double after = 0.5 * (imu_[n.k_next].t - t_k);
  const double on_boundary =
      1e-3 * (imu_.size() > 1 ? (imu_.back().t - imu_.front().t) / (imu_.size() - 1) : 1.0);
  auto tau_of = [&](std::size_t j) { return imu_[j].t - t_k + n.dt_ref; };
  auto first_at = [&](double tau) {  // the first sample at or after LiDAR tau
    return static_cast<std::size_t>(
        std::lower_bound(imu_.begin(), imu_.end(), tau,
                         [&](const ImuSample& x, double b) { return x.t - t_k + n.dt_ref < b; }) -
        imu_.begin());
  };
  // [lo, hi): the samples inside; hi, the first after them, is the last one read.
  std::size_t lo = first_at(-before - on_boundary), hi = first_at(after + on_boundary);
  if (lo >= hi) {  // no sample inside: the nearest one to the centre
    const std::size_t j = std::min(first_at(0.0), imu_.size() - 1);
    lo = j > 0 && -tau_of(j - 1) < tau_of(j) ? j - 1 : j;
    hi = lo + 1;
  }
  // With the sample after them read, later samples change nothing.
  if (complete != nullptr) *complete = hi < imu_.size();
  if (lo > 0) --lo;
  hi = std::min(hi, imu_.size() - 1);  // now the last sample read
  const int dim = static_cast<int>(std::min<std::size_t>(3, hi - lo + 1));  // degree + 1
  auto basis = [&](std::size_t j) {
    const double s = tau_of(j) * n.inv_h;
    Vec3 x(1.0, s, s * s);
    x.tail(3 - dim).setZero();
    return x;
  };
  // M = sum x x^T (its unused degrees the identity's); sample j's coefficients a_j = M^-1 x.
  Mat3 M = Mat3::Zero();
  for (std::size_t j = lo; j <= hi; ++j) {
    const Vec3 x = basis(j);
    M += x * x.transpose();
  }
  for (int d = dim; d < 3; ++d) M(d, d) = 1.0;
  const Mat3 M_inv = M.inverse();
  if (coef != nullptr) coef->fill(Vec3::Zero());
  if (cov != nullptr) cov->setZero();
  const double var_g = params_.gyro_sigma * params_.gyro_sigma;
  for (std::size_t j = lo; j <= hi; ++j) {
    const Vec3 a = M_inv * basis(j);
    if (coef != nullptr)
      for (int m = 0; m < dim; ++m) (*coef)[static_cast<std::size_t>(m)] += a(m) * imu_[j].gyro;
    if (cov != nullptr) {
      // Its noise relative to gyro_sigma, as in leverNoise().
      const double rel =
          j < imu_extra_var_.size() ? 1.0 + static_cast<double>(imu_extra_var_[j](0)) / var_g : 1.0;
      *cov += rel * a * a.transpose();
    }
  }
}

DopplerInertialFilter::Mat9 DopplerInertialFilter::leverCovariance(const Node& n) const {
  if (n.spansSamples()) {
    // Q_m's lever-arm part is lever_noise_ c_m (the quadratic through the fit instants of a
    // quadratic is itself): block (m, l) of the covariance is cov(c_m, c_l) L L^T.
    // The covariance kept at beginNode() (or referOffsets()) holds while every sample is a measured
    // one (with synthetic ones it depends on gyro_sigma, which setNoise() may have changed since).
    Mat3 cov = n.gyro_fit_cov;
    if (!imu_extra_var_.empty()) gyroFit(n, nullptr, &cov);
    const Mat3 LLt = lever_noise_ * lever_noise_.transpose();
    Mat9 C;
    for (int m = 0; m < 3; ++m)
      for (int l = 0; l < 3; ++l) C.block<3, 3>(3 * m, 3 * l) = cov(m, l) * LLt;
    return C;
  }
  const LeverNoise E = leverNoise(n);
  return E.lazyProduct(E.transpose());
}

void DopplerInertialFilter::marginalizeLeverNoise(const Node& n, Mat9& A, Vec9& b) const {
  // The node's LiDAR velocity is computed with the measured gyro, omega = gyro - b_g, through the
  // lever arm: v_l = R_bl^T (v_b + omega x p_bl). The gyro's white noise (gyro_sigma per sample
  // and axis) thus moves Q = [q0; q1; q2] by E n (n: the noise of the samples the interpolation
  // uses, leverNoise()), for every return of the node at once: with thousands of returns per
  // IMU sample it can exceed what their Doppler resolves (0.0025 rad/s through a 0.27 m arm is
  // 0.7 mm/s; 10,000 returns at 0.03 m/s resolve 0.3 mm/s). It is marginalized out of the
  // node's quadratic form: the returns' residuals z + D Q then have the covariance
  // sigma_d^2 I + D C D^T, C = sigma_g^2 E E^T, and with A = D^T D, b = D^T z,
  //   D^T (sigma_d^2 I + D C D^T)^-1 [D, z] = (sigma_d^2 I + A C)^-1 [A, b],
  // so A' = Y^-1 A and b' = Y^-1 b with Y = I + A C / sigma_d^2 (one 9x9 solve, touching no
  // return). Left out, the filter's covariance fell below the Cramer-Rao bound when
  // kappa = (2/3) sigma_g^2 |p_bl|^2 n_node / sigma_d^2 was near or above 1.
  // Not modelled: the correlation between neighbouring nodes (they share samples) and with the
  // same samples' noise in the attitude propagation (its process noise).
  // Coefficient-based products (lazyProduct): at these sizes Eigen's blocked kernels cost more.
  Mat9 C_scaled;  // C / sigma_d^2
  if (n.spansSamples()) {
    C_scaled = leverCovariance(n) / lever_ratio_;
  } else {
    const LeverNoise E = leverNoise(n);
    C_scaled = E.lazyProduct(E.transpose()) / lever_ratio_;
  }
  Mat9 Y = A.lazyProduct(C_scaled);
  Y.diagonal().array() += 1.0;
  Eigen::Matrix<double, 9, 10> X;
  X << A, b;
  solveInPlace(Y, X);
  A = 0.5 * (X.leftCols<9>() + X.leftCols<9>().transpose());
  b = X.col(9);
}

template <int D, int R>
DopplerInertialFilter::VecS DopplerInertialFilter::kalmanUpdate(
    const Eigen::Matrix<double, R, D>& H, const Eigen::Matrix<double, R, 1>& r0,
    const VecS& dx_prior, MatS& P) {
  // On the first D components (the others constant, uncorrelated, and without effect here when
  // D < 19); residual r0 + H dx, unit noise. The products as vector code (filter_kernels.h).
  // Neither the Doppler nor the rest depends on the position: H's position columns are zero,
  // and the products skip them (a fifth of H P and of H P H^T). Checked (27 values), so that a
  // measurement model that comes to depend on the position cannot be updated wrongly in silence.
  static_assert(kPos == 3 && kStateDim == 19, "the layout filter_kernels.h assumes");
  if (!H.template middleCols<3>(kPos).isZero(0.0))
    throw std::logic_error("DopplerInertialFilter::kalmanUpdate: H depends on the position");
  const Eigen::Matrix<double, R, 1> innovation = -r0 - H * dx_prior.template head<D>();
  VecS dx = dx_prior;
  detail::kalmanUpdateKernel<D, R>(P.data(), H.data(), innovation.data(), dx.data());
  return dx;
}

DopplerInertialFilter::VecS DopplerInertialFilter::dopplerUpdate(const Node& n, const Vec9& Q,
                                                                 const Mat9xS& G,
                                                                 const VecS& dx_prior, MatS& P,
                                                                 bool full) const {
  const int rows = static_cast<int>(n.rows.W.rows());
  if (rows == 0) return dx_prior;
  // Fixed-size 9-row form (rows beyond the node's rank are zero: they add an identity block to
  // S and nothing else), so that every product below is unrolled at compile time.
  Mat9 W = Mat9::Zero();
  Vec9 y0 = Vec9::Zero();
  W.topRows(rows) = n.rows.W;
  y0.head(rows) = n.rows.y0;
  // H = W G (formed by the kernel) on the components updated only (the calibration's columns
  // are not needed when it is declared exact). The Doppler does not depend on the position: the
  // kernel skips G's position columns, checked here (see kalmanUpdate()).
  const Vec9 r0 = W * Q + y0;
  if (!G.middleCols<3>(kPos).isZero(0.0))
    throw std::logic_error("DopplerInertialFilter::dopplerUpdate: G depends on the position");
  VecS dx = dx_prior;
  switch (full ? kStateDim : active_) {
    case kStateDim:
      detail::dopplerUpdateKernel<kStateDim>(P.data(), W.data(), G.data(), r0.data(), dx.data());
      break;
    case kTimeDim:
      detail::dopplerUpdateKernel<kTimeDim>(P.data(), W.data(), G.data(), r0.data(), dx.data());
      break;
    default:
      detail::dopplerUpdateKernel<kCoreDim>(P.data(), W.data(), G.data(), r0.data(), dx.data());
  }
  return dx;
}

void DopplerInertialFilter::update() {
  // One Gauss-Newton step per solve: the smoother re-linearizes every node afterwards, so the
  // forward pass needs its update for the gates only. One step, and one more from it after the
  // second gate, against two and one: median difference of error/bound 1e-4 (held-out seeds
  // 15000001-300: no status changed, the same wrong results flagged; a few ill-posed ones that
  // are flagged either way moved), for 5 % fewer instructions.
  Node& n = nodes_.back();
  nodeChanged(nodes_.size() - 1);
  gateAndSum(n);
  const MatS P_pred = n.P;
  // The update linearized at x_start (Q, G: the node's velocity polynomial there and its
  // Jacobian): the prediction, where beginNode() linearized the node for its gate (q_open_,
  // G_open_), or the first solve's result, where the second gate linearized it, when that gate
  // dropped a few points.
  auto solve = [&](FilterState& x_out, MatS& P_out, const FilterState& x_start, const Vec9& Q,
                   const Mat9xS& G) {
    buildRows(n);
    P_out = P_pred;
    if (n.rows.W.rows() == 0) {
      x_out = n.x_pred;
      return;
    }
    const VecS dx_prior = boxminus(n.x_pred, x_start);
    x_out = boxplus(x_start, dopplerUpdate(n, Q, G, dx_prior, P_out, false));
  };
  FilterState x;
  MatS P;
  solve(x, P, n.x_pred, q_open_, G_open_);
  // Second gate, against the update: the first one, against the prediction, must be wide where
  // the prediction is uncertain (the first nodes) and lets slow moving objects through; the
  // points are gated again at regate_sigma of their residual's std after the update (no floor,
  // no share of the speed: at the update the model is exact for a static point), and the node
  // is solved again with the points that pass.
  OpenReturns& o = open_;
  if (params_.regate_sigma > 0 && o.used > 0) {
    Mat9xS G;
    const Vec9 q = velocityPolynomial(n, x, &G);
    const Eigen::Matrix<double, 3, kStateDim> G0 = G.topRows<3>();
    const Mat3 M = G0.lazyProduct(P).lazyProduct(G0.transpose());
    const double k2 = params_.regate_sigma * params_.regate_sigma;
    // Residual and its variance against the update; which of those the first gate accepted pass
    // their own gate.
    const std::size_t m = o.given;
    GatePrediction g;
    for (int i = 0; i < 9; ++i) g.q[i] = q(i);
    g.setCovariance(M);
    g.inv_h = n.inv_h;
    g.r_doppler = r_doppler_;
    regateReturns(m, g, k2, o.in.tau, o.in.x, o.in.y, o.in.z, o.in.doppler, o.inv_norm.data(),
                  o.accepted.data(), o.residual.data(), o.residual2.data(), o.variance2.data(),
                  o.passed.data());
    std::int64_t* pass = o.passed.data();
    // Coherence: the returns of an object moving slowly along the line of sight each pass the
    // gate, but neighbours in the scan (consecutive returns) share its residual's sign and size.
    // A point whose neighbourhood's mean residual is significantly non-zero is dropped (a static
    // world leaves white residuals against the update).
    const int K = params_.coherence_window;
    if (K > 1 && o.used >= static_cast<std::size_t>(K)) {
      // Those that passed, in order: their indices among the given ones and the prefix sums of
      // their residuals and variances, packed without branches (a return that did not pass adds
      // zero, and its slot is written again by the next one that does).
      std::uint32_t* idx = o.index.data();
      double* cum_r = o.cum_r.data();
      double* cum_v = o.cum_v.data();
      const double* r2 = o.residual2.data();
      const double* v2 = o.variance2.data();
      double run_r = 0, run_v = 0;
      cum_r[0] = cum_v[0] = 0.0;
      std::size_t np = 0;
      for (std::size_t i = 0; i < m; ++i) {
        const bool p = pass[i] != 0;
        run_r += p ? r2[i] : 0.0;
        run_v += p ? v2[i] : 0.0;
        idx[np] = static_cast<std::uint32_t>(i);
        np += p ? 1 : 0;
        cum_r[np] = run_r;
        cum_v[np] = run_v;
      }
      // The test reads the prefix sums only: a point's verdict does not change its neighbours'.
      // A neighbourhood is [j - half, j + half], cut at the ends, and tested if it holds K / 2
      // returns or more.
      const std::size_t half = static_cast<std::size_t>(K / 2);
      const double c2 = params_.coherence_sigma * params_.coherence_sigma;
      std::int64_t* coherent = o.coherent.data();
      coherenceTest(np, half, static_cast<std::size_t>(K) / 2, c2, cum_r, cum_v, coherent);
      auto dropsIt = [&](std::size_t j) { return coherent[j]; };
      forEachFlagged(np, dropsIt, [&](std::size_t j) { pass[idx[j]] = 0; });
    }
    // The dropped points leave the sums (a small share: taking them out is cheaper than summing
    // the kept ones again), in the order given, each as the first gate summed it.
    std::size_t dropped = 0;
    const std::int64_t* accepted = o.accepted.data();
    auto leaves = [&](std::size_t i) { return accepted[i] & ~pass[i]; };  // both 0 or 1
    forEachFlagged(m, leaves, [&](std::size_t i) {
      o.accepted[i] = 0;
      const double inv_norm = o.inv_norm[i];  // the first gate's, as it summed the return
      const Vec3 direction(o.in.x[i] * inv_norm, o.in.y[i] * inv_norm, o.in.z[i] * inv_norm);
      accumulate(n.sums, static_cast<double>(o.in.tau[i]) * n.inv_h, direction,
                 static_cast<double>(o.in.doppler[i]), -1.0);
      ++dropped;
    });
    o.used -= dropped;
    if (dropped > 0) {
      const FilterState x_first = x;
      solve(x, P, x_first, q, G);
    }
    // The kept returns' squared residuals against the update, from the sums (no pass over the
    // returns): what the Doppler noise is estimated from (forwardResiduals()).
    if (n.sums.n > 0) {
      double quad = 0, lin = 0;
      for (int j = 0; j < 3; ++j) {
        lin += n.sums.bz.col(j).dot(q.segment<3>(3 * j));
        for (int k = 0; k < 3; ++k)
          quad += q.segment<3>(3 * j).dot(n.sums.moment(j + k) * q.segment<3>(3 * k));
      }
      forward_rss_ += std::max(0.0, n.sums.c + 2.0 * lin + quad);
      forward_returns_ += n.sums.n;
    }
  }
  n.x = n.xs = x;
  n.P = P;
  node_open_ = false;
}

DopplerInertialFilter::VecS DopplerInertialFilter::restUpdate(const Node& n, const Vec3& gyro,
                                                              const FilterState& x_lin,
                                                              const VecS& dx, MatS& P,
                                                              bool full) const {
  if (!(n.rest_velocity_sigma > 0) && !(n.rest_rate_sigma > 0)) return dx;
  // Zero velocity: v_b = R^T v_w = 0, dv_b = R^T dv_w + [v_b]x dtheta. Zero rate: the gyro
  // sample measures the bias, gyro - b_g = 0 + n, d(.) = -db_g. Stacked and whitened, relative
  // to x_lin + dx (a part not used: zero rows, which change nothing).
  Eigen::Matrix<double, 6, kStateDim> H = Eigen::Matrix<double, 6, kStateDim>::Zero();
  Eigen::Matrix<double, 6, 1> r = Eigen::Matrix<double, 6, 1>::Zero();
  const FilterState x = boxplus(x_lin, dx);
  const Vec3 v_b = x.R_wb.transpose() * x.v_w;
  if (n.rest_velocity_sigma > 0) {
    const double w = 1.0 / n.rest_velocity_sigma;
    H.block<3, 3>(0, 0) = w * skew(v_b);
    H.block<3, 3>(0, 6) = w * x.R_wb.transpose();
    r.head<3>() = w * v_b;
  }
  if (n.rest_rate_sigma > 0) {
    const double w = std::sqrt(static_cast<double>(n.rest_samples)) / n.rest_rate_sigma;
    H.block<3, 3>(3, 9) = w * Mat3::Identity();
    r.tail<3>() = -w * (gyro - x.b_g);
  }
  // The step is relative to x_lin + dx: its own prior mean is zero, then it is added to dx.
  using HCore = Eigen::Matrix<double, 6, kCoreDim>;
  using HTime = Eigen::Matrix<double, 6, kTimeDim>;
  switch (full ? kStateDim : active_) {
    case kStateDim:
      return dx + kalmanUpdate<kStateDim, 6>(H, r, VecS::Zero(), P);
    case kTimeDim:
      return dx + kalmanUpdate<kTimeDim, 6>(HTime(H.leftCols<kTimeDim>()), r, VecS::Zero(), P);
    default:
      return dx + kalmanUpdate<kCoreDim, 6>(HCore(H.leftCols<kCoreDim>()), r, VecS::Zero(), P);
  }
}

void DopplerInertialFilter::updateRest(double velocity_sigma, double rate_sigma) {
  Node& n = nodes_.back();
  nodeChanged(nodes_.size() - 1);
  // The zero velocity holds at every sample the node stands for (those after the previous node
  // up to this one): as many measurements' information as a node per sample would have.
  const std::size_t span = n.k > n.k_prev ? n.k - n.k_prev : 1;
  n.rest_velocity_sigma = velocity_sigma / std::sqrt(static_cast<double>(span));
  // The gyro's measured samples after the previous node up to this one's: their mean measures
  // the bias (an interpolated sample, ImuScreen, measures no rate).
  auto measured = [&](std::size_t j) {
    return j >= imu_extra_var_.size() || imu_extra_var_[j](0) == 0.0f;
  };
  const std::size_t first = n.k > n.k_prev ? n.k_prev + 1 : n.k;
  std::size_t count = 0;
  Vec3 sum = Vec3::Zero();
  for (std::size_t j = first; j <= n.k; ++j)
    if (measured(j)) {
      sum += imu_[j].gyro;
      ++count;
    }
  n.rest_rate_sigma = count > 0 ? rate_sigma : 0.0;
  n.rest_samples = std::max<std::size_t>(count, 1);
  n.rest_gyro = count > 0 ? Vec3(sum / static_cast<double>(count)) : imu_[n.k].gyro;
  MatS P = n.P;
  const VecS dx = restUpdate(n, n.rest_gyro, n.x, VecS::Zero(), P);
  n.x = n.xs = boxplus(n.x, dx);
  n.P = P;
}

void DopplerInertialFilter::cancelRestFrom(double t, bool keep_rate) {
  for (std::size_t k = 0; k < nodes_.size(); ++k) {
    Node& n = nodes_[k];
    if (imu_[n.k].t < t) continue;
    if (n.rest_velocity_sigma > 0 || (n.rest_rate_sigma > 0 && !keep_rate)) nodeChanged(k);
    n.rest_velocity_sigma = 0;
    if (!keep_rate) n.rest_rate_sigma = 0;
  }
}

void DopplerInertialFilter::prepareSmoothing(std::size_t n) {
  constexpr std::size_t kMostPrepared = 1000;
  if (n <= kMostPrepared && smoother_P_f_.size() < n) {
    smoother_P_f_.assign(n, MatS::Zero());
    smoother_P_p_.assign(n, MatS::Zero());
    linearization_.assign(n, Linearization{});
    smoother_dx_f_.assign(n, VecS::Zero());
    smoother_dx_p_.assign(n, VecS::Zero());
    forward_kept_ = 0;
  }
}

void DopplerInertialFilter::linearize(std::size_t k, Linearization& L) const {
  const Node& n = nodes_[k];
  L.x = n.xs;
  if (n.rows.W.rows() > 0) {
    L.Q = velocityPolynomial(n, n.xs, &L.G);
  }
  if (k + 1 < nodes_.size()) L.x_next = propagate(n, n.xs, &L.F);
}

void DopplerInertialFilter::smootherForward(std::size_t first) {
  // A Kalman filter on the errors around the nominal trajectory xs. From node k to the next: the
  // predicted error and covariance.
  const std::size_t N = nodes_.size();
  std::vector<MatS>& P_f = smoother_P_f_;
  std::vector<MatS>& P_p = smoother_P_p_;
  std::vector<VecS>& dx_f = smoother_dx_f_;
  std::vector<VecS>& dx_p = smoother_dx_p_;
  std::vector<Linearization>& lin = linearization_;
  auto predictNext = [&](std::size_t k) {
    const Node &n = nodes_[k], &m = nodes_[k + 1];
    dx_p[k + 1] = lin[k].F.times(dx_f[k]) + boxminus(lin[k].x_next, m.xs);
    P_p[k + 1] = propagateCovariance(lin[k].F, P_f[k], n);
  };
  if (first == 0) {
    // The prior of node 0, expressed where node 0 now is (its yaw gauge about the current
    // vertical: held about the prior's, it would hold a part of the tilt too).
    dx_p[0] = priorMean(nodes_[0].xs);
    P_p[0] = priorCovariance(nodes_[0].xs);
  } else if (first < N) {
    // The transition after the nodes kept (their last one had none then).
    Linearization& L = lin[first - 1];
    L.x_next = propagate(nodes_[first - 1], nodes_[first - 1].xs, &L.F);
    predictNext(first - 1);
  }
  for (std::size_t k = first; k < N; ++k) {
    Node& n = nodes_[k];
    Linearization& L = lin[k];
    linearize(k, L);
    MatS P = P_p[k];
    dx_f[k] = restUpdate(n, n.rest_gyro, n.xs, dopplerUpdate(n, L.Q, L.G, dx_p[k], P, false), P);
    P_f[k] = P;
    if (k + 1 < N) predictNext(k);
  }
}

void DopplerInertialFilter::referOffsets() {
  // Each node's returns integrated with the smoothed offset where it moved away from their
  // reference by more than kOffsetRefStep (the model is linear in the offset about it, its
  // error growing with the distance squared); held through a smoothing's iterations (a
  // reference moved at each one changes the model under Gauss-Newton).
  for (std::size_t k = 0; k < nodes_.size(); ++k) {
    Node& n = nodes_[k];
    const bool moved = std::abs(n.xs.dt_l - n.dt_ref) > kOffsetRefStep;
    if (moved) n.dt_ref = n.xs.dt_l;
    // The lever-arm gyro's fit where it moved or was made before all its samples had arrived
    // (a negative offset reads samples after the next node's), with the rows it weighs.
    const bool refit = n.spansSamples() && (moved || !n.gyro_fit_complete);
    if (refit) {
      gyroFit(n, &n.gyro_fit, &n.gyro_fit_cov, &n.gyro_fit_complete);
      buildRows(n);
      n.rows_stale = false;
    }
    if (moved || refit) nodeChanged(k);
  }
}

int DopplerInertialFilter::smooth(double looseness, bool ahead) {
  const std::size_t N = nodes_.size();
  if (N == 0) return 0;
  for (Node& n : nodes_)
    if (n.rows_stale) {
      buildRows(n);
      n.rows_stale = false;
    }
  // After an earlier smoothing, the nodes the filter added since start from the propagation of
  // the last smoothed node, not from the filter's own states. The filter, going on from the
  // smoothed covariance, is free along the weakly observed direction (tilt with the accelerometer
  // bias and the world velocity: smoothed at 80 % of dyna_05, where the early smoothing ran when
  // this was measured, pitch widens from 1.2 to 10 mrad, the bias from 0.01 to 0.1 m/s^2), and
  // its one-step updates scatter the states along it; linearized there, the first Gauss-Newton
  // step overshot along that direction and the second took it back (1761, 1678, 43 tolerances).
  // From the propagation (no process defect): 248, 3.
  if (smoothed_ > 0)
    for (std::size_t k = smoothed_; k < N; ++k)
      nodes_[k].xs = propagate(nodes_[k - 1], nodes_[k - 1].xs, nullptr);
  const std::size_t smoothed_before = smoothed_;
  smoothed_ = N;
  referOffsets();
  // The forward pass an earlier smoothing made ahead, around the states it left, holds for the
  // first forward_kept_ nodes (their data unchanged since): this smoothing's first iteration
  // takes it as it is for them (after the early smoothing, three quarters of the final one's).
  const std::size_t kept = std::min(forward_kept_, smoothed_before);
  forward_kept_ = 0;
  std::vector<VecS> dxs(N);
  if (smoother_P_f_.size() < N) {  // the five grow together (prepareSmoothing)
    smoother_P_f_.resize(N);
    smoother_P_p_.resize(N);
    smoother_dx_f_.resize(N);
    smoother_dx_p_.resize(N);
    linearization_.resize(N);
  }
  std::vector<MatS>& P_f = smoother_P_f_;  // every element read below is written first
  std::vector<MatS>& P_p = smoother_P_p_;
  std::vector<VecS>& dx_f = smoother_dx_f_;
  std::vector<VecS>& dx_p = smoother_dx_p_;
  std::vector<Linearization>& lin = linearization_;
  linearized_ = 0;
  int iterations = 0;
  double previous_step = 0;  // none yet: no evidence of the convergence rate
  for (int it = 0; it < params_.max_iterations; ++it) {
    ++iterations;
    smootherForward(it == 0 ? kept : 0);
    // Backward: Rauch-Tung-Striebel, dxs_k = dx_f_k + P_f_k F_k^T P_p_k+1^-1 (dxs_k+1 - dx_p_k+1),
    // evaluated right to left (one solve with a vector; the smoothed covariances are not needed).
    nodes_[N - 1].P = P_f[N - 1];
    dxs[N - 1] = dx_f[N - 1];
    for (std::size_t k = N - 1; k-- > 0;) {
      // y = P_p^-1 (dxs - dx_p), by Cholesky: with the calibration constant, its part of y is
      // zero and its step dx_f's.
      VecS y = dxs[k + 1] - dx_p[k + 1];
      switch (active_) {
        case kStateDim:
          detail::choleskySolveKernel<kStateDim>(P_p[k + 1].data(), y.data());
          break;
        case kTimeDim:
          detail::choleskySolveKernel<kTimeDim>(P_p[k + 1].data(), y.data());
          y.tail<kStateDim - kTimeDim>().setZero();
          break;
        default:
          detail::choleskySolveKernel<kCoreDim>(P_p[k + 1].data(), y.data());
          y.tail<kStateDim - kCoreDim>().setZero();
      }
      const VecS Fty = lin[k].F.transposeTimes(y);
      dxs[k] = dx_f[k];
      switch (active_) {
        case kStateDim:
          dxs[k] += P_f[k] * Fty;
          break;
        case kTimeDim:
          dxs[k].head<kTimeDim>() +=
              P_f[k].topLeftCorner<kTimeDim, kTimeDim>() * Fty.head<kTimeDim>();
          break;
        default:
          dxs[k].head<kCoreDim>() +=
              P_f[k].topLeftCorner<kCoreDim, kCoreDim>() * Fty.head<kCoreDim>();
      }
      nodes_[k].P = P_f[k];
    }
    // Converged when no node moves by more than the tolerance of its block (scaled), or when the
    // steps shrink as Gauss-Newton's do near the solution (tenfold or more per iteration) and
    // the next one, at the rate of the last two, would be below one tolerance. The last node's
    // estimate is this iteration's (its smoothed and filtered states agree); its covariance was
    // linearized one step away, at most a tenth of the previous one.
    double step = 0;
    for (std::size_t k = 0; k < N; ++k) {
      nodes_[k].xs = boxplus(nodes_[k].xs, dxs[k]);
      step = std::max(step, stepInTolerances(dxs[k]));
    }
    const double c = params_.convergence * looseness;
    if (step < c || (step < 0.1 * previous_step && step * (step / previous_step) < c)) {
      linearized_ = N;
      break;
    }
    previous_step = step;
  }
  if (ahead) {
    // Around the references the next smoothing will start from.
    referOffsets();
    smootherForward(0);
    forward_kept_ = N;
  }
  // The filter can go on from the last node (an early smoothing while the window is received).
  nodes_.back().x = nodes_.back().xs;
  return iterations;
}

DopplerInertialFilter::CalibrationTest DopplerInertialFilter::testCalibration(
    double rotation_sigma, double time_sigma) const {
  // One forward pass of the linear filter around the converged trajectory, the calibration's
  // prior widened: its estimate at the last node is what the data say of it. The start's body
  // velocity prior is left out (scaled up a million times in variance): the start decision
  // measured it with the returns and the declared calibration, so it would vouch for that
  // calibration (a LiDAR-IMU rotation error turns the velocity the returns give: with the prior
  // in, a 1 deg error while driving read as a 0.03 deg sigma).
  CalibrationTest out;
  const std::size_t N = nodes_.size();
  if (N == 0) return out;
  for (const Node& n : nodes_)
    if (n.rows_stale)
      throw std::logic_error("DopplerInertialFilter::testCalibration: removePoint without smooth");
  std::vector<Linearization> fresh;
  const Linearization* lin = linearization_.data();
  if (linearized_ != N) {
    fresh.resize(N);
    for (std::size_t k = 0; k < N; ++k) linearize(k, fresh[k]);
    lin = fresh.data();
  }
  VecS dx;
  MatS P;
  const KeptCalibrationPass& kept = test_kept_;
  if (kept.nodes > 0 && kept.nodes <= N && kept.rotation_sigma == rotation_sigma &&
      kept.time_sigma == time_sigma) {
    // On from the kept pass's last node: its transition to the first node added since, at the
    // point that pass linearized it.
    dx = kept.dx;
    P = kept.P;
    if (kept.nodes < N) {
      const Node& n = nodes_[kept.nodes - 1];
      IntegrationJacobian F;
      const FilterState x_next = propagate(n, kept.x, &F);
      dx = F.times(dx) + boxminus(x_next, lin[kept.nodes].x);
      P = propagateCovariance(F, P, n, true);
      calibrationPass(lin, kept.nodes, N, dx, P);
    }
  } else {
    calibrationPrior(lin[0].x, rotation_sigma, time_sigma, dx, P);
    calibrationPass(lin, 0, N, dx, P);
  }
  out.correction = dx;
  out.covariance = P;
  Eigen::Matrix<double, 4, 1> c;
  c << dx.segment<3>(kRot), dx(kTime);
  Eigen::Matrix4d Pc;
  Pc.topLeftCorner<3, 3>() = P.block<3, 3>(kRot, kRot);
  Pc.topRightCorner<3, 1>() = P.block<3, 1>(kRot, kTime);
  Pc.bottomLeftCorner<1, 3>() = P.block<1, 3>(kTime, kRot);
  Pc(3, 3) = P(kTime, kTime);
  out.mahalanobis2 = c.dot(Pc.ldlt().solve(c));
  out.ok = std::isfinite(out.mahalanobis2);
  return out;
}

void DopplerInertialFilter::testCalibrationAhead(double rotation_sigma, double time_sigma) {
  const std::size_t N = nodes_.size();
  test_kept_.nodes = 0;
  if (N == 0 || forward_kept_ != N) return;  // no pass made ahead to go along with
  KeptCalibrationPass& kept = test_kept_;
  calibrationPrior(linearization_[0].x, rotation_sigma, time_sigma, kept.dx, kept.P);
  calibrationPass(linearization_.data(), 0, N, kept.dx, kept.P);
  kept.rotation_sigma = rotation_sigma;
  kept.time_sigma = time_sigma;
  kept.x = linearization_[N - 1].x;
  kept.nodes = N;
}

void DopplerInertialFilter::calibrationPrior(const FilterState& x0, double rotation_sigma,
                                             double time_sigma, VecS& dx, MatS& P) const {
  constexpr double kUninformedVelocity = 1e6;
  P = priorCovariance(x0, kUninformedVelocity);
  P.block<3, 3>(kRot, kRot).diagonal().setConstant(rotation_sigma * rotation_sigma);
  P(kTime, kTime) = time_sigma * time_sigma;
  dx = priorMean(x0);
}

void DopplerInertialFilter::calibrationPass(const Linearization* lin, std::size_t from,
                                            std::size_t to, VecS& dx, MatS& P) const {
  for (std::size_t k = from; k < to; ++k) {
    const Node& n = nodes_[k];
    const Linearization& L = lin[k];
    dx = restUpdate(n, n.rest_gyro, L.x, dopplerUpdate(n, L.Q, L.G, dx, P, true), P, true);
    if (k + 1 == to) break;
    dx = L.F.times(dx) + boxminus(L.x_next, lin[k + 1].x);
    P = propagateCovariance(L.F, P, n, true);
  }
}

std::vector<DopplerInertialFilter::Vec9> DopplerInertialFilter::lidarVelocityPolynomials() const {
  std::vector<Vec9> Q;
  Q.reserve(nodes_.size());
  for (std::size_t k = 0; k < nodes_.size(); ++k) Q.push_back(lidarVelocityPolynomial(k));
  return Q;
}

void DopplerInertialFilter::checkPolynomials(const std::vector<Vec9>& Q) const {
  if (Q.size() != nodes_.size())
    throw std::invalid_argument("DopplerInertialFilter: " + std::to_string(Q.size()) +
                                " velocity polynomials for " + std::to_string(nodes_.size()) +
                                " nodes");
}

double DopplerInertialFilter::residualSumOfSquares(const std::vector<Vec9>& Qs) const {
  checkPolynomials(Qs);
  double rss = 0;
  for (std::size_t i = 0; i < nodes_.size(); ++i) rss += nodeResidualSumOfSquares(i, Qs[i]);
  return std::max(0.0, rss);
}

double DopplerInertialFilter::nodeResidualSumOfSquares(std::size_t k, const Vec9& Q) const {
  const Node& n = nodes_[k];
  if (n.sums.n == 0) return 0.0;
  double quad = 0, lin = 0;
  for (int m = 0; m < 3; ++m) {
    lin += n.sums.bz.col(m).dot(Q.segment<3>(3 * m));
    for (int i = 0; i < 3; ++i)
      quad += Q.segment<3>(3 * m).dot(n.sums.moment(m + i) * Q.segment<3>(3 * i));
  }
  return n.sums.c + 2.0 * lin + quad;
}

std::size_t DopplerInertialFilter::acceptedPointsTotal() const {
  std::size_t total = 0;
  for (const Node& n : nodes_) total += n.sums.n;
  return total;
}

DopplerInertialFilter::NodeResiduals DopplerInertialFilter::nodeResiduals(
    std::size_t min_returns, const std::vector<Vec9>& Qs) const {
  checkPolynomials(Qs);
  NodeResiduals out;
  const double var_g = params_.gyro_sigma * params_.gyro_sigma;
  for (std::size_t k = 0; k < nodes_.size(); ++k) {
    const Node& n = nodes_[k];
    if (n.sums.n == 0 || n.sums.n < min_returns) continue;
    if (n.rest_velocity_sigma > 0 || n.rest_rate_sigma > 0) continue;
    // sum r d = sum z d + sum d d^T q(s), r = z + d^T q(s): from the sums.
    const Vec9& Q = Qs[k];
    Vec3 g = n.sums.bz.col(0);
    for (int m = 0; m < 3; ++m) g += n.sums.moment(m) * Q.segment<3>(3 * m);
    const Mat3 S = n.sums.moment(0);
    Mat3 cov = r_doppler_ * S;
    if (lever_ratio_ > 0) {  // g moves by [S0 S1 S2] E n with the gyro noise n
      Eigen::Matrix<double, 3, 9> G;
      for (int m = 0; m < 3; ++m) G.middleCols<3>(3 * m) = n.sums.moment(m);
      if (n.spansSamples()) {
        const Eigen::Matrix<double, 3, 9> GC = G.lazyProduct(leverCovariance(n));
        cov += var_g * GC.lazyProduct(G.transpose());
      } else {
        const Eigen::Matrix<double, 3, kLeverDim> GE = G.lazyProduct(leverNoise(n));
        cov += var_g * GE.lazyProduct(GE.transpose());
      }
    }
    const Eigen::LDLT<Mat3> ldlt(cov);
    if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0)) continue;
    out.chi2 += g.dot(ldlt.solve(g));
    out.dof += 3;
  }
  return out;
}

}  // namespace freeinit
