// PNG snapshots rendered offscreen (mrpt::opengl::CFBORender works headless through EGL).
#pragma once

#include <freeinit/initial_state.h>
#include <freeinit/mrpt/ground_truth.h>

#include <string>
#include <vector>

namespace freeinit::mrpt_glue {

/// 3-D view: the static map (colored by height), the rejected points (red), the initialization
/// trajectory (green) and the estimated gravity arrow at the final pose (blue). Written atomically.
void renderMapSnapshot(const std::string& png, const InitResult& result, int width, int height);

/// Body-frame velocity over the window, one panel per axis, with ground truth when `truth` is
/// not empty. Written atomically.
void renderVelocityPlot(const std::string& png, const InitResult& result,
                        const std::vector<TruthSample>& truth, int width, int height);

}  // namespace freeinit::mrpt_glue
