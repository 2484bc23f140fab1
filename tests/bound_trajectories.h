// Trajectories shared by the bound's tests.
#pragma once

#include <freeinit/sim/analytic_trajectory.h>

namespace freeinit::test {

/// Walking with fast hand rotation: several rad/s about every axis, up to ~10 m/s^2.
inline sim::AnalyticTrajectory movingTrajectory() {
  sim::TrajectoryParams p;
  p.t0 = 0;
  p.p_start_w = Vec3(1, 2, 1.4);
  p.rpy_start = Vec3(0.2, -0.3, 0.5);
  p.pos[0].poly = {0.0, 1.2, 0.4};
  p.pos[0].waves = {{0.05, 1.8, 0.3}};
  p.pos[1].waves = {{0.08, 1.1, 1.0}};
  p.pos[2].waves = {{0.04, 2.2, 0.2}};
  p.rpy[0].waves = {{0.3, 2.0, 0.4}};
  p.rpy[1].waves = {{0.25, 1.7, 2.0}};
  p.rpy[2].waves = {{0.5, 1.6, 0.7}};
  return sim::AnalyticTrajectory(p);
}

}  // namespace freeinit::test
