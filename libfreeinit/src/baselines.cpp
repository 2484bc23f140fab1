// Baseline initializers (FAST-LIO2, DLIO, per-frame Doppler least squares), see baselines.h.
#include <freeinit/baselines.h>
#include <freeinit/rotation.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "paper/velocity_bootstrap.h"

namespace freeinit::baselines {
namespace {

// Variances reported for what a baseline assumes instead of estimating.
constexpr double kAssumedVelocityVar = 1.0;       ///< [(m/s)^2] "v = 0" is an assumption
constexpr double kAssumedAccelBiasVar = 0.04;     ///< [(m/s^2)^2] "b_a = 0": a 0.2 m/s^2 prior
constexpr double kDefinedByConventionVar = 1e-9;  ///< p_w = 0, yaw = 0, g_w fixed by definition

/// Means and sample covariances of gyro and accel over imu[first, last).
struct ImuStatistics {
  Vec3 gyro_mean = Vec3::Zero();
  Vec3 accel_mean = Vec3::Zero();
  Mat3 gyro_cov = Mat3::Zero();   ///< sample covariance of one sample
  Mat3 accel_cov = Mat3::Zero();  ///< sample covariance of one sample
  std::size_t count = 0;
};

ImuStatistics statistics(const std::vector<ImuSample>& imu, std::size_t first, std::size_t last) {
  ImuStatistics st;
  st.count = last - first;
  for (std::size_t i = first; i < last; ++i) {
    st.gyro_mean += imu[i].gyro;
    st.accel_mean += imu[i].accel;
  }
  const double n = static_cast<double>(st.count);
  st.gyro_mean /= n;
  st.accel_mean /= n;
  for (std::size_t i = first; i < last; ++i) {
    const Vec3 dg = imu[i].gyro - st.gyro_mean;
    const Vec3 da = imu[i].accel - st.accel_mean;
    st.gyro_cov += dg * dg.transpose();
    st.accel_cov += da * da.transpose();
  }
  if (st.count > 1) {
    st.gyro_cov /= n - 1.0;
    st.accel_cov /= n - 1.0;
  }
  return st;
}

/// The state of a static-mean initializer: gravity-aligned attitude (yaw 0) from the mean
/// specific force, b_g = mean gyro, v = 0, b_a = b_a_body, with covariance: roll/pitch from the
/// accelerometer mean noise and the (unestimated) horizontal bias, b_g from the gyro mean noise,
/// the assumed quantities with large variances.
InitialState staticMeanState(const ImuStatistics& st, double timestamp, const Vec3& b_a_body,
                             double b_a_var) {
  InitialState s;
  s.status = InitStatus::Ok;
  s.timestamp = timestamp;
  const Vec3 g_b = -(st.accel_mean - b_a_body);
  const Mat3 R_wb = alignToGravity(g_b);
  s.q_wb = Quat(R_wb).normalized();
  s.p_w.setZero();
  s.v_w.setZero();
  s.b_g = st.gyro_mean;
  s.b_a = b_a_body;
  s.g_w = Vec3(0, 0, -kGravity);

  const double n = static_cast<double>(st.count);
  // Tilt (right perturbation, body frame): an error e_b of the horizontal specific force tilts
  // the attitude by about |e_b| / g about the body axes orthogonal to gravity.
  const Vec3 up_b = -g_b.normalized();
  const Mat3 P_horizontal = Mat3::Identity() - up_b * up_b.transpose();
  const Mat3 cov_f = st.accel_cov / n + b_a_var * Mat3::Identity();
  Mat3 cov_theta = P_horizontal * cov_f * P_horizontal / (kGravity * kGravity);
  cov_theta += kDefinedByConventionVar * up_b * up_b.transpose();  // yaw defined as zero
  cov_theta += 1e-12 * Mat3::Identity();

  s.cov.setZero();
  s.cov.block<3, 3>(kTheta, kTheta) = cov_theta;
  s.cov.block<3, 3>(kPos, kPos) = kDefinedByConventionVar * Mat3::Identity();
  s.cov.block<3, 3>(kVel, kVel) = kAssumedVelocityVar * Mat3::Identity();
  s.cov.block<3, 3>(kBg, kBg) = st.gyro_cov / n + 1e-12 * Mat3::Identity();
  s.cov.block<3, 3>(kBa, kBa) = b_a_var * Mat3::Identity();
  s.cov.block<3, 3>(kGrav, kGrav) = kDefinedByConventionVar * Mat3::Identity();
  return s;
}

InitResult notEnoughData(const std::string& why) {
  InitResult r;
  r.state.status = InitStatus::NotEnoughData;
  r.state.message = why;
  return r;
}

/// The trajectory of a static initializer: the window's IMU times at the initial pose.
void fillTrajectory(const std::vector<ImuSample>& imu, std::size_t count, InitResult& r) {
  r.trajectory.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    PoseSample p;
    p.t = imu[i].t;
    p.q_wb = r.state.q_wb;
    p.p_w = r.state.p_w;
    r.trajectory.push_back(p);
  }
}

}  // namespace

InitResult fastLio2(const std::vector<ImuSample>& imu, int imu_samples) {
  if (imu_samples < 2) throw std::invalid_argument("baselines::fastLio2: imu_samples must be >= 2");
  const auto count = static_cast<std::size_t>(imu_samples);
  if (imu.size() < count)
    return notEnoughData("FAST-LIO2 init needs " + std::to_string(imu_samples) +
                         " IMU samples, got " + std::to_string(imu.size()));
  const ImuStatistics st = statistics(imu, 0, count);
  InitResult r;
  r.state = staticMeanState(st, imu[count - 1].t, Vec3::Zero(), kAssumedAccelBiasVar);
  fillTrajectory(imu, count, r);
  return r;
}

