// PNG snapshots rendered offscreen (mrpt::opengl::CFBORender works headless through EGL).
#pragma once

#include <freeinit/app_support/ground_truth.h>
#include <freeinit/initial_state.h>

#include <string>
#include <vector>

namespace freeinit::app_support {

/// Two 3-D views side by side, an overview and a close-up of the trajectory: the static map
/// (colored by height), the rejected points (red), the initialization trajectory (orange, body
/// axes every tenth, white start sphere), the body axes at the state and the gravity arrow (cyan),
/// under a title band with the status, speed, gravity tilt and counts. Written atomically.
void renderMapSnapshot(const std::string& png, const InitResult& result, int width, int height);

/// Body-frame velocity over the window, one panel per axis, and the gyro bias, with the window
/// shaded, the state's values marked and the ground truth when `truth` is not empty. Written
/// atomically.
void renderVelocityPlot(const std::string& png, const InitResult& result,
                        const std::vector<TruthSample>& truth, int width, int height);

/// One panel of a top view: a map (grey points), an estimated path and the true path, all in the
/// same planar frame.
struct TopViewPanel {
  std::string title;
  std::vector<float> map_x, map_y;  ///< [m]
  std::vector<Vec3> path;           ///< [m] (z ignored)
  std::vector<Vec3> truth;          ///< [m] (z ignored)
};

/// Panels stacked vertically under a title band, each an orthographic top view fitted to the
/// paths (x to the right), with the estimate in orange and the truth (if any) in white. Written
/// atomically.
void renderTopViewPanels(const std::string& png, const std::string& title,
                         const std::vector<TopViewPanel>& panels, int width, int height);

}  // namespace freeinit::app_support
