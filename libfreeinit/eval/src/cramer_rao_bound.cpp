#include <freeinit/eval/cramer_rao_bound.h>
#include <freeinit/eval/state_errors.h>
#include <freeinit/rotation.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace freeinit::eval {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;
/// [(m/s)^2, (rad/s)^2] A node whose true |v|^2 and |omega|^2 are at most this is at rest (the
/// simulator's standstill is exactly zero; this only absorbs rounding).
constexpr double kRestSquared = 1e-24;

/// Coefficients of the cubic Hermite basis in s (powers 0..3): H00, H10, H01, H11, so that
/// G(s) = H00 G(0) + H10 h G'(0) + H01 G(h) + H11 h G'(h).
constexpr double kHermite[4][4] = {{1, 0, -3, 2}, {0, 1, -2, 1}, {0, 0, 3, -2}, {0, 0, -1, 1}};

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("freeinit::eval::BoundModel: " + what);
}

}  // namespace

void BoundModel::validate() const {
  require(std::isfinite(doppler_sigma) && doppler_sigma > 0, "doppler_sigma must be > 0");
  require(std::isfinite(gyro_sigma) && gyro_sigma >= 0, "gyro_sigma must be >= 0");
  require(std::isfinite(accel_sigma) && accel_sigma >= 0, "accel_sigma must be >= 0");
  require(gyro_axis_scale.allFinite() && gyro_axis_scale.minCoeff() > 0,
          "gyro_axis_scale must be > 0");
  require(accel_axis_scale.allFinite() && accel_axis_scale.minCoeff() > 0,
          "accel_axis_scale must be > 0");
  require(std::isfinite(gyro_bias_random_walk) && gyro_bias_random_walk >= 0,
          "gyro_bias_random_walk must be >= 0");
  require(std::isfinite(accel_bias_random_walk) && accel_bias_random_walk >= 0,
          "accel_bias_random_walk must be >= 0");
  require(gyro_bias_prior_sigma > 0, "gyro_bias_prior_sigma must be > 0 (kNoPrior: none)");
  require(accel_bias_prior_sigma > 0, "accel_bias_prior_sigma must be > 0 (kNoPrior: none)");
  require(g_w.allFinite() && g_w.norm() > 0, "g_w must be finite and non-zero");
  require(extrinsics.R_bl.allFinite() && extrinsics.p_bl.allFinite(),
          "the extrinsics must be finite");
}

CramerRaoBound::CramerRaoBound(const BoundModel& model, std::vector<KinematicTruth> nodes)
    : model_(model), nodes_(std::move(nodes)) {
  model_.validate();
  if (nodes_.size() < 2)
    throw std::invalid_argument("freeinit::eval::CramerRaoBound: needs at least 2 IMU nodes");
  for (std::size_t k = 1; k < nodes_.size(); ++k)
    if (!(nodes_[k].t > nodes_[k - 1].t))
      throw std::invalid_argument("freeinit::eval::CramerRaoBound: node " + std::to_string(k) +
                                  ": times must increase");
  const Vec3& p_bl = model_.extrinsics.p_bl;
  const Mat3 R_lb = model_.extrinsics.R_bl.transpose();
  const std::size_t n = intervals();
  transitions_.resize(n);
  hermite_.resize(n);
  moments_.assign(n, Moments{});
  Mat18 T18 = Mat18::Identity();
  for (std::size_t k = 0; k < n; ++k) {
    const KinematicTruth& a = nodes_[k];
    const KinematicTruth& b = nodes_[k + 1];
    const double h = b.t - a.t;
    transitions_[k] = errorTransition(a, b, model_.g_w);
    T18.topRows<12>() = transitions_[k];
    // G(t) = C(t) T(t) and G' = (C' + C A) T, with T(a) = I.
    const Mat3x18 Ca = lidarVelocityJacobian(a, p_bl);
    const Mat3x18 Cb = lidarVelocityJacobian(b, p_bl);
    const Mat3x18 dGa = lidarVelocityJacobianRate(a) + Ca * errorDynamics(a, model_.g_w);
    const Mat3x18 dGb = (lidarVelocityJacobianRate(b) + Cb * errorDynamics(b, model_.g_w)) * T18;
    Eigen::Matrix<double, 12, 18>& B = hermite_[k];
    B.block<3, 18>(0, 0) = R_lb * Ca;
    B.block<3, 18>(3, 0) = h * R_lb * dGa;
    B.block<3, 18>(6, 0) = R_lb * Cb * T18;
    B.block<3, 18>(9, 0) = h * R_lb * dGb;
  }
}

