// Writers of the app's outputs. Each file is written to "<path>.tmp" and renamed when complete,
// so every output is either complete or absent.
#pragma once

#include <freeinit/initial_state.h>

#include <functional>
#include <iosfwd>
#include <string>
#include <vector>

namespace freeinit::mrpt_glue {

/// Writes through `fill` into a temporary file, then renames it onto `path`.
/// Throws std::runtime_error (naming the path) on any I/O error; the target is then untouched.
void writeFileAtomically(const std::string& path, const std::function<void(std::ostream&)>& fill,
                         bool binary = false);

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
