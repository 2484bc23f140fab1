#include <freeinit/doppler_inertial_odometry.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "paper/pose_integrator.h"
#include "paper/velocimeter.h"
#include "paper/velocimeter_inputs.h"

namespace freeinit {

DopplerInertialOdometry::DopplerInertialOdometry(const FreeInitConfig& config,
                                                 const InitialState& state, bool accel_aided)
    : config_(config), state_(state), accel_aided_(accel_aided) {
  if (!state.ok())
    throw std::invalid_argument("DopplerInertialOdometry: the initial state is not ok (" +
                                std::string(toString(state.status)) + ")");
  config_.validate();
}

std::vector<OdometrySample> DopplerInertialOdometry::run(
    const std::vector<ImuSample>& imu, const std::vector<LidarFrame>& frames) const {
  const InitialState& s = state_;
  const Extrinsics& ext = config_.extrinsics;
  // The state refers to an IMU sample (the window end): start there.
  const auto it = std::lower_bound(imu.begin(), imu.end(), s.timestamp - 1e-9,
                                   [](const ImuSample& a, double t) { return a.t < t; });
  if (it == imu.end() || it + 1 == imu.end())
    throw std::invalid_argument("DopplerInertialOdometry: no IMU data after the state time");
  const auto k_first = static_cast<std::size_t>(it - imu.begin());
  const double t_ref = imu[k_first].t;  // internal times are relative (precision)

  // Velocimeter restarted from the state: gyro bias and its uncertainty from the state, the LiDAR
  // velocity from the body velocity through the extrinsics (v_b = R_bl v_l + p_bl x omega_b).
  VelocimeterParams vp = velocimeterParams(config_);
  vp.gyro_bias_prior = s.b_g;
  vp.gyro_bias_sigma0 =
      std::max(1e-5, std::sqrt(s.cov.block<3, 3>(kBg, kBg).diagonal().maxCoeff()));
  Velocimeter velocimeter(vp, ext);
  const Mat3 R_wb0 = s.q_wb.toRotationMatrix();
  const Vec3 omega0 = imu[k_first].gyro - s.b_g;
  const Vec3 v_l0 = ext.R_bl.transpose() * (s.v_b() - ext.p_bl.cross(omega0));
  const Mat3 cov_v_b = R_wb0.transpose() * s.cov.block<3, 3>(kVel, kVel) * R_wb0;
  const Mat3 cov_v_l = ext.R_bl.transpose() * cov_v_b * ext.R_bl;
  velocimeter.start(0.0, v_l0, cov_v_l, imu[k_first].gyro);
  velocimeter.setOmegaSlope((imu[k_first + 1].gyro - imu[k_first].gyro) /
                            (imu[k_first + 1].t - imu[k_first].t));
  PoseIntegrator integrator;  // pose relative to the body at the state time
  integrator.reset(0.0, velocimeter.omega_b(), velocimeter.v_b());

  // Accelerometer-aided propagation: a_b = f - b_a + R_wb^T g_w and its slope to the next sample
  // (gravity in b turns as dg_b/dt = -omega x g_b).
  auto setAcceleration = [&](std::size_t k) {
    detail::setAidedAcceleration(velocimeter, imu, k, s.b_a,
                                 (R_wb0 * integrator.R_wb()).transpose() * s.g_w);
  };
  std::vector<OdometrySample> out;
  out.reserve(imu.size() - k_first);
  auto record = [&](double t) {
    OdometrySample o;
    o.t = t;
    o.q_wb = (s.q_wb * integrator.q_wb()).normalized();
    o.p_w = s.p_w + R_wb0 * integrator.p_w();
    o.v_b = velocimeter.v_b();
    o.omega_b = velocimeter.omega_b();
    out.push_back(o);
  };
  if (accel_aided_) setAcceleration(k_first);
  record(t_ref);

  // Point stride: as configured, or the one that brings the point rate closest to max_point_rate.
  const DopplerParams& dp = config_.doppler;
  const int stride = dp.point_stride > 0 ? dp.point_stride
                                         : detail::automaticPointStride(frames, dp.max_point_rate);

  // Points and gyro samples in time order: a point is processed before the gyro sample after it.
  std::size_t f = 0, p = 0, counter = 0;
  const detail::UsablePoints usable(dp);
  auto nextPoint = [&]() -> const DopplerPoint* {
    while (f < frames.size() && p >= frames[f].points.size()) {
      ++f;
      p = 0;
    }
    return f < frames.size() ? &frames[f].points[p] : nullptr;
  };
  for (std::size_t k = k_first + 1; k < imu.size(); ++k) {
    const double tg = imu[k].t - t_ref;
    for (const DopplerPoint* pt = nextPoint(); pt; pt = nextPoint()) {
      const double tp = frames[f].stamp - t_ref + pt->time_offset;
      if (tp > tg) break;
      ++p;
      if (tp <= 0) continue;  // part of the initialization window
      const bool use = counter == 0;
      counter = (counter + 1) % static_cast<std::size_t>(stride);
      if (!use || !usable(*pt)) continue;
      velocimeter.propagate(tp);
      velocimeter.updateDoppler(pt->p_l, pt->doppler);
      integrator.integrate(tp, velocimeter.omega_b(), velocimeter.v_b());
    }
    velocimeter.propagate(tg);
    detail::updateGyroAt(velocimeter, imu, k);
    integrator.integrate(tg, velocimeter.omega_b(), velocimeter.v_b());
    if (accel_aided_) setAcceleration(k);
    record(imu[k].t);
  }
  return out;
}

}  // namespace freeinit
