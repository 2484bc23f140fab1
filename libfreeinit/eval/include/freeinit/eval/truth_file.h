// The truth file beside a recording ("<name>.truth.csv", as freeinit-sim writes it): one CSV line
// per sample, header
//   t,p_x,p_y,p_z,q_w,q_x,q_y,q_z,v_x,v_y,v_z,omega_x,omega_y,omega_z,b_g_x,b_g_y,b_g_z,b_a_x,
//   b_a_y,b_a_z,g_x,g_y,g_z
// (t UNIX [s], p_w [m], q_wb, v_w [m/s], omega_b [rad/s], b_g [rad/s], b_a [m/s^2], g_w [m/s^2]).
#pragma once

#include <freeinit/eval/state_truth.h>

#include <string>
#include <vector>

namespace freeinit::eval {

/// Writes `truth` atomically (temporary file + rename). Throws std::runtime_error on I/O errors.
void writeTruthCsv(const std::string& path, const std::vector<StateTruth>& truth);

/// Reads a truth file. Throws std::runtime_error naming the file and line on a malformed file, a
/// non-finite value or times that do not increase.
std::vector<StateTruth> readTruthCsv(const std::string& path);

}  // namespace freeinit::eval
