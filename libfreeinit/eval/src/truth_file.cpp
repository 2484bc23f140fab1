#include <freeinit/eval/truth_file.h>
#include <freeinit/io/atomic_file.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <ostream>
#include <sstream>
#include <stdexcept>

namespace freeinit::eval {
namespace {

constexpr const char* kHeader =
    "t,p_x,p_y,p_z,q_w,q_x,q_y,q_z,v_x,v_y,v_z,omega_x,omega_y,omega_z,b_g_x,b_g_y,b_g_z,b_a_x,"
    "b_a_y,b_a_z,g_x,g_y,g_z";
constexpr int kColumns = 23;

}  // namespace

void writeTruthCsv(const std::string& path, const std::vector<StateTruth>& truth) {
  writeFileAtomically(path, [&](std::ostream& o) {
    o << kHeader << "\n";
    for (const auto& s : truth) {
      o << std::fixed << std::setprecision(9) << s.t << std::defaultfloat << std::setprecision(12);
      o << "," << s.p_w.x() << "," << s.p_w.y() << "," << s.p_w.z();
      o << "," << s.q_wb.w() << "," << s.q_wb.x() << "," << s.q_wb.y() << "," << s.q_wb.z();
      for (const Vec3* v : {&s.v_w, &s.omega_b, &s.b_g, &s.b_a, &s.g_w})
        o << "," << v->x() << "," << v->y() << "," << v->z();
      o << "\n";
    }
  });
}

std::vector<StateTruth> readTruthCsv(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw std::runtime_error(path + ": cannot open");
  std::string line;
  std::getline(f, line);
  if (line.rfind("t,", 0) != 0) throw std::runtime_error(path + ": line 1: not a truth CSV header");
  std::vector<StateTruth> out;
  for (int ln = 2; std::getline(f, line); ++ln) {
    if (line.empty()) continue;
    const std::string where = path + ": line " + std::to_string(ln);
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream is(line);
    double v[kColumns];
    for (double& x : v) {
      if (!(is >> x))
        throw std::runtime_error(where + ": expected " + std::to_string(kColumns) + " numbers");
      if (!std::isfinite(x)) throw std::runtime_error(where + ": a value is not finite");
    }
    StateTruth s;
    s.t = v[0];
    s.p_w = Vec3(v[1], v[2], v[3]);
    const Quat q(v[4], v[5], v[6], v[7]);
    if (!(q.norm() > 0.5 && q.norm() < 1.5))
      throw std::runtime_error(where + ": the attitude quaternion is not a unit quaternion");
    s.q_wb = q.normalized();
    s.v_w = Vec3(v[8], v[9], v[10]);
    s.omega_b = Vec3(v[11], v[12], v[13]);
    s.b_g = Vec3(v[14], v[15], v[16]);
    s.b_a = Vec3(v[17], v[18], v[19]);
    s.g_w = Vec3(v[20], v[21], v[22]);
    if (!out.empty() && !(s.t > out.back().t))
      throw std::runtime_error(where + ": time does not increase");
    out.push_back(s);
  }
  if (out.empty()) throw std::runtime_error(path + ": no samples");
  return out;
}

}  // namespace freeinit::eval
