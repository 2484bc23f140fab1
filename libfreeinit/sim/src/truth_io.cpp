#include <freeinit/io/atomic_file.h>
#include <freeinit/sim/truth_io.h>

#include <cmath>
#include <ostream>
#include <stdexcept>

namespace freeinit::sim {
namespace {

template <typename WriteLine>
void writeSampled(double t_begin, double t_end, double rate_hz, const std::string& path,
                  const char* header, WriteLine&& write_line) {
  if (!(rate_hz > 0) || !(t_end >= t_begin)) {
    throw std::invalid_argument("freeinit::sim: need rate_hz > 0 and t_end >= t_begin");
  }
  writeFileAtomically(path, [&](std::ostream& out) {
    out.precision(17);
    if (header != nullptr) out << header << '\n';
    const long n = static_cast<long>(std::floor((t_end - t_begin) * rate_hz + 1e-9)) + 1;
    for (long k = 0; k < n; ++k) write_line(out, t_begin + static_cast<double>(k) / rate_hz);
  });
}

}  // namespace

void writeTumPoses(const Trajectory& trajectory, double t_begin, double t_end, double rate_hz,
                   const std::string& path) {
  writeSampled(t_begin, t_end, rate_hz, path, nullptr, [&](std::ostream& out, double t) {
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
               [&](std::ostream& out, double t) {
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
