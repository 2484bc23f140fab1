#include <freeinit/sim/evaluation.h>

#include <algorithm>
#include <cmath>

namespace freeinit::sim {

eval::StateTruth stateTruth(const Recording& rec, double t) {
  const TruthState s = rec.truth(t);
  eval::StateTruth gt;
  gt.t = t;
  gt.q_wb = Quat(s.R_wb).normalized();
  gt.p_w = s.p_w;
  gt.v_w = s.v_w;
  gt.omega_b = s.omega_b;
  gt.b_g = rec.b_g;
  gt.b_a = rec.b_a;
  gt.g_w = rec.g_w;
  return gt;
}

InitErrors evaluate(const InitialState& state, const Recording& rec) {
  InitErrors err;
  if (!state.ok()) return err;
  err.valid = true;
  const eval::StateTruth truth = stateTruth(rec, state.timestamp);
  const eval::StateErrors e = eval::stateErrors(state, truth);
  err.vel_b = e.velocity;
  err.vel_b_true_norm = e.speed;
  err.gravity_deg = e.gravity_deg;
  err.gyro_bias = e.gyro_bias;
  err.accel_bias = e.accel_bias;
  err.accel_bias_vector = e.accel_bias_vector;
  err.accel_bias_vertical = e.accel_bias_vertical;
  err.gravity_deg_from_bias = e.gravity_deg_from_bias;
  const eval::Nees n = eval::stateNees(state, truth);
  err.nees_vel_b = n.velocity;
  err.nees_tilt = n.tilt;
  err.nees_gyro_bias = n.gyro_bias;
  err.nees_accel_bias = n.accel_bias;
  return err;
}

double gravityErrorFromBiasDeg(const Vec3& b_a_true, const Vec3& g_b_true) {
  return eval::gravityErrorFromBiasDeg(b_a_true, g_b_true);
}

eval::BoundModel boundModel(const Recording& rec, const FreeInitConfig& config) {
  eval::BoundModel m;
  m.extrinsics = rec.extrinsics;
  m.g_w = rec.g_w;
  // The noise the simulator drew (simulateImu: per axis; every point's Doppler the same), never
  // the figures the estimator was handed in `config`.
  m.doppler_sigma = rec.config.doppler_sigma;
  m.gyro_sigma = rec.config.gyro_sigma;
  m.accel_sigma = rec.config.accel_sigma;
  m.gyro_axis_scale = rec.config.gyro_sigma_scale;
  m.accel_axis_scale = rec.config.accel_sigma_scale;
  m.gyro_bias_prior_sigma = config.imu.gyro_bias_sigma0;
  m.accel_bias_prior_sigma = config.imu.accel_bias_prior_sigma;
  return m;
}

NoiseFigures trueNoise(const Recording& rec) {
  const double root3 = std::sqrt(3.0);
  return {rec.config.gyroSigmaPerAxis().norm() / root3,
          rec.config.accelSigmaPerAxis().norm() / root3, rec.config.doppler_sigma};
}

eval::Bound cramerRaoBound(const Recording& rec, const eval::BoundModel& model, double t_begin,
                           double t_end) {
  constexpr double kTimeTolerance = 1e-9;  // [s] the window's ends are IMU sample times
  std::vector<eval::KinematicTruth> nodes;
  for (const ImuSample& m : rec.imu) {
    if (m.t < t_begin - kTimeTolerance || m.t > t_end + kTimeTolerance) continue;
    const TruthState s = rec.truth(m.t);
    nodes.push_back({m.t, s.R_wb, s.v_w, s.a_w, s.omega_b});
  }
  if (nodes.size() < 2) {
    eval::Bound b;
    b.message = "fewer than 2 IMU samples in the window";
    return b;
  }
  eval::CramerRaoBound bound(model, std::move(nodes));
  const double t0 = bound.nodes().front().t, t1 = bound.nodes().back().t;
  for (std::size_t f = 0; f < rec.frames.size(); ++f) {
    const LidarFrame& frame = rec.frames[f];
    if (frame.points.empty() || rec.pointTime(frame, frame.points.front()) > t1) continue;
    if (rec.pointTime(frame, frame.points.back()) < t0) continue;
    const std::vector<PointLabel>& labels = rec.labels[f];
    for (std::size_t i = 0; i < frame.points.size(); ++i) {
      if (labels[i] != PointLabel::Static) continue;
      const DopplerPoint& p = frame.points[i];
      const double t = rec.pointTime(frame, p);  // the true (IMU-clock) time
      if (t < t0 || t > t1) continue;
      bound.addDoppler(t, p.p_l.cast<double>());
    }
  }
  return bound.compute();
}

eval::Bound cramerRaoBound(const Recording& rec, const FreeInitConfig& config,
                           const InitResult& result) {
  if (!result.state.ok() || result.trajectory.empty()) {
    eval::Bound b;
    b.message = "the result has no state or no trajectory";
    return b;
  }
  return cramerRaoBound(rec, boundModel(rec, config), result.trajectory.front().t,
                        result.state.timestamp);
}

}  // namespace freeinit::sim
