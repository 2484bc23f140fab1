// Accelerometer bias and gravity (paper Sec. III-C), two formulations of the same kinematics:
// the paper's differentiated form, Eq. (acc_bias_gravity_opt), and its integrated form.
#include "paper/gravity_estimator.h"

#include <ceres/ceres.h>
#include <ceres/sphere_manifold.h>
#include <freeinit/rotation.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "paper/affine_residual.h"

namespace freeinit {
namespace {

using Mat6 = Eigen::Matrix<double, 6, 6>;
constexpr double kPi = 3.14159265358979323846;

/// Square-root information L (L^T L = cov^-1) of a 3x3 covariance; tolerant of tiny asymmetry and
/// semi-definite input (a small jitter is added).
Mat3 sqrtInformation(const Mat3& cov) {
  Mat3 c = 0.5 * (cov + cov.transpose());
  const double jitter = 1e-12 + 1e-9 * std::max(c.trace(), 0.0);
  c.diagonal().array() += jitter;
  const Eigen::LLT<Mat3> llt(c);
  if (llt.info() != Eigen::Success) {
    Mat3 d = Mat3::Zero();
    for (int i = 0; i < 3; ++i) d(i, i) = 1.0 / std::sqrt(std::max(std::abs(c(i, i)), 1e-12));
    return d;
  }
  return llt.matrixL().solve(Mat3::Identity());
}

// ---------------------------------------------------------------------------------------------
// Integrated velocity residual (default formulation).
//
// Kinematics of the body origin in the window's world frame w (the first body frame):
//   d/dt v_w = a_w = R_wb (accel - b_a - n_a) + g_w.
// Integrating from the window start t_0 to t_k:
//   v_w(t_k) = v0_w + int_{t0}^{tk} R_wb accel dt - (int_{t0}^{tk} R_wb dt) b_a + g_w (t_k - t_0),
// with v0_w = v_w(t_0) a free unknown. The integrals are evaluated with the trapezoidal rule on the
// IMU samples: S_k = int R_wb accel, M_k = int R_wb. The measured velocity y_k is either
//   body:  y_k = R_wb,k v_b,k
//   LiDAR: y_k = R_wb,k R_bl v_l,k - R_wb,k (omega_k x p_bl),
// the latter because v_lw = R_wb (v_b + omega x p_bl) and d/dt(R_wb (omega x p_bl)) =
// R_wb (omega x (omega x p_bl) + alpha x p_bl): the lever-arm terms of the paper's LiDAR equation
// integrate in closed form, and both equations share the same start velocity v0_w. Residual:
//   e_k = y_k - S_k + M_k b_a - g_w (t_k - t_0) - v0_w + D_k db_g.
//
// Gyro bias. R_wb was integrated with a gyro bias that is off by db (unknown); to first order
// R_wb,true(t) = Exp(-M(t) db) R_wb(t), since the attitude error grows as d(phi)/dt = R_wb db in w
// and M(t) = int R_wb dt is the same integral as above. Then y_k and S_k change linearly:
//   y_k -> y_k + [y_k]x M_k db,   S_k -> S_k + int [R_wb accel]x M db dt,
// so D_k = [y_k]x M_k - int [R_wb accel]x M dt (the b_a M term is second order). db has a prior
// from the velocimeter; rotation about different axes makes it observable.
//
// e_k is affine in the unknowns; after whitening in time (addWhitenedResiduals) each residual is
//   r_k = L_k (c_k + G_g g_w + G_ba b_a + G_v0 v0_w + G_db db_g),
// an AffineResidual3x4 with exact Jacobians L_k G_*.
// ---------------------------------------------------------------------------------------------

// ---------------------------------------------------------------------------------------------
// Differentiated body residual, first term of Eq. (acc_bias_gravity_opt):
//   a_w,k = R_wb,k (accel_k - b_a) + g_w
// with a_w,k the numerical derivative of the low-pass filtered world velocity R_wb v_b and accel_k
// the equally filtered accelerometer sample. Residual, in w:
//   r_k = L_k [ a_w,k - R_wb,k (accel_k - b_a) - g_w ].
// ---------------------------------------------------------------------------------------------
struct BodyAccelerationResidual {
  BodyAccelerationResidual(const Vec3& a_w, const Mat3& R_wb, const Vec3& accel_b,
                           const Mat3& sqrt_info)
      : a_w_(a_w), R_wb_(R_wb), accel_b_(accel_b), sqrt_info_(sqrt_info) {}

