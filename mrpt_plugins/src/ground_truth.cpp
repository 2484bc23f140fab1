#include <freeinit/mrpt/ground_truth.h>
#include <freeinit/mrpt/output_writers.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace freeinit::mrpt_glue {

namespace {
constexpr const char* kHeader =
    "t,p_x,p_y,p_z,q_w,q_x,q_y,q_z,v_x,v_y,v_z,omega_x,omega_y,omega_z,b_g_x,b_g_y,b_g_z,b_a_x,"
    "b_a_y,b_a_z,g_x,g_y,g_z";
constexpr int kColumns = 23;
}  // namespace

std::string truthPathFor(const std::string& rawlog_path) {
  std::string p = rawlog_path;
  const std::string ext = ".rawlog";
  if (p.size() > ext.size() && p.compare(p.size() - ext.size(), ext.size(), ext) == 0)
    p.erase(p.size() - ext.size());
  return p + ".truth.csv";
}

void writeTruthCsv(const std::string& path, const std::vector<TruthSample>& truth) {
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

std::vector<TruthSample> readTruthCsv(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw std::runtime_error(path + ": cannot open");
  std::string line;
  std::getline(f, line);
  if (line.rfind("t,", 0) != 0) throw std::runtime_error(path + ": line 1: not a truth CSV header");
  std::vector<TruthSample> out;
  for (int ln = 2; std::getline(f, line); ++ln) {
    if (line.empty()) continue;
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream is(line);
    double v[kColumns];
    for (double& x : v) {
      if (!(is >> x))
        throw std::runtime_error(path + ": line " + std::to_string(ln) + ": expected " +
                                 std::to_string(kColumns) + " numbers");
    }
    TruthSample s;
    s.t = v[0];
    s.p_w = Vec3(v[1], v[2], v[3]);
    s.q_wb = Quat(v[4], v[5], v[6], v[7]).normalized();
    s.v_w = Vec3(v[8], v[9], v[10]);
    s.omega_b = Vec3(v[11], v[12], v[13]);
    s.b_g = Vec3(v[14], v[15], v[16]);
    s.b_a = Vec3(v[17], v[18], v[19]);
    s.g_w = Vec3(v[20], v[21], v[22]);
    out.push_back(s);
  }
  if (out.empty()) throw std::runtime_error(path + ": no samples");
  return out;
}

std::optional<TruthSample> truthAt(const std::vector<TruthSample>& truth, double t) {
  if (truth.empty() || t < truth.front().t - 1e-6 || t > truth.back().t + 1e-6) return std::nullopt;
  auto it = std::lower_bound(truth.begin(), truth.end(), t,
                             [](const TruthSample& s, double x) { return s.t < x; });
  if (it == truth.begin()) return truth.front();
  if (it == truth.end()) return truth.back();
  const TruthSample& a = *(it - 1);
  const TruthSample& b = *it;
  const double u = (t - a.t) / (b.t - a.t);
  TruthSample s = a;
  s.t = t;
  s.q_wb = a.q_wb.slerp(u, b.q_wb);
  s.p_w = (1 - u) * a.p_w + u * b.p_w;
  s.v_w = (1 - u) * a.v_w + u * b.v_w;
  s.omega_b = (1 - u) * a.omega_b + u * b.omega_b;
  return s;
}

TruthErrors compareWithTruth(const InitialState& s, const std::vector<TruthSample>& truth) {
  const auto gt = truthAt(truth, s.timestamp);
  if (!gt) {
    std::ostringstream os;
    os << std::fixed << "the state time " << s.timestamp << " is outside the ground truth ["
       << truth.front().t << ", " << truth.back().t << "]";
    throw std::runtime_error(os.str());
  }
  TruthErrors e;
  e.t = s.timestamp;
  const Mat3 R_bw = gt->q_wb.conjugate().toRotationMatrix();
  e.v_b_true = R_bw * gt->v_w;
  e.velocity = (s.v_b() - e.v_b_true).norm();
  const Vec3 g_b_true = R_bw * gt->g_w;
  const double c = std::clamp(s.g_b().normalized().dot(g_b_true.normalized()), -1.0, 1.0);
  e.gravity_deg = std::acos(c) * 180.0 / M_PI;
  e.gyro_bias = (s.b_g - gt->b_g).norm();
  e.accel_bias = (s.b_a - gt->b_a).norm();
  return e;
}

void writeTruthErrors(const std::string& path, const TruthErrors& e) {
  writeFileAtomically(path, [&](std::ostream& o) {
    o << std::setprecision(9);
    o << "[errors_wrt_ground_truth]\n";
    o << "timestamp       = " << std::fixed << e.t << std::defaultfloat << "\n";
    o << "velocity        = " << e.velocity << " ; [m/s] |v_b - v_b_true|\n";
    o << "gravity_deg     = " << e.gravity_deg << " ; [deg] gravity direction in the body frame\n";
    o << "gyro_bias       = " << e.gyro_bias << " ; [rad/s] |b_g - b_g_true|\n";
    o << "accel_bias      = " << e.accel_bias << " ; [m/s^2] |b_a - b_a_true|\n";
  });
}

}  // namespace freeinit::mrpt_glue
