// PNG snapshots rendered offscreen (mrpt::opengl::CFBORender works headless through EGL).
#pragma once

#include <freeinit/initial_state.h>
#include <freeinit/mrpt/ground_truth.h>

#include <string>
#include <vector>

namespace freeinit::mrpt_glue {

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

}  // namespace freeinit::mrpt_glue