  template <typename T>
  bool operator()(const T* const g_w_ptr, const T* const b_a_ptr, T* residual_ptr) const {
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> g_w(g_w_ptr);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> b_a(b_a_ptr);
    const Eigen::Matrix<T, 3, 1> e =
        a_w_.cast<T>() - R_wb_.cast<T>() * (accel_b_.cast<T>() - b_a) - g_w;
    Eigen::Map<Eigen::Matrix<T, 3, 1>> residual(residual_ptr);
    residual = sqrt_info_.cast<T>() * e;
    return true;
  }

  static ceres::CostFunction* Create(const Vec3& a_w, const Mat3& R_wb, const Vec3& accel_b,
                                     const Mat3& sqrt_info) {
    return new ceres::AutoDiffCostFunction<BodyAccelerationResidual, 3, 3, 3>(
        new BodyAccelerationResidual(a_w, R_wb, accel_b, sqrt_info));
  }

  Vec3 a_w_;
  Mat3 R_wb_;
  Vec3 accel_b_;
  Mat3 sqrt_info_;
};

// ---------------------------------------------------------------------------------------------
// Differentiated LiDAR residual, second term of Eq. (acc_bias_gravity_opt), in the body frame:
//   R_bl a_l,k = (accel_k - b_a) + R_wb,k^T g_w + [omega_k]x^2 p_bl + [alpha_k]x p_bl,
// where R_bl a_l,k = R_wb,k^T a_lw,k and a_lw,k is the numerical derivative of the low-pass
// filtered LiDAR velocity in w (R_wb R_bl v_l); omega_k is the filtered angular velocity and
// alpha_k its numerical derivative. The lever-arm terms do not depend on the unknowns and are
// folded into the constant c_b,k = R_bl a_l,k - [omega_k]x^2 p_bl - [alpha_k]x p_bl. Residual:
//   r_k = L_k [ c_b,k - (accel_k - b_a) - R_wb,k^T g_w ].
// ---------------------------------------------------------------------------------------------
struct LidarAccelerationResidual {
  LidarAccelerationResidual(const Vec3& c_b, const Mat3& R_wb, const Vec3& accel_b,
                            const Mat3& sqrt_info)
      : c_b_(c_b), R_wb_(R_wb), accel_b_(accel_b), sqrt_info_(sqrt_info) {}

  template <typename T>
  bool operator()(const T* const g_w_ptr, const T* const b_a_ptr, T* residual_ptr) const {
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> g_w(g_w_ptr);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> b_a(b_a_ptr);
    const Eigen::Matrix<T, 3, 1> e =
        c_b_.cast<T>() - (accel_b_.cast<T>() - b_a) - R_wb_.transpose().cast<T>() * g_w;
    Eigen::Map<Eigen::Matrix<T, 3, 1>> residual(residual_ptr);
    residual = sqrt_info_.cast<T>() * e;
    return true;
  }

  static ceres::CostFunction* Create(const Vec3& c_b, const Mat3& R_wb, const Vec3& accel_b,
                                     const Mat3& sqrt_info) {
    return new ceres::AutoDiffCostFunction<LidarAccelerationResidual, 3, 3, 3>(
        new LidarAccelerationResidual(c_b, R_wb, accel_b, sqrt_info));
  }

  Vec3 c_b_;
  Mat3 R_wb_;
  Vec3 accel_b_;
  Mat3 sqrt_info_;
};

// ---------------------------------------------------------------------------------------------
// Weak zero-mean prior on the accelerometer bias, b_a ~ N(0, sigma^2 I): r = b_a / sigma.
// It keeps b_a defined where the motion does not observe it (e.g. its horizontal part at rest).
// ---------------------------------------------------------------------------------------------
struct AccelBiasPrior {
  explicit AccelBiasPrior(double sigma) : inv_sigma_(1.0 / sigma) {}

  template <typename T>
  bool operator()(const T* const b_a_ptr, T* residual_ptr) const {
    for (int i = 0; i < 3; ++i) residual_ptr[i] = b_a_ptr[i] * T(inv_sigma_);
    return true;
  }

