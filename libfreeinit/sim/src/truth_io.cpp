#include <freeinit/sim/truth_io.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>

namespace freeinit::sim {
namespace {

template <typename WriteLine>
void writeSampled(double t_begin, double t_end, double rate_hz, const std::string& path,
                  const char* header, WriteLine&& write_line) {
  if (!(rate_hz > 0) || !(t_end >= t_begin)) {
    throw std::invalid_argument("freeinit::sim: need rate_hz > 0 and t_end >= t_begin");
  }
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp);
    if (!out) throw std::runtime_error("freeinit::sim: cannot open " + tmp);
    out.precision(17);
    if (header != nullptr) out << header << '\n';
    const long n = static_cast<long>(std::floor((t_end - t_begin) * rate_hz + 1e-9)) + 1;
    for (long k = 0; k < n; ++k) write_line(out, t_begin + static_cast<double>(k) / rate_hz);
    out.flush();
    if (!out) throw std::runtime_error("freeinit::sim: write failed on " + tmp);
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw std::runtime_error("freeinit::sim: cannot rename " + tmp + " to " + path);
  }
}

}  // namespace

void writeTumPoses(const Trajectory& trajectory, double t_begin, double t_end, double rate_hz,
                   const std::string& path) {
  writeSampled(t_begin, t_end, rate_hz, path, nullptr, [&](std::ofstream& out, double t) {
    const TruthState s = trajectory.at(t);
    const Quat q(s.R_wb);
    out << t << ' ' << s.p_w.x() << ' ' << s.p_w.y() << ' ' << s.p_w.z() << ' ' << q.x() << ' '
        << q.y() << ' ' << q.z() << ' ' << q.w() << '\n';
  });
}

void writeTruthCsv(const Trajectory& trajectory, double t_begin, double t_end, double rate_hz,
                   const std::string& path) {
  writeSampled(t_begin, t_end, rate_hz, path,
               "t,qw,qx,qy,qz,px,py,pz,vx,vy,vz,ax,ay,az,wx,wy,wz,alx,aly,alz",
               [&](std::ofstream& out, double t) {
                 const TruthState s = trajectory.at(t);
                 const Quat q(s.R_wb);
                 out << t << ',' << q.w() << ',' << q.x() << ',' << q.y() << ',' << q.z();
                 for (const Vec3* v : {&s.p_w, &s.v_w, &s.a_w, &s.omega_b, &s.alpha_b}) {
                   out << ',' << v->x() << ',' << v->y() << ',' << v->z();
                 }
                 out << '\n';
               });
}

}  // namespace freeinit::sim