std::size_t CramerRaoBound::intervalOf(double t) {
  const std::size_t n = intervals();
  if (cursor_ < n && t >= nodes_[cursor_].t && t < nodes_[cursor_ + 1].t) return cursor_;
  const auto it = std::upper_bound(nodes_.begin(), nodes_.end(), t,
                                   [](double x, const KinematicTruth& s) { return x < s.t; });
  const auto k = static_cast<std::size_t>(it - nodes_.begin());
  cursor_ = std::min(k == 0 ? 0 : k - 1, n - 1);  // the last node belongs to the last interval
  return cursor_;
}

bool CramerRaoBound::addDoppler(double t, const Vec3& d_l, double sigma) {
  if (!(t >= nodes_.front().t && t <= nodes_.back().t)) return false;
  const double norm2 = d_l.squaredNorm();
  if (!(norm2 > 0) || !std::isfinite(norm2))
    throw std::invalid_argument("freeinit::eval::CramerRaoBound::addDoppler: direction is zero");
  if (!(sigma > 0) || !std::isfinite(sigma))
    throw std::invalid_argument("freeinit::eval::CramerRaoBound::addDoppler: sigma must be > 0");
  const std::size_t k = intervalOf(t);
  const double s = (t - nodes_[k].t) / (nodes_[k + 1].t - nodes_[k].t);
  const double w = 1.0 / (sigma * sigma * norm2);  // unit direction: d d^T / |d|^2
  const double q[6] = {w * d_l.x() * d_l.x(), w * d_l.x() * d_l.y(), w * d_l.x() * d_l.z(),
                       w * d_l.y() * d_l.y(), w * d_l.y() * d_l.z(), w * d_l.z() * d_l.z()};
  double* P = moments_[k].data();
  double sm = 1;
  for (int m = 0; m < 7; ++m, sm *= s)
    for (int e = 0; e < 6; ++e) P[6 * m + e] += q[e] * sm;
  ++measurements_;
  return true;
}

Eigen::Matrix<double, 1, 18> CramerRaoBound::dopplerRow(std::size_t k, double t,
                                                        const Vec3& d_l) const {
  const double s = (t - nodes_[k].t) / (nodes_[k + 1].t - nodes_[k].t);
  Eigen::Matrix<double, 1, 18> r = Eigen::Matrix<double, 1, 18>::Zero();
  for (int i = 0; i < 4; ++i) {
    const double* c = kHermite[i];
    const double H = c[0] + s * (c[1] + s * (c[2] + s * c[3]));
    r -= H * d_l.normalized().transpose() * hermite_[k].block<3, 18>(3 * i, 0);
  }
  return r;
}

Mat18 CramerRaoBound::intervalInformation(std::size_t k) const {
  const double* P = moments_[k].data();
  auto moment = [&](int m) {
    const double* p = P + 6 * m;
    Mat3 S;
    S << p[0], p[1], p[2], p[1], p[3], p[4], p[2], p[4], p[5];
    return S;
  };
  Mat3 Pm[7];
  for (int m = 0; m < 7; ++m) Pm[m] = moment(m);
  // M_ij = sum_pq c_ip c_jq P_(p+q): the moments of H_i(s) H_j(s) d d^T.
  Eigen::Matrix<double, 12, 12> M = Eigen::Matrix<double, 12, 12>::Zero();
  for (int i = 0; i < 4; ++i)
    for (int j = i; j < 4; ++j) {
      Mat3 Mij = Mat3::Zero();
      for (int p = 0; p < 4; ++p)
        for (int q = 0; q < 4; ++q) {
          const double c = kHermite[i][p] * kHermite[j][q];
          if (c != 0) Mij += c * Pm[p + q];
        }
      M.block<3, 3>(3 * i, 3 * j) = Mij;
      M.block<3, 3>(3 * j, 3 * i) = Mij.transpose();
    }
  const Eigen::Matrix<double, 12, 18>& B = hermite_[k];
  const Mat18 Z = B.transpose() * M * B;
  return 0.5 * (Z + Z.transpose());
}

Mat12 CramerRaoBound::priorInformation() const {
  Mat12 L = Mat12::Zero();
  const double sg = model_.gyro_bias_prior_sigma, sa = model_.accel_bias_prior_sigma;
  if (std::isfinite(sg)) L.block<3, 3>(kDBg, kDBg) = Mat3::Identity() / (sg * sg);
  if (std::isfinite(sa)) L.block<3, 3>(kDBa, kDBa) = Mat3::Identity() / (sa * sa);
  return L;
}

Eigen::Matrix<double, 11, 12> CramerRaoBound::outputJacobian() const {
  const KinematicTruth& s = nodes_.back();
  const Mat3 R_bw = s.R_wb.transpose();
  Eigen::Matrix<double, 11, 12> A = Eigen::Matrix<double, 11, 12>::Zero();
  A.block<3, 3>(0, kDTheta) = skew(Vec3(R_bw * s.v_w));
  A.block<3, 3>(0, kDVel) = R_bw;
  A.block<2, 3>(3, kDTheta) = tiltBasis(R_bw * model_.g_w).transpose();
  A.block<3, 3>(5, kDBg) = Mat3::Identity();
  A.block<3, 3>(8, kDBa) = Mat3::Identity();
  return A;
}