  static ceres::CostFunction* Create(double sigma) {
    return new ceres::AutoDiffCostFunction<AccelBiasPrior, 3, 3>(new AccelBiasPrior(sigma));
  }

  double inv_sigma_;
};

// ---------------------------------------------------------------------------------------------
// Prior on the gyro-bias correction, db ~ N(0, C): r = L db with L^T L = C^-1.
// ---------------------------------------------------------------------------------------------
struct GyroBiasPrior {
  explicit GyroBiasPrior(const Mat3& sqrt_info) : sqrt_info_(sqrt_info) {}

  template <typename T>
  bool operator()(const T* const db_ptr, T* residual_ptr) const {
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> db(db_ptr);
    Eigen::Map<Eigen::Matrix<T, 3, 1>> residual(residual_ptr);
    residual = sqrt_info_.cast<T>() * db;
    return true;
  }

  static ceres::CostFunction* Create(const Mat3& sqrt_info) {
    return new ceres::AutoDiffCostFunction<GyroBiasPrior, 3, 3>(new GyroBiasPrior(sqrt_info));
  }

  Mat3 sqrt_info_;
};

/// Second-order Butterworth low-pass (bilinear transform, prewarped), applied forward and backward
/// (zero phase) with an odd extension at both ends so that linear trends pass without transients.
class ZeroPhaseLowPass {
 public:
  ZeroPhaseLowPass(double cutoff_hz, double sample_rate_hz) {
    const double k = std::tan(kPi * cutoff_hz / sample_rate_hz);
    const double norm = 1.0 / (1.0 + std::sqrt(2.0) * k + k * k);
    b0_ = k * k * norm;
    b1_ = 2.0 * b0_;
    b2_ = b0_;
    a1_ = 2.0 * (k * k - 1.0) * norm;
    a2_ = (1.0 - std::sqrt(2.0) * k + k * k) * norm;
    pad_ = static_cast<int>(std::ceil(2.0 * sample_rate_hz / cutoff_hz));
  }

  std::vector<Vec3> apply(const std::vector<Vec3>& x) const {
    const int n = static_cast<int>(x.size());
    const int pad = std::max(0, std::min(pad_, n - 1));
    std::vector<Vec3> ext;
    ext.reserve(static_cast<std::size_t>(n + 2 * pad));
    for (int i = pad; i >= 1; --i) ext.push_back(2.0 * x.front() - x[static_cast<std::size_t>(i)]);
    ext.insert(ext.end(), x.begin(), x.end());
    for (int i = 1; i <= pad; ++i)
      ext.push_back(2.0 * x.back() - x[static_cast<std::size_t>(n - 1 - i)]);
    pass(ext);
    std::reverse(ext.begin(), ext.end());
    pass(ext);
    std::reverse(ext.begin(), ext.end());
    return std::vector<Vec3>(ext.begin() + pad, ext.begin() + pad + n);
  }

  /// Power gain |H(f)|^4 of the forward-backward filter at frequency f [Hz] (analog prototype).
  static double powerGain(double f, double cutoff_hz) {
    const double r4 = std::pow(f / cutoff_hz, 4);
    return 1.0 / ((1.0 + r4) * (1.0 + r4));
  }

 private:
  void pass(std::vector<Vec3>& s) const {
    // Steady-state start at the first value (unit DC gain).
    Vec3 x1 = s.front(), x2 = s.front(), y1 = s.front(), y2 = s.front();
    for (Vec3& v : s) {
      const Vec3 y = b0_ * v + b1_ * x1 + b2_ * x2 - a1_ * y1 - a2_ * y2;
      x2 = x1;
      x1 = v;
      y2 = y1;
      y1 = y;
      v = y;
    }
  }

