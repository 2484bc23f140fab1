// The two ways the facade can solve an initialization window, behind one interface.
#pragma once

#include <freeinit/config.h>
#include <freeinit/initial_state.h>

#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "measurement_sequencer.h"
#include "usable_points.h"

namespace freeinit::detail {

/// An estimator over the sequencer's buffered data. processBuffered() processes, in time order,
/// everything the data received so far allow, and returns true once `result` is final (initialized
/// or not). The sequencer outlives the pipeline; the pipeline reads it only.
class Pipeline {
 public:
  virtual ~Pipeline() = default;
  virtual bool processBuffered(InitResult& result) = 0;
  /// Fills result.static_map and result.rejected once processBuffered() returned true, if
  /// processBuffered() left them for later (the state does not wait for the map); called once.
  virtual void completeMap(InitResult& /*result*/) {}
};

/// The joint window estimator (EstimatorParams::Method::Joint).
std::unique_ptr<Pipeline> makeJointPipeline(const FreeInitConfig& config,
                                            const MeasurementSequencer& sequencer);
/// The paper's two stages (EstimatorParams::Method::Paper).
std::unique_ptr<Pipeline> makePaperPipeline(const FreeInitConfig& config,
                                            const MeasurementSequencer& sequencer);

/// Marks `result` as not initialized.
inline void failResult(InitResult& result, InitStatus status, const std::string& message) {
  result.state.status = status;
  result.state.message = message;
}

/// [s] a monotonic clock, for the durations the diagnostics report.
inline double wallSeconds() {
  using Clock = std::chrono::steady_clock;
  return std::chrono::duration<double>(Clock::now().time_since_epoch()).count();
}

/// automaticPointStride() over the frames the sequencer has buffered.
inline int automaticPointStride(const MeasurementSequencer& sequencer, double max_point_rate) {
  struct FramePoints {
    const std::vector<DopplerPoint>& points;
  };
  std::vector<FramePoints> frames;
  for (const MeasurementSequencer::FrameRef& f : sequencer.frames()) frames.push_back({*f.points});
  return automaticPointStride(frames, max_point_rate);
}

}  // namespace freeinit::detail
