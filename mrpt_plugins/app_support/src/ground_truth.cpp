#include <freeinit/app_support/ground_truth.h>
#include <freeinit/app_support/output_writers.h>
#include <freeinit/eval/state_errors.h>
#include <freeinit/eval/truth_file.h>

#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace freeinit::app_support {

std::string truthPathFor(const std::string& input_path) {
  std::string p = input_path;
  // A rosbag2 folder given as "rec/": the truth sits beside the folder, not in it.
  while (p.size() > 1 && p.back() == '/') p.pop_back();
  for (const std::string ext : {".rawlog", ".mcap", ".bag", ".db3"})
    if (p.size() > ext.size() && p.compare(p.size() - ext.size(), ext.size(), ext) == 0) {
      p.erase(p.size() - ext.size());
      break;
    }
  return p + ".truth.csv";
}

void writeTruthCsv(const std::string& path, const std::vector<TruthSample>& truth) {
  eval::writeTruthCsv(path, truth);
}

std::vector<TruthSample> readTruthCsv(const std::string& path) { return eval::readTruthCsv(path); }

std::optional<TruthSample> truthAt(const std::vector<TruthSample>& truth, double t) {
  return eval::interpolateTruth(truth, t);
}

TruthErrors compareWithTruth(const InitialState& s, const std::vector<TruthSample>& truth) {
  const auto gt = truthAt(truth, s.timestamp);
  if (!gt) {
    std::ostringstream os;
    os << std::fixed << "the state time " << s.timestamp << " is outside the ground truth ["
       << truth.front().t << ", " << truth.back().t << "]";
    throw std::runtime_error(os.str());
  }
  const eval::StateErrors err = eval::stateErrors(s, *gt);
  const eval::Nees nees = eval::stateNees(s, *gt);
  TruthErrors e;
  e.t = s.timestamp;
  e.v_b_true = err.v_b_true;
  e.velocity = err.velocity;
  e.gravity_deg = err.gravity_deg;
  e.gyro_bias = err.gyro_bias;
  e.accel_bias = err.accel_bias;
  e.nees_velocity = nees.velocity;
  e.nees_tilt = nees.tilt;
  e.nees_gyro_bias = nees.gyro_bias;
  e.nees_accel_bias = nees.accel_bias;
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
    o << "nees_velocity   = " << e.nees_velocity << " ; [-] of the state's covariance, 3 dof\n";
    o << "nees_tilt       = " << e.nees_tilt << " ; [-] gravity direction, 2 dof\n";
    o << "nees_gyro_bias  = " << e.nees_gyro_bias << " ; [-] 3 dof\n";
    o << "nees_accel_bias = " << e.nees_accel_bias << " ; [-] 3 dof\n";
  });
}

}  // namespace freeinit::app_support
