// Ground truth beside a recording ("<name>.truth.csv", written by freeinit-sim) and the comparison
// of an initial state against it, through the evaluation module (freeinit/eval): only
// frame-independent quantities are compared (the body-frame velocity, the gravity direction in the
// body frame and the biases), with the NEES of the state's covariance.
#pragma once

#include <freeinit/eval/state_truth.h>
#include <freeinit/initial_state.h>

#include <optional>
#include <string>
#include <vector>

namespace freeinit::app_support {

/// The evaluation's truth type (one sample of the truth file).
using TruthSample = eval::StateTruth;

/// "<dir>/<stem>.truth.csv" for a recording "<dir>/<stem>.rawlog", "<dir>/<stem>.mcap",
/// "<dir>/<stem>.bag" or "<dir>/<stem>.db3", and for a rosbag2 folder "<dir>/<stem>" (or
/// "<dir>/<stem>/"): the truth file beside the recording. Another name gets ".truth.csv" appended.
std::string truthPathFor(const std::string& input_path);
/// eval::writeTruthCsv.
void writeTruthCsv(const std::string& path, const std::vector<TruthSample>& truth);
/// eval::readTruthCsv: throws std::runtime_error naming the file and line on a malformed file.
std::vector<TruthSample> readTruthCsv(const std::string& path);
/// eval::interpolateTruth: nullopt outside the covered time span.
std::optional<TruthSample> truthAt(const std::vector<TruthSample>& truth, double t);

/// The record of errors_wrt_gt.ini.
struct TruthErrors {
  double t = 0;            ///< [s] instant compared (the state timestamp)
  double velocity = 0;     ///< [m/s] |v_b - v_b_true|
  double gravity_deg = 0;  ///< [deg] angle between g_b and g_b_true
  double gyro_bias = 0;    ///< [rad/s] |b_g - b_g_true|
  double accel_bias = 0;   ///< [m/s^2] |b_a - b_a_true|
  Vec3 v_b_true = Vec3::Zero();
  // NEES of the state's covariance (eval::stateNees): 3, 2, 3 and 3 dof.
  double nees_velocity = 0;
  double nees_tilt = 0;
  double nees_gyro_bias = 0;
  double nees_accel_bias = 0;
};

/// Throws std::runtime_error if the state time is not covered by the truth.
TruthErrors compareWithTruth(const InitialState& s, const std::vector<TruthSample>& truth);
void writeTruthErrors(const std::string& path, const TruthErrors& e);

}  // namespace freeinit::app_support
