#include <freeinit/doppler_inertial_odometry.h>
#include <freeinit/pose_integrator.h>
#include <freeinit/velocimeter.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "velocimeter_steps.h"

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
  const auto k0 = static_cast<std::size_t>(it - imu.begin());
  const double t_ref = imu[k0].t;  // internal times are relative (precision)

  // Velocimeter restarted from the state: gyro bias and its uncertainty from the state, the LiDAR
  // velocity from the body velocity through the extrinsics (v_b = R_bl v_l + p_bl x omega_b).
  VelocimeterParams vp = config_.velocimeter;
  vp.gyro_bias_prior = s.b_g;
  vp.gyro_bias_sigma0 =
      std::max(1e-5, std::sqrt(s.cov.block<3, 3>(kBg, kBg).diagonal().maxCoeff()));
  Velocimeter div(vp, ext);
  const Mat3 R_wb0 = s.q_wb.toRotationMatrix();
  const Vec3 omega0 = imu[k0].gyro - s.b_g;
  const Vec3 v_l0 = ext.R_bl.transpose() * (s.v_b() - ext.p_bl.cross(omega0));
  const Mat3 cov_v_b = R_wb0.transpose() * s.cov.block<3, 3>(kVel, kVel) * R_wb0;
  const Mat3 cov_v_l = ext.R_bl.transpose() * cov_v_b * ext.R_bl;
  div.start(0.0, v_l0, cov_v_l, imu[k0].gyro);
  div.setOmegaSlope((imu[k0 + 1].gyro - imu[k0].gyro) / (imu[k0 + 1].t - imu[k0].t));
  PoseIntegrator integrator;  // pose relative to the body at the state time
  integrator.reset(0.0, div.omega_b(), div.v_b());

  // Accelerometer-aided propagation: a_b = f - b_a + R_wb^T g_w and its slope to the next sample
  // (gravity in b turns as dg_b/dt = -omega x g_b).
  auto setAcceleration = [&](std::size_t k) {
    detail::setAidedAcceleration(div, imu, k, s.b_a,
                                 (R_wb0 * integrator.R_wb()).transpose() * s.g_w);
  };
  std::vector<OdometrySample> out;
  out.reserve(imu.size() - k0);
  auto record = [&](double t) {
    OdometrySample o;
    o.t = t;
    o.q_wb = (s.q_wb * integrator.q_wb()).normalized();
    o.p_w = s.p_w + R_wb0 * integrator.p_w();
    o.v_b = div.v_b();
    o.omega_b = div.omega_b();
    out.push_back(o);
  };
  if (accel_aided_) setAcceleration(k0);
  record(t_ref);

  // Point stride: as configured, or the one that brings the point rate closest to max_point_rate.
  const int stride = vp.point_stride > 0 ? vp.point_stride
                                         : detail::automaticPointStride(frames, vp.max_point_rate);

  // Points and gyro samples in time order: a point is processed before the gyro sample after it.
  std::size_t f = 0, p = 0, counter = 0;
  auto nextPoint = [&]() -> const DopplerPoint* {
    while (f < frames.size() && p >= frames[f].points.size()) {
      ++f;
      p = 0;
    }
    return f < frames.size() ? &frames[f].points[p] : nullptr;
  };
  for (std::size_t k = k0 + 1; k < imu.size(); ++k) {
    const double tg = imu[k].t - t_ref;
    for (const DopplerPoint* pt = nextPoint(); pt; pt = nextPoint()) {
      const double tp = frames[f].stamp - t_ref + pt->time_offset;
      if (tp > tg) break;
      ++p;
      if (tp <= 0) continue;  // part of the initialization window
      const bool use = counter == 0;
      counter = (counter + 1) % static_cast<std::size_t>(stride);
      if (!use || !detail::usablePoint(*pt, vp)) continue;
      div.propagate(tp);
      div.updateDoppler(pt->p_l, pt->doppler);
      integrator.integrate(tp, div.omega_b(), div.v_b());
    }
    div.propagate(tg);
    detail::updateGyroAt(div, imu, k);
    integrator.integrate(tg, div.omega_b(), div.v_b());
    if (accel_aided_) setAcceleration(k);
    record(imu[k].t);
  }
  return out;
}

}  // namespace freeinit