InitResult dlio(const std::vector<ImuSample>& imu, double duration) {
  if (!(duration > 0)) throw std::invalid_argument("baselines::dlio: duration must be > 0 s");
  if (imu.size() < 2) return notEnoughData("DLIO init needs IMU data");
  const double t_start = imu.front().t;
  std::size_t count = 0;
  while (count < imu.size() && imu[count].t <= t_start + duration + 1e-9) ++count;
  // The data must cover the calibration time (one sample period of slack).
  const double dt = (imu[count - 1].t - t_start) / std::max(1.0, static_cast<double>(count - 1));
  if (count < 2 || imu[count - 1].t < t_start + duration - 1.5 * dt)
    return notEnoughData("DLIO init needs " + std::to_string(duration) + " s of IMU data");
  const ImuStatistics st = statistics(imu, 0, count);
  // DLIO: the bias is what the mean specific force has beyond 9.81, along its own direction.
  const Vec3 b_a = st.accel_mean - kGravity * st.accel_mean.normalized();
  InitResult r;
  r.state = staticMeanState(st, imu[count - 1].t, b_a, kAssumedAccelBiasVar);
  // The magnitude (vertical) part of b_a is measured: shrink its variance to the mean noise.
  const Vec3 up_b = st.accel_mean.normalized();
  const double n = static_cast<double>(st.count);
  const double vertical_var = up_b.dot(st.accel_cov * up_b) / n + 1e-12;
  const Mat3 P_h = Mat3::Identity() - up_b * up_b.transpose();
  r.state.cov.block<3, 3>(kBa, kBa) =
      kAssumedAccelBiasVar * P_h + vertical_var * up_b * up_b.transpose();
  fillTrajectory(imu, count, r);
  return r;
}

FrameVelocity dopplerFrameVelocity(const LidarFrame& frame, const std::vector<ImuSample>& imu,
                                   const Extrinsics& extrinsics) {
  FrameVelocity out;
  if (frame.points.empty()) {
    out.message = "frame without points";
    return out;
  }
  const double t_first = frame.stamp + frame.points.front().time_offset;
  const double t_last = frame.stamp + frame.points.back().time_offset;
  out.t_mid = 0.5 * (t_first + t_last);

  // Directions and Doppler of the frame's returns.
  std::vector<Vec3> d_l;
  std::vector<double> doppler;
  d_l.reserve(frame.points.size());
  doppler.reserve(frame.points.size());
  for (const DopplerPoint& p : frame.points) {
    const Vec3 p_l = p.p_l.cast<double>();
    const double range = p_l.norm();
    if (!(range > 1e-3) || !std::isfinite(p.doppler)) continue;
    d_l.push_back(p_l / range);
    doppler.push_back(p.doppler);
  }
  if (d_l.size() < 10) {
    out.status = InitStatus::NoDoppler;
    out.message = "too few valid Doppler returns in the frame";
    return out;
  }

  // The same robust least squares (IRLS, Cauchy) as Free-Init's bootstrap, on the whole frame.
  const VelocityFit fit = fitLidarVelocity(d_l, doppler, VelocityFitParams{}, 0.03);
  if (!fit.ok) {
    out.status = InitStatus::DegenerateGeometry;
    out.message = fit.message;
    return out;
  }

  // Mean (raw) gyro over the frame's time span for the lever arm.
  Vec3 omega_b = Vec3::Zero();
  int n_gyro = 0;
  for (const ImuSample& s : imu) {
    if (s.t >= t_first && s.t <= t_last) {
      omega_b += s.gyro;
      ++n_gyro;
    }
  }
  if (n_gyro > 0) {
    omega_b /= n_gyro;
  } else if (!imu.empty()) {
    const auto nearest =
        std::min_element(imu.begin(), imu.end(), [&](const auto& a, const auto& b) {
          return std::abs(a.t - frame.stamp) < std::abs(b.t - frame.stamp);
        });
    omega_b = nearest->gyro;
  }

  // v_l = R_bl^T (v_b + omega x p_bl)  =>  v_b = R_bl v_l - omega x p_bl.
  out.status = InitStatus::Ok;
  out.v_b = extrinsics.R_bl * fit.v_l - omega_b.cross(extrinsics.p_bl);
  out.cov_v_b = extrinsics.R_bl * fit.cov * extrinsics.R_bl.transpose();
  return out;
}

InitResult dopplerLeastSquares(const std::vector<ImuSample>& imu,
                               const std::vector<LidarFrame>& frames, const Extrinsics& extrinsics,
                               int imu_samples) {
  InitResult r = fastLio2(imu, imu_samples);
  if (!r.state.ok()) return r;
  const auto count = static_cast<std::size_t>(imu_samples);
  const double t_begin = imu.front().t;
  const double t_end = imu[count - 1].t;

  // The last frame that starts inside the window and has points.
  const LidarFrame* frame = nullptr;
  for (const LidarFrame& f : frames)
    if (f.stamp >= t_begin && f.stamp <= t_end && f.points.size() >= 10) frame = &f;
  if (frame == nullptr) {
    r.state.status = InitStatus::NotEnoughData;
    r.state.message = "no LiDAR frame with points inside the IMU window";
    return r;
  }
  const FrameVelocity fv = dopplerFrameVelocity(*frame, imu, extrinsics);
  if (!fv.ok()) {
    r.state.status = fv.status;
    r.state.message = "last frame: " + fv.message;
    return r;
  }
  const Mat3 R_wb = r.state.q_wb.toRotationMatrix();
  r.state.v_w = R_wb * fv.v_b;
  r.state.cov.block<3, 3>(kVel, kVel) = R_wb * fv.cov_v_b * R_wb.transpose();
  return r;
}

}  // namespace freeinit::baselines
