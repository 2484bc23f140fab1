// Ground truth beside a rawlog ("<name>.truth.csv", written by freeinit-sim) and the comparison
// of an initial state against it. Only frame-independent quantities are compared: the body-frame
// velocity, the gravity direction in the body frame and the biases.
#pragma once

#include <freeinit/initial_state.h>

#include <optional>
#include <string>
#include <vector>

namespace freeinit::mrpt_glue {

struct TruthSample {
  double t = 0;  ///< [s] UNIX
  Quat q_wb = Quat::Identity();
  Vec3 p_w = Vec3::Zero();      ///< [m]
  Vec3 v_w = Vec3::Zero();      ///< [m/s]
  Vec3 omega_b = Vec3::Zero();  ///< [rad/s]
  Vec3 b_g = Vec3::Zero();      ///< [rad/s]
  Vec3 b_a = Vec3::Zero();      ///< [m/s^2]
  Vec3 g_w = Vec3(0, 0, -kGravity);
};

/// "<dir>/<stem>.truth.csv" for "<dir>/<stem>.rawlog".
std::string truthPathFor(const std::string& rawlog_path);
void writeTruthCsv(const std::string& path, const std::vector<TruthSample>& truth);
/// Throws std::runtime_error naming the file and line on a malformed file.
std::vector<TruthSample> readTruthCsv(const std::string& path);
/// Linear interpolation (slerp for the attitude); nullopt outside the covered time span.
std::optional<TruthSample> truthAt(const std::vector<TruthSample>& truth, double t);

struct TruthErrors {
  double t = 0;            ///< [s] instant compared (the state timestamp)
  double velocity = 0;     ///< [m/s] |v_b - v_b_true|
  double gravity_deg = 0;  ///< [deg] angle between g_b and g_b_true
  double gyro_bias = 0;    ///< [rad/s] |b_g - b_g_true|
  double accel_bias = 0;   ///< [m/s^2] |b_a - b_a_true|
  Vec3 v_b_true = Vec3::Zero();
};

/// Throws std::runtime_error if the state time is not covered by the truth.
TruthErrors compareWithTruth(const InitialState& s, const std::vector<TruthSample>& truth);
void writeTruthErrors(const std::string& path, const TruthErrors& e);

}  // namespace freeinit::mrpt_glue
