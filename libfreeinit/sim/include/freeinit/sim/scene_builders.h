// Builders of the four scene kinds. World frame: z up, ground at z = 0, streets/corridors/tunnels
// run along +x and are centred on y = 0. Every builder is deterministic given its rng state.
#pragma once

#include <freeinit/sim/scene.h>

#include <random>

namespace freeinit::sim {

/// Street: ground, building facades (boxes) both sides, end buildings, poles, parked cars, moving
/// cars in two lanes (y = -2.5 towards +x, y = +2.5 towards -x), pedestrians on both sidewalks.
/// Cross-section: facades at |y| >= half_width, poles at |y| = half_width - 2.8, parked cars at
/// |y| = half_width - 4.2, pedestrians at y = -(half_width - 0.6) and y = +(half_width - 1.5).
struct StreetOptions {
  double x_min = 0;                 ///< [m] smallest x the platform reaches
  double x_max = 50;                ///< [m] largest x the platform reaches
  double half_width = 10;           ///< [m] facade-to-centre distance
  double duration = 5;              ///< [s] recording length (moving objects stay placed for it)
  double cars_per_100m = 4;         ///< moving cars per 100 m and lane
  double pedestrians_per_100m = 6;  ///< pedestrians per 100 m and sidewalk
  double ego_lane_speed = 0;        ///< [m/s] > 0: the platform drives in lane y = -2.5 at this
                                    ///< speed starting at x_min; cars in that lane start ahead and
                                    ///< are faster, so they never collide with it
};
Scene makeStreetScene(const StreetOptions& opt, std::mt19937_64& rng);

/// Corridor: floor, ceiling, walls at |y| = half_width, end walls, pillars and cabinets along the
/// walls, ceiling lamps, optionally people walking at |y| = 0.75.
struct CorridorOptions {
  double x_min = 0;          ///< [m]
  double x_max = 20;         ///< [m]
  double half_width = 1.3;   ///< [m]
  double height = 3.0;       ///< [m]
  int pedestrians = 0;       ///< moving people
};
Scene makeCorridorScene(const CorridorOptions& opt, std::mt19937_64& rng);

/// Tunnel: floor, ceiling and two walls, long and featureless along x (the degenerate case).
struct TunnelOptions {
  double x_min = 0;          ///< [m]
  double x_max = 100;        ///< [m]
  double half_width = 5;     ///< [m]
  double height = 6;         ///< [m]
};
Scene makeTunnelScene(const TunnelOptions& opt);

/// Open field: a large ground plane and a few far objects (buildings, silos, trees), plus a few
/// pedestrians at |y| >= 8.
struct OpenOptions {
  double x_min = 0;          ///< [m]
  double x_max = 20;         ///< [m]
  int pedestrians = 2;
};
Scene makeOpenScene(const OpenOptions& opt, std::mt19937_64& rng);

}  // namespace freeinit::sim
