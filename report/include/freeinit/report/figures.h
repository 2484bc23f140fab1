// The evaluation figures: each method's velocity error over the initialization window (log
// scale), and estimated against true body-velocity components. One panel per input; tile() them.
#pragma once

#include <freeinit/report/methods.h>

#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace freeinit::report {

/// A method's velocity estimates over time with the truth at the same instants.
struct VelocityTrack {
  std::string method;
  bool per_frame = false;           ///< one estimate per LiDAR frame: drawn as markers
  std::vector<double> t;            ///< [s] since the start of the recording
  std::vector<Vec3> v_est, v_true;  ///< [m/s] body velocity in b
};

/// The tracks of `runs`, with truth from `v_b_true(t_unix)` and times relative to `t0`.
template <typename TruthFn>
std::vector<VelocityTrack> velocityTracks(const std::vector<MethodRun>& runs, double t0,
                                          TruthFn&& v_b_true) {
  std::vector<VelocityTrack> out;
  for (const MethodRun& m : runs) {
    VelocityTrack tr;
    tr.method = m.method;
    tr.per_frame = m.track_per_frame;
    for (const TimedVelocity& s : m.track) {
      tr.t.push_back(s.t - t0);
      tr.v_est.push_back(s.v_b);
      tr.v_true.push_back(v_b_true(s.t));
    }
    out.push_back(std::move(tr));
  }
  return out;
}

/// |v_est - v_true| over time for every method, log y axis. The static-mean baselines assume
/// v = 0 over the same window: when both are present they share one line.
cv::Mat velocityErrorPanel(const std::string& title, const std::vector<VelocityTrack>& tracks,
                           int width, int height);

/// Free-Init's body-velocity components (lines) and the per-frame Doppler fits (markers) against
/// the truth (thin black dashed lines): plot::componentPanel, the layout of the app's velocity
/// snapshot.
cv::Mat velocityComponentsPanel(const std::string& title, const std::vector<VelocityTrack>& tracks,
                                int width, int height);

}  // namespace freeinit::report
