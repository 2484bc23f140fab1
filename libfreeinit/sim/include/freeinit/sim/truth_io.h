// Ground-truth export at any rate. Files are written to "<path>.tmp" and then renamed, so readers
// never see a partial file. Throws std::runtime_error on I/O failure.
#pragma once

#include <freeinit/sim/simulator.h>

#include <string>

namespace freeinit::sim {

/// Writes body poses in TUM format, one line per sample: "t x y z qx qy qz qw" (t UNIX [s],
/// p_w [m], q_wb unit quaternion), at t_begin + k / rate_hz for all k with t <= t_end.
void writeTumPoses(const Trajectory& trajectory, double t_begin, double t_end, double rate_hz,
                   const std::string& path);

/// Writes the full TruthState as CSV with a header line:
/// t,qw,qx,qy,qz,px,py,pz,vx,vy,vz,ax,ay,az,wx,wy,wz,alx,aly,alz
/// (q_wb, p_w [m], v_w [m/s], a_w [m/s^2], omega_b [rad/s], alpha_b [rad/s^2]), same sampling.
void writeTruthCsv(const Trajectory& trajectory, double t_begin, double t_end, double rate_hz,
                   const std::string& path);

}  // namespace freeinit::sim
