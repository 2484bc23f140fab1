// Builders of the scene kinds. Path frame: z up, ground at z = 0, streets, corridors, tunnels and
// parking aisles run along +x and are centred on y = 0. Every builder is deterministic given its
// rng state. x_min, x_max (and duration) are the stretch the platform covers; the simulator fills
// them.
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
  bool near_traffic = true;         ///< add the presets' traffic placed relative to x_min (cars
                                    ///< and pedestrians seen from the first frame on)
};
Scene makeStreetScene(const StreetOptions& opt, std::mt19937_64& rng);

/// Corridor: floor, ceiling, walls at |y| = half_width, end walls, pillars and cabinets along the
/// walls, ceiling lamps, optionally people walking at |y| = 0.75.
struct CorridorOptions {
  double x_min = 0;                 ///< [m]
  double x_max = 20;                ///< [m]
  double half_width = 1.3;          ///< [m]
  double height = 3.0;              ///< [m]
  int pedestrians = 0;              ///< moving people
  double pedestrian_offset = 0.75;  ///< [m] |y| of the people's paths
};
Scene makeCorridorScene(const CorridorOptions& opt, std::mt19937_64& rng);

/// Tunnel: floor, ceiling and two walls, long and featureless along x (the degenerate case), with
/// optional features: ceiling lights, wall niches and signs.
struct TunnelOptions {
  double x_min = 0;              ///< [m]
  double x_max = 100;            ///< [m]
  double half_width = 5;         ///< [m]
  double height = 6;             ///< [m]
  double features_per_100m = 0;  ///< lights / niches / signs per 100 m (0: featureless)
};
Scene makeTunnelScene(const TunnelOptions& opt, std::mt19937_64& rng);

/// Open field: a large ground plane and a few far objects (buildings, silos, trees), plus a few
/// pedestrians at |y| >= 8.
struct OpenOptions {
  double x_min = 0;   ///< [m]
  double x_max = 20;  ///< [m]
  int pedestrians = 2;
};
Scene makeOpenScene(const OpenOptions& opt, std::mt19937_64& rng);

/// Parking lot: ground, rows of cars parked across the bays on both sides of an aisle along x
/// (|y| >= aisle_half_width), a second row back to back, lamp posts, buildings around, cars
/// driving in the parallel aisles and people walking along the parked cars at
/// |y| = aisle_half_width - 0.6.
struct ParkingOptions {
  double x_min = 0;               ///< [m]
  double x_max = 30;              ///< [m]
  double duration = 5;            ///< [s]
  double aisle_half_width = 3.5;  ///< [m] free half width of the aisle the platform uses
  double occupancy = 0.7;         ///< share of occupied bays, in [0, 1]
  int pedestrians = 2;            ///< people walking along the aisle
  int moving_cars = 1;            ///< cars driving in the parallel aisles
};
Scene makeParkingScene(const ParkingOptions& opt, std::mt19937_64& rng);

}  // namespace freeinit::sim
