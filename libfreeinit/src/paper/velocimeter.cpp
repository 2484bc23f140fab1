#include "paper/velocimeter.h"

#include <freeinit/rotation.h>

#include <algorithm>
#include <cmath>

namespace freeinit {
namespace {

/// The covariance transition is applied once this much time has accumulated [s]. At 10 rad/s
/// this keeps |A dt| below 2e-2, so the first-order transition matrix is accurate to ~2e-4.
constexpr double kTransitionPeriod = 2e-3;

}  // namespace

VelocimeterParams velocimeterParams(const FreeInitConfig& config) {
  const DopplerParams& d = config.doppler;
  const ImuParams& imu = config.imu;
  const PaperVelocimeterParams& v = config.paper_velocimeter;
  VelocimeterParams p;
  p.doppler_sigma = d.doppler_sigma;
  p.gyro_sigma = imu.gyro_sigma;
  p.vel_random_walk = v.vel_random_walk;
  p.omega_random_walk = v.omega_random_walk;
  p.aided_vel_random_walk = v.aided_vel_random_walk;
  p.gyro_bias_random_walk = imu.gyro_bias_random_walk;
  p.gyro_bias_tau = v.gyro_bias_tau;
  p.gyro_bias_sigma0 = imu.gyro_bias_sigma0;
  p.gyro_bias_prior = imu.gyro_bias_prior;
  p.kinematic_propagation = v.kinematic_propagation;
  p.doppler_updates_omega = v.doppler_updates_omega;
  p.gate_sigma = d.gate_sigma;
  p.gate_min = d.gate_min;
  p.gate_rel = d.gate_rel;
  return p;
}

Velocimeter::Velocimeter(const VelocimeterParams& params, const Extrinsics& extrinsics)
    : params_(params), R_bl_(extrinsics.R_bl), p_bl_(extrinsics.p_bl) {
  q_v_ = params.vel_random_walk * params.vel_random_walk;
  q_w_ = params.omega_random_walk * params.omega_random_walk;
  q_b_ = params.gyro_bias_random_walk * params.gyro_bias_random_walk;
  r_doppler_ = params.doppler_sigma * params.doppler_sigma;
  r_gyro_ = params.gyro_sigma * params.gyro_sigma;
  gate_min2_ = params.gate_min * params.gate_min;
  gate_k2_ = params.gate_sigma * params.gate_sigma;
}

void Velocimeter::start(double t, const Vec3& v_l, const Mat3& cov_v_l, const Vec3& gyro) {
  t_ = t;
  pending_dt_ = 0;
  omega_slope_.setZero();
  b_g_ = params_.gyro_bias_prior;
  omega_b_ = gyro - b_g_;
  v_l_ = v_l;
  P_l_ = cov_v_l;
  // v_b = R_bl v_l + p_bl x omega_b  (rigid body, paper Eq. (noninertial_kin_lin_1st)).
  v_b_ = R_bl_ * v_l_ + p_bl_.cross(omega_b_);
  const Mat3 P_bg = Mat3::Identity() * params_.gyro_bias_sigma0 * params_.gyro_bias_sigma0;
  const Mat3 P_w = Mat3::Identity() * r_gyro_ + P_bg;  // omega = gyro - b_g
  const Mat3 P_wbg = -P_bg;
  const Mat3 Sp = skew(p_bl_);
  P_b_.setZero();
  P_b_.block<3, 3>(0, 0) = R_bl_ * P_l_ * R_bl_.transpose() + Sp * P_w * Sp.transpose();
  P_b_.block<3, 3>(0, 3) = Sp * P_w;
  P_b_.block<3, 3>(0, 6) = Sp * P_wbg;
  P_b_.block<3, 3>(3, 3) = P_w;
  P_b_.block<3, 3>(3, 6) = P_wbg;
  P_b_.block<3, 3>(6, 6) = P_bg;
  P_b_.block<3, 3>(3, 0) = P_b_.block<3, 3>(0, 3).transpose();
  P_b_.block<3, 3>(6, 0) = P_b_.block<3, 3>(0, 6).transpose();
  P_b_.block<3, 3>(6, 3) = P_b_.block<3, 3>(3, 6).transpose();
}

void Velocimeter::propagate(double t) {
  const double dt = t - t_;
  if (dt <= 0) return;
  if (params_.kinematic_propagation) {
    // dv/dt = a - omega x v in the moving frame; a is the random walk's business.
    const Vec3 omega_l = R_bl_.transpose() * omega_b_;
    Vec3 dv_l = v_l_.cross(omega_l);
    Vec3 dv_b = v_b_.cross(omega_b_);
    if (aided_) {
      // LiDAR acceleration from the body's: a_l = R_lb (a_b + alpha x p + omega x (omega x p)).
      const Vec3 a_b = a_b_ + a_b_slope_ * (t - t_acc_);
      dv_b += a_b;
      dv_l += R_bl_.transpose() *
              (a_b + omega_slope_.cross(p_bl_) + omega_b_.cross(omega_b_.cross(p_bl_)));
    }
    v_l_ += dv_l * dt;
    v_b_ += dv_b * dt;
    omega_b_ += omega_slope_ * dt;
  }
  b_g_ *= 1.0 - dt / params_.gyro_bias_tau;  // first-order Gauss-Markov
  // Continuous-time process noise: Q dt.
  P_l_.diagonal().array() += q_v_ * dt;
  P_b_.diagonal().segment<3>(0).array() += q_v_ * dt;
  P_b_.diagonal().segment<3>(3).array() += q_w_ * dt;
  P_b_.diagonal().segment<3>(6).array() += q_b_ * dt;
  t_ = t;
  pending_dt_ += dt;
  if (pending_dt_ >= kTransitionPeriod) applyTransition();
}

void Velocimeter::applyTransition() {
  const double dt = pending_dt_;
  pending_dt_ = 0;
  const double decay = 1.0 - dt / params_.gyro_bias_tau;
  if (!params_.kinematic_propagation) {
    P_b_.block<9, 3>(0, 6) *= decay;
    P_b_.block<3, 9>(6, 0) *= decay;
    return;
  }
  // F = I + A dt with the Jacobians of the kinematic terms.
  const Vec3 omega_l = R_bl_.transpose() * omega_b_;
  const Mat3 F_l = Mat3::Identity() - skew(omega_l) * dt;
  P_l_ = F_l * P_l_ * F_l.transpose();
  P_l_ = 0.5 * (P_l_ + P_l_.transpose()).eval();  // the Doppler downdates keep what this gives
  Mat9 F = Mat9::Identity();
  F.block<3, 3>(0, 0) -= skew(omega_b_) * dt;  // d(v x w)/dv = -[w]x
  F.block<3, 3>(0, 3) = skew(v_b_) * dt;       // d(v x w)/dw = [v]x
  F.block<3, 3>(6, 6) *= decay;
  P_b_ = (F * P_b_ * F.transpose()).eval();
  P_b_ = 0.5 * (P_b_ + P_b_.transpose()).eval();
}

Velocimeter::DopplerOutcome Velocimeter::updateDoppler(const Eigen::Vector3f& p_l, double doppler) {
  DopplerOutcome out;
  const Vec3 d = p_l.cast<double>().normalized();
  // Body model: z = -u^T v_b + (u x p_bl)^T omega_b, u = R_bl d.
  const Vec3 u = R_bl_ * d;
  const Vec3 c = u.cross(p_bl_);
  Eigen::Matrix<double, 6, 1> h;
  h << -u, c;
  const double r_b = doppler - (h.head<3>().dot(v_b_) + c.dot(omega_b_));
  const Eigen::Matrix<double, 9, 1> PH = P_b_.leftCols<6>() * h;
  const double S_b = h.dot(PH.head<6>()) + r_doppler_;
  out.residual = r_b;
  // Gate: dynamic points and gross outliers disagree with the current velocity.
  const double gate =
      std::sqrt(std::max(gate_min2_, gate_k2_ * S_b)) + params_.gate_rel * v_l_.norm();
  if (std::abs(r_b) > gate) return out;
  out.accepted = true;
  const double inv_S = 1.0 / S_b;
  const Eigen::Matrix<double, 9, 1> K = PH * inv_S;
  v_b_ += K.segment<3>(0) * r_b;
  if (params_.doppler_updates_omega) {
    omega_b_ += K.segment<3>(3) * r_b;
    b_g_ += K.segment<3>(6) * r_b;
    P_b_.noalias() -= K * PH.transpose();
  } else {
    // Schmidt ("consider") update: omega_b and b_g shape the gain through S but keep their
    // estimates and covariance; only the v_b rows and columns change.
    const Eigen::Matrix<double, 3, 9> dP = K.segment<3>(0) * PH.transpose();
    P_b_.topRows<3>() -= dP;
    P_b_.block<6, 3>(3, 0) -= dP.rightCols<6>().transpose();
  }
  // LiDAR model: z = -d^T v_l.
  const double r_l = doppler + d.dot(v_l_);
  const Vec3 PHl = -(P_l_ * d);
  const double S_l = -d.dot(PHl) + r_doppler_;  // d^T P_l d, with PHl = -P_l d
  const double gate_l =
      std::sqrt(std::max(gate_min2_, gate_k2_ * S_l)) + params_.gate_rel * v_l_.norm();
  if (std::abs(r_l) <= gate_l) {
    v_l_ += PHl * (r_l / S_l);
    P_l_.noalias() -= PHl * PHl.transpose() / S_l;
  }
  return out;
}

void Velocimeter::updateGyro(const Vec3& gyro, const Vec3& next_gyro, double dt_next) {
  // z = omega_b + b_g: H = [0 I I] over [v_b omega_b b_g].
  const Vec3 r = gyro - omega_b_ - b_g_;
  const Eigen::Matrix<double, 9, 3> PH = P_b_.middleCols<3>(3) + P_b_.middleCols<3>(6);
  const Mat3 S = PH.middleRows<3>(3) + PH.middleRows<3>(6) + Mat3::Identity() * r_gyro_;
  const Eigen::Matrix<double, 9, 3> K = PH * S.inverse();
  const Eigen::Matrix<double, 9, 1> dx = K * r;
  v_b_ += dx.segment<3>(0);
  omega_b_ += dx.segment<3>(3);
  b_g_ += dx.segment<3>(6);
  P_b_ -= K * PH.transpose();
  P_b_ = 0.5 * (P_b_ + P_b_.transpose()).eval();
  omega_slope_ = dt_next > 0 ? Vec3((next_gyro - gyro) / dt_next) : Vec3::Zero();
}

void Velocimeter::setAcceleration(const Vec3& a_b, const Vec3& a_b_slope) {
  aided_ = true;
  a_b_ = a_b;
  a_b_slope_ = a_b_slope;
  t_acc_ = t_;
  q_v_ = params_.aided_vel_random_walk * params_.aided_vel_random_walk;
}

void Velocimeter::updateZeroVelocity(double sigma) {
  const double r = sigma * sigma;
  // v_l = 0.
  const Mat3 K_l = P_l_ * (P_l_ + Mat3::Identity() * r).inverse();
  v_l_ -= K_l * v_l_;
  P_l_ = ((Mat3::Identity() - K_l) * P_l_).eval();
  P_l_ = 0.5 * (P_l_ + P_l_.transpose()).eval();
  // v_b = 0, omega_b = 0: H selects the first six states.
  const Eigen::Matrix<double, 6, 6> S =
      P_b_.topLeftCorner<6, 6>() + Eigen::Matrix<double, 6, 6>::Identity() * r;
  const Eigen::Matrix<double, 9, 6> K = P_b_.leftCols<6>() * S.inverse();
  Eigen::Matrix<double, 6, 1> z;
  z << v_b_, omega_b_;
  const Eigen::Matrix<double, 9, 1> dx = -K * z;
  v_b_ += dx.segment<3>(0);
  omega_b_ += dx.segment<3>(3);
  b_g_ += dx.segment<3>(6);
  P_b_ -= K * P_b_.topRows<6>();
  P_b_ = 0.5 * (P_b_ + P_b_.transpose()).eval();
}

void Velocimeter::releaseZeroVelocity(double sigma_v, double sigma_omega) {
  P_l_ = Mat3::Identity() * sigma_v * sigma_v;
  const Mat3 P_bg = P_b_.block<3, 3>(6, 6);
  P_b_.setZero();
  P_b_.block<3, 3>(0, 0) = Mat3::Identity() * sigma_v * sigma_v;
  P_b_.block<3, 3>(3, 3) = Mat3::Identity() * sigma_omega * sigma_omega + P_bg;
  P_b_.block<3, 3>(3, 6) = -P_bg;
  P_b_.block<3, 3>(6, 3) = -P_bg;
  P_b_.block<3, 3>(6, 6) = P_bg;
}

}  // namespace freeinit
