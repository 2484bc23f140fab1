// Writers of the app's outputs. Each file is written to "<path>.tmp" and renamed when complete,
// so every output is either complete or absent.
#pragma once

#include <freeinit/atomic_file.h>
#include <freeinit/initial_state.h>

#include <string>
#include <vector>

namespace freeinit::mrpt_glue {

/// The core's atomic writer (freeinit/atomic_file.h), under the name the glue has always used.
using freeinit::writeFileAtomically;

/// The initial-state contract (DESIGN.md): [initial_state] status, timestamp, q_wb, p_w, v_w, b_g,
/// b_a, g_w, cov (18x18 row-major, order [dtheta p v b_g b_a g]).
void writeInitialStateIni(const std::string& path, const InitialState& s);
/// TUM: "t x y z qx qy qz qw" per line.
void writeTum(const std::string& path, const std::vector<PoseSample>& trajectory);
/// The velocimeter's time series, CSV with a header line.
void writeVelocityCsv(const std::string& path, const std::vector<VelocitySample>& v);
/// Binary little-endian PLY with x y z intensity (float32).
void writePly(const std::string& path, const std::vector<MapPoint>& points);

}  // namespace freeinit::mrpt_glue