  double b0_ = 1, b1_ = 0, b2_ = 0, a1_ = 0, a2_ = 0;
  int pad_ = 0;
};

/// Central differences on a possibly non-uniform grid; one-sided at both ends.
std::vector<Vec3> differentiate(const std::vector<double>& t, const std::vector<Vec3>& x) {
  const std::size_t n = x.size();
  std::vector<Vec3> d(n, Vec3::Zero());
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t lo = k == 0 ? 0 : k - 1;
    const std::size_t hi = k + 1 == n ? n - 1 : k + 1;
    d[k] = (x[hi] - x[lo]) / (t[hi] - t[lo]);
  }
  return d;
}

/// Variance factors of the differentiated formulation for white input noise of unit variance per
/// sample: {derivative of the filtered signal [1/s^2], filtered signal [-]}. Evaluated by
/// integrating the spectra of the (central difference x zero-phase filter) up to Nyquist.
std::pair<double, double> filteredNoiseGains(double dt, double cutoff_hz) {
  const double fs = 1.0 / dt;
  const int steps = 400;
  const double df = 0.5 * fs / steps;
  double deriv = 0, value = 0;
  for (int i = 0; i < steps; ++i) {
    const double f = (i + 0.5) * df;
    const double h = cutoff_hz > 0 ? ZeroPhaseLowPass::powerGain(f, cutoff_hz) : 1.0;
    const double d = std::sin(2.0 * kPi * f * dt) / dt;  // central difference response
    deriv += d * d * h * df;
    value += h * df;
  }
  // A white sequence of unit variance has a one-sided PSD of 2/fs over [0, fs/2].
  return {deriv * 2.0 / fs, value * 2.0 / fs};
}

/// Adds the integrated residuals e_k = a_k + B_k x (x = [g_w; b_a; v0_w; db_g]), whitened in time.
///
/// Noise model: e_k's error is u_k + s_k with u_k the velocimeter's velocity error (covariance C_k,
/// first-order Gauss-Markov with coefficient phi between samples; phi = 0: white) and s_k the
/// accelerometer noise integrated since the window start (a random walk, var_acc_rate per second).
/// Residuals relative to the window start are therefore correlated; a Kalman filter over the noise
/// state [u; s] turns them into innovations, which are white, so least squares on the whitened
/// innovations is the exact generalized least squares of this model. The filter gains depend on
/// the covariances only, so the innovations are affine in x: the filter is run on a_k and on each
/// column of B_k.
void addWhitenedResiduals(const std::vector<Vec3>& a,
                          const std::vector<Eigen::Matrix<double, 3, 12>>& B,
                          const std::vector<Mat3>& C, const std::vector<KinematicSample>& samples,
                          double phi, double var_acc_rate, double weight, ceres::LossFunction* loss,
                          double* g_w, double* b_a, double* v0_w, double* db_g,
                          ceres::Problem& problem) {
  using Mat36 = Eigen::Matrix<double, 3, 6>;
  using Cols = Eigen::Matrix<double, 6, 13>;  // state estimate of the noise for a and B's columns
  const std::size_t n = a.size();
  Mat36 H;
  H << Mat3::Identity(), Mat3::Identity();
  Mat6 P = Mat6::Zero();
  P.topLeftCorner<3, 3>() = C[0];
  Cols x = Cols::Zero();
  for (std::size_t k = 0; k < n; ++k) {
    if (k > 0) {
      const double dt = samples[k].t - samples[k - 1].t;
      Mat6 F = Mat6::Identity();
      F.topLeftCorner<3, 3>() *= phi;
      Mat6 Q = Mat6::Zero();
      Q.topLeftCorner<3, 3>() = (1.0 - phi * phi) * C[k];
      Q.bottomRightCorner<3, 3>() = var_acc_rate * dt * Mat3::Identity();
      P = F * P * F.transpose() + Q;
      x = F * x;
    }
    Eigen::Matrix<double, 3, 13> z;
    z << a[k], B[k];
    const Eigen::Matrix<double, 3, 13> nu = z - H * x;
    const Mat3 S = H * P * H.transpose();
    const Eigen::Matrix<double, 6, 3> K = P * H.transpose() * S.inverse();
    x += K * nu;
    P = ((Mat6::Identity() - K * H) * P).eval();
    P = 0.5 * (P + P.transpose()).eval();
    const Mat3 L = weight * sqrtInformation(S);
    problem.AddResidualBlock(
        new AffineResidual3x4(L * nu.col(0), L * nu.middleCols<3>(1), L * nu.middleCols<3>(4),
                              L * nu.middleCols<3>(7), L * nu.middleCols<3>(10)),
        loss, g_w, b_a, v0_w, db_g);
  }
}

}  // namespace

