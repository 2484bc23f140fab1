#include <freeinit/mrpt/output_writers.h>

#include <iomanip>

namespace freeinit::mrpt_glue {

namespace {
void vec(std::ostream& o, const Vec3& v) { o << v.x() << " " << v.y() << " " << v.z(); }
}  // namespace

void writeInitialStateIni(const std::string& path, const InitialState& s) {
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
             "(z up), meters\nelement vertex "
          << points.size()
          << "\nproperty float x\nproperty float y\nproperty float z\nproperty float "
             "intensity\nend_header\n";
        for (const auto& p : points) {
          const float rec[4] = {p.p_w.x(), p.p_w.y(), p.p_w.z(), p.intensity};
          o.write(reinterpret_cast<const char*>(rec), sizeof(rec));
        }
      },
      true);
}

}  // namespace freeinit::mrpt_glue