Eigen::Matrix<double, 12, 1> CramerRaoBound::yawDirection(std::size_t k) const {
  // A rotation psi of the world about the vertical: R -> Exp(psi e) R = R Exp(psi R^T e),
  // v -> Exp(psi e) v: dtheta = R^T e psi, dv = e x v psi; the biases do not change.
  const KinematicTruth& s = nodes_[k];
  const Vec3 e = -model_.g_w.normalized();
  Eigen::Matrix<double, 12, 1> n = Eigen::Matrix<double, 12, 1>::Zero();
  n.segment<3>(kDTheta) = s.R_wb.transpose() * e;
  n.segment<3>(kDVel) = e.cross(s.v_w);
  return n.normalized();
}

Bound CramerRaoBound::compute() const {
  Bound out;
  out.t_begin = nodes_.front().t;
  out.t_end = nodes_.back().t;
  out.nodes = nodes_.size();
  out.measurements = measurements_;

  // The process noise of an interval: [n_g, n_a] (in the rows, constant over the interval) and the
  // bias random walks [w_g, w_a] (added at the next node). Only those with a non-zero variance.
  struct Noise {
    int z_col;  ///< column in z_k (n_g, n_a) or -1 (random walk)
    int x_row;  ///< for a random walk: the bias it drives
    Vec3 var;   ///< per component
  };
  std::vector<Noise> noises;
  if (model_.gyro_sigma > 0) noises.push_back({kNg, 0, model_.gyroSigmaPerAxis().cwiseAbs2()});
  if (model_.accel_sigma > 0) noises.push_back({kNa, 0, model_.accelSigmaPerAxis().cwiseAbs2()});
  const bool rw_g = model_.gyro_bias_random_walk > 0, rw_a = model_.accel_bias_random_walk > 0;
  const auto m = static_cast<Eigen::Index>(3 * (noises.size() + (rw_g ? 1 : 0) + (rw_a ? 1 : 0)));

  Mat12 L = priorInformation();
  for (std::size_t k = 0; k < intervals(); ++k) {
    const double h = nodes_[k + 1].t - nodes_[k].t;
    const Mat18 Z = intervalInformation(k);
    const Mat12x18& T = transitions_[k];
    const Mat12 Phi_inv = T.leftCols<12>().inverse();
    if (m == 0) {
      L = Phi_inv.transpose() * (L + Z.topLeftCorner<12, 12>()) * Phi_inv;
    } else {
      std::vector<Noise> all = noises;
      if (rw_g)
        all.push_back(
            {-1, kDBg,
             Vec3::Constant(model_.gyro_bias_random_walk * model_.gyro_bias_random_walk * h)});
      if (rw_a)
        all.push_back(
            {-1, kDBa,
             Vec3::Constant(model_.accel_bias_random_walk * model_.accel_bias_random_walk * h)});
      // Information J on [x_k; noise] and x_k+1 = Phi x_k + Gamma noise.
      Eigen::MatrixXd J = Eigen::MatrixXd::Zero(12 + m, 12 + m);
      Eigen::MatrixXd Gamma = Eigen::MatrixXd::Zero(12, m);
      J.topLeftCorner<12, 12>() = L + Z.topLeftCorner<12, 12>();
      for (std::size_t i = 0; i < all.size(); ++i) {
        const Eigen::Index oi = 12 + 3 * static_cast<Eigen::Index>(i);
        J.block<3, 3>(oi, oi) += all[i].var.cwiseInverse().asDiagonal();
        if (all[i].z_col < 0) {
          Gamma.block<3, 3>(all[i].x_row, oi - 12) = Mat3::Identity();
          continue;
        }
        Gamma.block<12, 3>(0, oi - 12) = T.block<12, 3>(0, all[i].z_col);
        J.block<12, 3>(0, oi) = Z.block<12, 3>(0, all[i].z_col);
        J.block<3, 12>(oi, 0) = Z.block<3, 12>(all[i].z_col, 0);
        for (std::size_t j = 0; j < all.size(); ++j) {
          if (all[j].z_col < 0) continue;
          const Eigen::Index oj = 12 + 3 * static_cast<Eigen::Index>(j);
          J.block<3, 3>(oi, oj) += Z.block<3, 3>(all[i].z_col, all[j].z_col);
        }
      }
      // [x_k; noise] = M [x_k+1; noise], M = [Phi^-1, -Phi^-1 Gamma; 0, I].
      Eigen::MatrixXd M = Eigen::MatrixXd::Identity(12 + m, 12 + m);
      M.topLeftCorner<12, 12>() = Phi_inv;
      M.topRightCorner(12, m) = -Phi_inv * Gamma;
      const Eigen::MatrixXd Jp = M.transpose() * J * M;
      const Eigen::MatrixXd Jnn = Jp.bottomRightCorner(m, m);
      const Eigen::MatrixXd Jnx = Jp.bottomLeftCorner(m, 12);
      L = Jp.topLeftCorner<12, 12>() - Jnx.transpose() * Jnn.ldlt().solve(Jnx);
    }
    L = 0.5 * (L + L.transpose()).eval();
  }

  // Gauge: information along the world-yaw direction (in the null space of L), scaled like L.
  const Eigen::Matrix<double, 12, 1> yaw = yawDirection(intervals());
  const double scale = std::max(L.trace() / 12.0, 1.0);
  const Mat12 Lg = L + scale * yaw * yaw.transpose();
  if (!Lg.allFinite()) {
    out.message = "the information is not finite";
    return out;
  }
  // Pseudo-inverse of the Jacobi-scaled information; directions of (numerically) no information
  // make every output block that sees them unobservable (infinite).
  Eigen::Matrix<double, 12, 1> d;
  for (int i = 0; i < 12; ++i) d(i) = Lg(i, i) > 0 ? 1.0 / std::sqrt(Lg(i, i)) : 1.0;
  const Mat12 S = d.asDiagonal() * Lg * d.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Mat12> es(S);
  const double ev_max = std::max(es.eigenvalues().maxCoeff(), 0.0);
  const Eigen::Matrix<double, 11, 12> A = outputJacobian();
  const Eigen::Matrix<double, 11, 12> Ad = A * d.asDiagonal();
  Mat12 S_pinv = Mat12::Zero();
  bool unobservable[11] = {};
  for (int i = 0; i < 12; ++i) {
    const double ev = es.eigenvalues()(i);
    const Eigen::Matrix<double, 12, 1> u = es.eigenvectors().col(i);
    if (ev > 1e-12 * ev_max) {
      S_pinv += u * u.transpose() / ev;
      continue;
    }
    const Eigen::Matrix<double, 11, 1> seen = Ad * u;
    for (int r = 0; r < 11; ++r)
      if (std::abs(seen(r)) > 1e-6 * Ad.row(r).norm()) unobservable[r] = true;
  }
  out.cov = Ad * S_pinv * Ad.transpose();
  out.cov = 0.5 * (out.cov + out.cov.transpose()).eval();
  // A block is unobservable if any of its rows is.
  const int begin[4] = {0, 3, 5, 8}, size[4] = {3, 2, 3, 3};
  double* bounds[4] = {&out.velocity, &out.gravity_deg, &out.gyro_bias, &out.accel_bias};
  const double inf = std::numeric_limits<double>::infinity();
  for (int b = 0; b < 4; ++b) {
    bool unobs = false;
    for (int r = begin[b]; r < begin[b] + size[b]; ++r) unobs = unobs || unobservable[r];
    if (unobs) {
      for (int r = begin[b]; r < begin[b] + size[b]; ++r) out.cov(r, r) = inf;
      *bounds[b] = inf;
    } else {
      *bounds[b] =
          std::sqrt(std::max(out.cov.block(begin[b], begin[b], size[b], size[b]).trace(), 0.0));
    }
  }
  out.gravity_deg *= kRadToDeg;
  out.tilt_basis = A.block<2, 3>(3, kDTheta).transpose();
  for (const KinematicTruth& s : nodes_)
    if (s.v_w.squaredNorm() <= kRestSquared && s.omega_b.squaredNorm() <= kRestSquared)
      ++out.rest_nodes;
  out.gyro_bias_zero_rate = zeroRateGyroBiasBound(model_.gyroSigmaPerAxis(), out.rest_nodes,
                                                  model_.gyro_bias_prior_sigma);
  out.ok = true;
  return out;
}

double zeroRateGyroBiasBound(const Vec3& gyro_sigma, std::size_t rest_samples, double prior_sigma) {
  if (rest_samples == 0) return std::numeric_limits<double>::quiet_NaN();
  const double n = static_cast<double>(rest_samples);
  const double prior_information =
      std::isfinite(prior_sigma) ? 1.0 / (prior_sigma * prior_sigma) : 0;
  double variance = 0;
  for (int i = 0; i < 3; ++i) {
    if (gyro_sigma(i) == 0) continue;  // an exact axis: known exactly from one sample
    variance += 1.0 / (n / (gyro_sigma(i) * gyro_sigma(i)) + prior_information);
  }
  return std::sqrt(variance);
}

}  // namespace freeinit::eval