GravityParams gravityParams(const FreeInitConfig& config) {
  const PaperGravityParams& g = config.paper_gravity;
  GravityParams p;
  p.formulation = g.formulation;
  p.use_body_equation = g.use_body_equation;
  p.use_lidar_equation = g.use_lidar_equation;
  p.accel_sigma = config.imu.accel_sigma;
  p.accel_bias_bound = config.imu.accel_bias_bound;
  p.accel_bias_prior_sigma = config.imu.accel_bias_prior_sigma;
  p.lowpass_cutoff_hz = g.lowpass_cutoff_hz;
  p.velocity_error_correlation_time = g.velocity_error_correlation_time;
  p.equations_share_errors = g.equations_share_errors;
  p.loss_scale = g.loss_scale;
  p.max_iterations = g.max_iterations;
  p.estimate_gyro_bias = g.estimate_gyro_bias;
  return p;
}

GravityEstimate GravityEstimator::estimate(const std::vector<KinematicSample>& samples,
                                           const Extrinsics& extrinsics, const Mat3& gyro_bias_cov,
                                           const GravityEstimate* start) const {
  const GravityParams& P = params_;
  if (!P.use_body_equation && !P.use_lidar_equation)
    throw std::invalid_argument(
        "GravityEstimator: use_body_equation and use_lidar_equation are both false");
  if (!(P.accel_bias_bound > 0) || !(P.accel_bias_prior_sigma > 0) || !(P.accel_sigma > 0) ||
      !(P.loss_scale > 0) || P.max_iterations < 1 || !(P.velocity_error_correlation_time >= 0))
    throw std::invalid_argument(
        "GravityEstimator: accel_bias_bound, accel_bias_prior_sigma, accel_sigma, loss_scale "
        "must be > 0, velocity_error_correlation_time >= 0 and max_iterations >= 1");

  GravityEstimate out;
  const std::size_t n = samples.size();
  if (n < 10) {
    out.message = "not enough samples for the gravity/accelerometer-bias solve (" +
                  std::to_string(n) + " < 10)";
    return out;
  }
  for (std::size_t k = 1; k < n; ++k) {
    if (!(samples[k].t > samples[k - 1].t)) {
      out.message = "kinematic samples are not strictly increasing in time";
      return out;
    }
  }
  const double duration = samples.back().t - samples.front().t;
  const double dt_mean = duration / static_cast<double>(n - 1);
  const Mat3& R_bl = extrinsics.R_bl;
  const Vec3& p_bl = extrinsics.p_bl;

  // Unknowns. Gravity starts from the mean rotated specific force (exact at rest, a few degrees
  // off in motion), on the sphere of radius 9.81.
  Vec3 mean_f_w = Vec3::Zero();
  for (const KinematicSample& s : samples) mean_f_w += s.R_wb * s.accel;
  mean_f_w /= static_cast<double>(n);
  Vec3 g_init =
      mean_f_w.norm() > 1e-6 ? Vec3(-mean_f_w.normalized() * kGravity) : Vec3(0, 0, -kGravity);
  Vec3 b_a_init = Vec3::Zero();
  if (start != nullptr && start->ok && start->g_w.allFinite() && start->b_a.allFinite() &&
      start->b_a.cwiseAbs().maxCoeff() <= P.accel_bias_bound) {
    g_init = start->g_w.normalized() * kGravity;
    b_a_init = start->b_a;
  }
  double g_w[3] = {g_init.x(), g_init.y(), g_init.z()};
  double b_a[3] = {b_a_init.x(), b_a_init.y(), b_a_init.z()};
  double v0_w[3] = {0, 0, 0};
  double db_g[3] = {0, 0, 0};
  const bool estimate_db = P.formulation == Formulation::Integrated && P.estimate_gyro_bias &&
                           gyro_bias_cov.allFinite() &&
                           Eigen::LLT<Mat3>(gyro_bias_cov).info() == Eigen::Success &&
                           gyro_bias_cov.trace() > 0;

  ceres::Problem problem;  // owns the cost functions, the loss and the manifold
  // One loss object shared by the residual blocks of this problem only (Ceres deletes it once).
  ceres::LossFunction* loss = new ceres::CauchyLoss(P.loss_scale);
  const double t0 = samples.front().t;

  if (P.formulation == Formulation::Integrated) {
    const Vec3 v_start = samples.front().R_wb * samples.front().v_b;
    v0_w[0] = v_start.x();
    v0_w[1] = v_start.y();
    v0_w[2] = v_start.z();
    const double tau = P.velocity_error_correlation_time;
    const double phi = tau > 0 ? std::exp(-dt_mean / tau) : 0.0;
    const double var_acc_rate = P.accel_sigma * P.accel_sigma * dt_mean;  // [(m/s)^2 / s]
    // Both equations see the same accelerometer noise and velocity errors from the same points:
    // each gets half the information so that together they count it once.
    const int n_eq = (P.use_body_equation ? 1 : 0) + (P.use_lidar_equation ? 1 : 0);
    const double eq_weight =
        P.equations_share_errors ? 1.0 / std::sqrt(static_cast<double>(n_eq)) : 1.0;
    std::vector<Vec3> a(n);
    std::vector<Eigen::Matrix<double, 3, 12>> B(n);
    std::vector<Mat3> C(n);
    for (int eq = 0; eq < 2; ++eq) {
      if ((eq == 0 && !P.use_body_equation) || (eq == 1 && !P.use_lidar_equation)) continue;
      Vec3 S_w = Vec3::Zero();  // trapezoidal integral of R_wb accel
      Mat3 M_w = Mat3::Zero();  // trapezoidal integral of R_wb
      Mat3 N_w = Mat3::Zero();  // trapezoidal integral of [R_wb accel]x M
      for (std::size_t k = 0; k < n; ++k) {
        const KinematicSample& s = samples[k];
        if (k > 0) {
          const KinematicSample& sp = samples[k - 1];
          const double dt = s.t - sp.t;
          const Mat3 M_prev = M_w;
          S_w += 0.5 * dt * (sp.R_wb * sp.accel + s.R_wb * s.accel);
          M_w += 0.5 * dt * (sp.R_wb + s.R_wb);
          N_w += 0.5 * dt *
                 (skew(Vec3(sp.R_wb * sp.accel)) * M_prev + skew(Vec3(s.R_wb * s.accel)) * M_w);
        }
        Vec3 y;
        if (eq == 0) {
          y = s.R_wb * s.v_b;
          C[k] = s.R_wb * s.cov_v_b * s.R_wb.transpose();
        } else {
          const Mat3 R_wl = s.R_wb * R_bl;
          y = R_wl * s.v_l - s.R_wb * s.omega_b.cross(p_bl);
          C[k] = R_wl * s.cov_v_l * R_wl.transpose();
        }
        // e_k = a_k + B_k [g_w; b_a; v0_w; db_g]
        a[k] = y - S_w;
        B[k] << -(s.t - t0) * Mat3::Identity(), M_w, -Mat3::Identity(), skew(y) * M_w - N_w;
      }
      addWhitenedResiduals(a, B, C, samples, phi, var_acc_rate, eq_weight, loss, g_w, b_a, v0_w,
                           db_g, problem);
    }
  } else {
    // Differentiated (paper) form: filter, then central differences.
    std::vector<double> t(n);
    std::vector<Vec3> v_w(n), v_lw(n), omega_b(n), accel_b(n);
    for (std::size_t k = 0; k < n; ++k) {
      const KinematicSample& s = samples[k];
      t[k] = s.t;
      v_w[k] = s.R_wb * s.v_b;
      v_lw[k] = s.R_wb * R_bl * s.v_l;
      omega_b[k] = s.omega_b;
      accel_b[k] = s.accel;
    }
    const double fs = 1.0 / dt_mean;
    const bool filter = P.lowpass_cutoff_hz > 0 && P.lowpass_cutoff_hz < 0.45 * fs;
    if (filter) {
      const ZeroPhaseLowPass lpf(P.lowpass_cutoff_hz, fs);
      v_w = lpf.apply(v_w);
      v_lw = lpf.apply(v_lw);
      omega_b = lpf.apply(omega_b);
      accel_b = lpf.apply(accel_b);
    }
    const std::vector<Vec3> a_w = differentiate(t, v_w);
    const std::vector<Vec3> a_lw = differentiate(t, v_lw);
    const std::vector<Vec3> alpha_b = differentiate(t, omega_b);
    const auto gains = filteredNoiseGains(dt_mean, filter ? P.lowpass_cutoff_hz : 0.0);
    const Mat3 cov_acc = P.accel_sigma * P.accel_sigma * gains.second * Mat3::Identity();
    // Interior samples only: the end points have one-sided derivatives.
    for (std::size_t k = 1; k + 1 < n; ++k) {
      const KinematicSample& s = samples[k];
      if (P.use_body_equation) {
        const Mat3 cov = gains.first * s.R_wb * s.cov_v_b * s.R_wb.transpose() +
                         s.R_wb * cov_acc * s.R_wb.transpose();
        problem.AddResidualBlock(
            BodyAccelerationResidual::Create(a_w[k], s.R_wb, accel_b[k], sqrtInformation(cov)),
            loss, g_w, b_a);
      }
      if (P.use_lidar_equation) {
        const Vec3& w = omega_b[k];
        const Vec3 c_b =
            s.R_wb.transpose() * a_lw[k] - w.cross(w.cross(p_bl)) - alpha_b[k].cross(p_bl);
        const Mat3 cov = gains.first * R_bl * s.cov_v_l * R_bl.transpose() + cov_acc;
        problem.AddResidualBlock(
            LidarAccelerationResidual::Create(c_b, s.R_wb, accel_b[k], sqrtInformation(cov)), loss,
            g_w, b_a);
      }
    }
  }

  problem.AddResidualBlock(AccelBiasPrior::Create(P.accel_bias_prior_sigma), nullptr, b_a);
  if (P.formulation == Formulation::Integrated) {
    if (estimate_db)
      problem.AddResidualBlock(GyroBiasPrior::Create(sqrtInformation(gyro_bias_cov)), nullptr,
                               db_g);
    else
      problem.SetParameterBlockConstant(db_g);
  }
  problem.SetManifold(g_w, new ceres::SphereManifold<3>());
  for (int i = 0; i < 3; ++i) {
    problem.SetParameterLowerBound(b_a, i, -P.accel_bias_bound);
    problem.SetParameterUpperBound(b_a, i, P.accel_bias_bound);
  }

  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.num_threads = 1;
  options.max_num_iterations = P.max_iterations;
  options.minimizer_progress_to_stdout = false;
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);

  out.final_cost = summary.final_cost;
  out.iterations = static_cast<int>(summary.iterations.size());
  if (!summary.IsSolutionUsable()) {
    out.message = "gravity/accelerometer-bias solve not usable: " + summary.BriefReport();
    return out;
  }
  out.g_w = Vec3(g_w[0], g_w[1], g_w[2]);
  out.b_a = Vec3(b_a[0], b_a[1], b_a[2]);
  out.delta_b_g = Vec3(db_g[0], db_g[1], db_g[2]);
  if (!P.compute_covariance) {
    out.ok = true;
    out.message = summary.BriefReport();
    return out;
  }

  // Covariance of [g_w, b_a] in ambient coordinates (Ceres lifts the tangent-space covariance of
  // the sphere through its plus Jacobian, so the g block has rank 2); v0_w is marginalized.
  ceres::Covariance::Options cov_options;
  cov_options.algorithm_type = ceres::DENSE_SVD;
  cov_options.num_threads = 1;
  ceres::Covariance covariance(cov_options);
  std::vector<const double*> cov_blocks = {g_w, b_a};
  if (estimate_db) cov_blocks.push_back(db_g);
  std::vector<std::pair<const double*, const double*>> blocks;
  for (std::size_t i = 0; i < cov_blocks.size(); ++i)
    for (std::size_t j = i; j < cov_blocks.size(); ++j)
      blocks.emplace_back(cov_blocks[i], cov_blocks[j]);
  if (!covariance.Compute(blocks, &problem)) {
    out.message = "gravity/accelerometer-bias covariance is rank deficient";
    return out;
  }
  const int dim = 3 * static_cast<int>(cov_blocks.size());
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> cov(dim, dim);
  if (!covariance.GetCovarianceMatrix(cov_blocks, cov.data())) {
    out.message = "gravity/accelerometer-bias covariance could not be extracted";
    return out;
  }
  out.cov_full.setZero();
  out.cov_full.topLeftCorner(dim, dim) = 0.5 * (cov + cov.transpose());
  out.cov = out.cov_full.topLeftCorner<6, 6>();
  out.ok = true;
  out.message = summary.BriefReport();
  return out;
}

}  // namespace freeinit
