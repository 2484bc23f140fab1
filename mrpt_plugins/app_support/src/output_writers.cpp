#include <freeinit/app_support/output_writers.h>
#include <freeinit/rotation.h>

#include <cmath>
#include <iomanip>
#include <tuple>

namespace freeinit::app_support {

namespace {
void vec(std::ostream& o, const Vec3& v) { o << v.x() << " " << v.y() << " " << v.z(); }
}  // namespace

StateVerdict verdictOf(const InitResult& r, double doppler_sigma) {
  const InitialState& s = r.state;
  StateVerdict v;
  const Mat3 R = s.q_wb.toRotationMatrix();
  // Body velocity v_b = R^T v_w with R = R^ Exp(dtheta): dv_b = R^T dv_w + [v_b]x dtheta.
  Eigen::Matrix<double, 3, 18> A = Eigen::Matrix<double, 3, 18>::Zero();
  A.block<3, 3>(0, kTheta) = skew(s.v_b());
  A.block<3, 3>(0, kVel) = R.transpose();
  v.sigma_v_b = (A * s.cov * A.transpose()).diagonal().cwiseMax(0.0).cwiseSqrt();
  // Gravity in the body frame turns by dtheta; its direction by the part of dtheta across it.
  const Vec3 u = s.g_b().normalized();
  const Mat3 across = Mat3::Identity() - u * u.transpose();
  const double tilt_var = (across * s.cov.block<3, 3>(kTheta, kTheta) * across).trace();
  v.sigma_tilt_deg = std::sqrt(std::max(tilt_var, 0.0)) * 180.0 / 3.14159265358979323846;
  v.sigma_b_g = s.cov.block<3, 3>(kBg, kBg).diagonal().cwiseMax(0.0).cwiseSqrt();
  v.sigma_b_a = s.cov.block<3, 3>(kBa, kBa).diagonal().cwiseMax(0.0).cwiseSqrt();
  v.window_s = r.diag.window_duration;
  v.window_frames = r.diag.frames_in_window;
  v.points_used = r.diag.points_used;
  v.residual_rms = r.diag.doppler_residual_rms;
  v.doppler_sigma = doppler_sigma;
  v.node_residual_ratio = r.diag.node_residual_ratio;
  v.time_offset = s.time_offset;
  v.time_offset_sigma = s.time_offset_sigma;
  v.time_offset_estimated = s.time_offset_estimated;
  v.noise = r.diag.noise;
  v.imu_faults = r.diag.imu_faults;
  v.imu_gap_s = r.diag.imu_gap_s;
  return v;
}

void printVerdict(std::ostream& log, const StateVerdict& v) {
  const auto flags = log.flags();
  const auto precision = log.precision();
  log << std::setprecision(2) << std::scientific << "  sigma: v_b " << v.sigma_v_b.x() << " "
      << v.sigma_v_b.y() << " " << v.sigma_v_b.z() << " m/s, b_g " << v.sigma_b_g.x() << " "
      << v.sigma_b_g.y() << " " << v.sigma_b_g.z() << " rad/s, b_a " << v.sigma_b_a.x() << " "
      << v.sigma_b_a.y() << " " << v.sigma_b_a.z() << " m/s^2, gravity direction " << std::fixed
      << v.sigma_tilt_deg << " deg\n"
      << std::setprecision(3) << "  window: " << v.window_s << " s, " << v.window_frames
      << " frames; Doppler residual RMS " << std::setprecision(4) << v.residual_rms
      << " m/s (configured noise " << v.doppler_sigma << " m/s)\n";
  // Clocks declared synchronized ([joint] time_offset_sigma = 0): no offset line.
  if (v.time_offset_estimated || v.time_offset_sigma > 0)
    log << std::setprecision(2) << "  LiDAR-IMU clock offset " << 1e3 * v.time_offset
        << " ms, sigma " << 1e3 * v.time_offset_sigma << " ms ("
        << (v.time_offset_estimated ? "estimated from the motion" : "its prior: not observed")
        << ")\n";
  const std::tuple<const NoiseUsed*, const char*, const char*> noises[] = {
      {&v.noise.gyro, "gyro", "rad/s"},
      {&v.noise.accel, "accel", "m/s^2"},
      {&v.noise.doppler, "Doppler", "m/s"}};
  if (v.noise.gyro.value > 0) {
    log << "  noise used:";
    const char* sep = " ";
    for (const auto& [n, name, unit] : noises) {
      log << sep << name << " " << std::setprecision(3) << std::defaultfloat << n->value;
      if (n->rel_sigma > 0) log << " +- " << std::setprecision(2) << 100.0 * n->rel_sigma << " %";
      log << " " << unit << " (" << toString(n->source) << ", configured " << std::setprecision(3)
          << n->declared << ")";
      sep = "; ";
    }
    log << "\n";
  }
  log.flags(flags);
  log.precision(precision);
}

void writeInitialStateIni(const std::string& path, const InitialState& s,
                          const StateVerdict* verdict) {
  writeFileAtomically(path, [&](std::ostream& o) {
    o << std::setprecision(17);
    o << "[initial_state]\n";
    o << "status    = " << (s.ok() ? std::string("ok") : std::string(toString(s.status)));
    if (!s.ok() && !s.message.empty()) o << " ; " << s.message;
    o << "\n";
    o << "timestamp = " << std::fixed << std::setprecision(9) << s.timestamp << std::defaultfloat
      << std::setprecision(17) << "\n";
    o << "q_wb      = " << s.q_wb.w() << " " << s.q_wb.x() << " " << s.q_wb.y() << " " << s.q_wb.z()
      << "\n";
    o << "p_w       = ";
    vec(o, s.p_w);
    o << "\nv_w       = ";
    vec(o, s.v_w);
    o << "\nb_g       = ";
    vec(o, s.b_g);
    o << "\nb_a       = ";
    vec(o, s.b_a);
    o << "\ng_w       = ";
    vec(o, s.g_w);
    o << "\ncov       =";
    for (int i = 0; i < 18; ++i)
      for (int j = 0; j < 18; ++j) o << " " << s.cov(i, j);
    o << "\n";
    if (s.ok())
      o << "time_offset = " << s.time_offset << " " << s.time_offset_sigma << " "
        << (s.time_offset_estimated ? "estimated" : "prior") << "\n";
    if (verdict != nullptr && s.ok()) {
      const StateVerdict& v = *verdict;
      o << std::setprecision(6) << "sigma_v_b            = ";
      vec(o, v.sigma_v_b);
      o << "\nsigma_tilt_deg       = " << v.sigma_tilt_deg << "\nsigma_b_g            = ";
      vec(o, v.sigma_b_g);
      o << "\nsigma_b_a            = ";
      vec(o, v.sigma_b_a);
      o << "\nwindow_s             = " << v.window_s
        << "\nwindow_frames        = " << v.window_frames
        << "\npoints_used          = " << v.points_used
        << "\ndoppler_residual_rms = " << v.residual_rms
        << "\ndoppler_sigma        = " << v.doppler_sigma
        << "\nnode_chi2_per_dof    = " << v.node_residual_ratio
        << "\nimu_faults           = " << v.imu_faults << "\nimu_gap_s            = " << v.imu_gap_s
        << "\n";
      // The white noise used: value, relative 1-sigma, source; the configured one beside.
      const std::tuple<const NoiseUsed*, const char*, const char*> noises[] = {
          {&v.noise.gyro, "noise_gyro           = ", "[rad/s] per sample"},
          {&v.noise.accel, "noise_accel          = ", "[m/s^2] per sample"},
          {&v.noise.doppler, "noise_doppler        = ", "[m/s] per return"}};
      for (const auto& [n, key, unit] : noises)
        if (n->value > 0)
          o << key << n->value << " " << n->rel_sigma << " " << toString(n->source) << " ; " << unit
            << " used, relative sigma, source (configured " << n->declared << ")\n";
      o << std::setprecision(17);
    }
    o << "warnings  = " << s.warnings.size() << "\n";
    for (std::size_t i = 0; i < s.warnings.size(); ++i)
      o << "warning_" << i + 1 << " = " << s.warnings[i] << "\n";
  });
}

void writeTum(const std::string& path, const std::vector<PoseSample>& trajectory) {
  writeFileAtomically(path, [&](std::ostream& o) {
    o << "# timestamp x y z qx qy qz qw  (body = IMU frame in the gravity-aligned world)\n";
    for (const auto& p : trajectory) {
      o << std::fixed << std::setprecision(9) << p.t << std::setprecision(9) << " " << p.p_w.x()
        << " " << p.p_w.y() << " " << p.p_w.z() << " " << p.q_wb.x() << " " << p.q_wb.y() << " "
        << p.q_wb.z() << " " << p.q_wb.w() << "\n";
    }
  });
}

void writeVelocityCsv(const std::string& path, const std::vector<VelocitySample>& v) {
  writeFileAtomically(path, [&](std::ostream& o) {
    o << "t,v_l_x,v_l_y,v_l_z,v_b_x,v_b_y,v_b_z,omega_b_x,omega_b_y,omega_b_z,b_g_x,b_g_y,b_g_z,"
         "sigma_v_b_x,sigma_v_b_y,sigma_v_b_z,stationary\n";
    for (const auto& s : v) {
      o << std::fixed << std::setprecision(9) << s.t << std::defaultfloat << std::setprecision(9);
      for (const Vec3* x : {&s.v_l, &s.v_b, &s.omega_b, &s.b_g, &s.sigma_v_b})
        o << "," << x->x() << "," << x->y() << "," << x->z();
      o << "," << (s.stationary ? 1 : 0) << "\n";
    }
  });
}

void writePly(const std::string& path, const std::vector<MapPoint>& points) {
  writeFileAtomically(
      path,
      [&](std::ostream& o) {
        o << "ply\nformat binary_little_endian 1.0\ncomment Free-Init static map, world frame "
             "(z up), meters\ncomment doppler: the measured range rate [m/s], negative when "
             "approaching\ncomment time: the return's time minus the initial state's timestamp "
             "(initial_state.ini) [s]\nelement vertex "
          << points.size()
          << "\nproperty float x\nproperty float y\nproperty float z\nproperty float "
             "intensity\nproperty float doppler\nproperty float time\nend_header\n";
        for (const auto& p : points) {
          const float rec[6] = {p.p_w.x(), p.p_w.y(), p.p_w.z(), p.intensity, p.doppler, p.time};
          o.write(reinterpret_cast<const char*>(rec), sizeof(rec));
        }
      },
      true);
}

}  // namespace freeinit::app_support
