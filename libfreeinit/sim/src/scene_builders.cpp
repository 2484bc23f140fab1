#include <freeinit/sim/scene_builders.h>

#include <cmath>

namespace freeinit::sim {
namespace {

double uniform(std::mt19937_64& rng, double a, double b) {
  return std::uniform_real_distribution<double>(a, b)(rng);
}

float reflect(std::mt19937_64& rng, double a, double b) {
  return static_cast<float>(uniform(rng, a, b));
}

/// Rotation whose columns are (u, v, u x v): a rectangle spanned by u, v with normal u x v.
Mat3 span(const Vec3& u, const Vec3& v) {
  Mat3 R;
  R.col(0) = u;
  R.col(1) = v;
  R.col(2) = u.cross(v);
  return R;
}

/// A horizontal ground rectangle at z = 0.
Primitive ground(double x_min, double x_max, double half_y, float reflectivity) {
  return makeRectangle(Vec3(0.5 * (x_min + x_max), 0, 0), Mat3::Identity(), 0.5 * (x_max - x_min),
                       half_y, reflectivity);
}

Primitive pedestrian(const Vec3& foot_w, double vx, std::mt19937_64& rng) {
  const double h = uniform(rng, 1.6, 1.9);
  return makeCylinder(foot_w + Vec3(0, 0, 0.5 * h), 0.28, 0.5 * h, reflect(rng, 0.3, 0.6),
                      Vec3(vx, 0, 0));
}

}  // namespace

Scene makeStreetScene(const StreetOptions& opt, std::mt19937_64& rng) {
  Scene scene("street");
  const double xa = opt.x_min - 40.0;   // start of the street (a building closes it)
  const double xb = opt.x_max + 110.0;  // end of the street (a building closes it)
  const double hw = opt.half_width;
  scene.add(ground(xa - 60.0, xb + 60.0, hw + 60.0, 0.25f));
  // Building blocks with varying length, height and setback on both sides.
  for (double side : {-1.0, 1.0}) {
    double x = xa - 10.0;
    while (x < xb + 10.0) {
      const double len = uniform(rng, 12.0, 35.0);
      const double height = uniform(rng, 12.0, 30.0);
      const double setback = uniform(rng, 0.0, 1.2);
      scene.add(makeBox(Vec3(x + 0.5 * len, side * (hw + setback + 6.0), 0.5 * height),
                        Vec3(0.5 * len, 6.0, 0.5 * height), 0.0, reflect(rng, 0.3, 0.8)));
      x += len;
    }
  }
  // End buildings across the street.
  for (double xe : {xa - 6.0, xb + 6.0}) {
    scene.add(makeBox(Vec3(xe, 0, 15.0), Vec3(6.0, hw + 20.0, 15.0), 0.0, reflect(rng, 0.4, 0.7)));
  }
  // Poles (street lights, signs).
  for (double side : {-1.0, 1.0}) {
    for (double x = xa + uniform(rng, 0, 8); x < xb; x += uniform(rng, 10.0, 20.0)) {
      scene.add(makeCylinder(Vec3(x, side * (hw - 2.8), 3.5), 0.12, 3.5, reflect(rng, 0.5, 0.9)));
    }
  }
  // Parked cars, with gaps.
  for (double side : {-1.0, 1.0}) {
    for (double x = xa + uniform(rng, 0, 6); x < xb; x += uniform(rng, 5.0, 16.0)) {
      if (uniform(rng, 0, 1) < 0.3) continue;
      const double h = uniform(rng, 1.4, 1.9);
      scene.add(makeBox(Vec3(x, side * (hw - 4.2), 0.5 * h), Vec3(2.25, 0.9, 0.5 * h),
                        uniform(rng, -0.03, 0.03), reflect(rng, 0.4, 0.95)));
    }
  }
  // Moving cars. Lane y = -2.5 drives towards +x, lane y = +2.5 towards -x.
  const double span_x = xb - xa;
  const int cars = static_cast<int>(std::ceil(opt.cars_per_100m * span_x / 100.0));
  for (int i = 0; i < cars; ++i) {
    const double h = uniform(rng, 1.4, 1.9);
    const Vec3 half(2.25, 0.9, 0.5 * h);
    // Opposite lane: spread so that they pass the platform during the recording.
    const double v_opp = uniform(rng, 9.0, 15.0);
    const double x_opp = xa + uniform(rng, 0.0, span_x + v_opp * opt.duration);
    scene.add(
        makeBox(Vec3(x_opp, 2.5, 0.5 * h), half, 0, reflect(rng, 0.4, 0.95), Vec3(-v_opp, 0, 0)));
    double x_own = xa + uniform(rng, 0.0, span_x);
    double v_own = uniform(rng, 8.0, 13.0);
    if (opt.ego_lane_speed > 0) {
      // Ahead of the platform and faster: never caught up with.
      x_own = opt.x_min + 14.0 + uniform(rng, 0.0, 100.0);
      v_own = opt.ego_lane_speed + uniform(rng, 1.0, 4.0);
    }
    const double h2 = uniform(rng, 1.4, 1.9);
    scene.add(makeBox(Vec3(x_own, -2.5, 0.5 * h2), Vec3(2.25, 0.9, 0.5 * h2), 0,
                      reflect(rng, 0.4, 0.95), Vec3(v_own, 0, 0)));
  }
  // Moving objects placed relative to the platform so that every street recording sees traffic
  // from the first frame on (not left to chance).
  if (opt.near_traffic && opt.ego_lane_speed > 0) {
    for (double ahead : {18.0, 45.0}) {
      scene.add(makeBox(Vec3(opt.x_min + ahead, -2.5, 0.8), Vec3(2.25, 0.9, 0.8), 0,
                        reflect(rng, 0.5, 0.95), Vec3(opt.ego_lane_speed + ahead / 15.0, 0, 0)));
    }
    for (double ahead : {40.0, 90.0, 150.0}) {
      scene.add(makeBox(Vec3(opt.x_min + ahead, 2.5, 0.75), Vec3(2.25, 0.9, 0.75), 0,
                        reflect(rng, 0.5, 0.95), Vec3(-uniform(rng, 10.0, 15.0), 0, 0)));
    }
  } else if (opt.near_traffic) {
    // The platform walks / rolls on the right sidewalk (y = -(half_width - 1.8)).
    for (double ahead : {5.0, 11.0}) {
      scene.add(pedestrian(Vec3(opt.x_min + ahead, -(hw - 0.6), 0), 1.7, rng));
    }
    scene.add(pedestrian(Vec3(opt.x_min + 18.0, -(hw - 0.6), 0), -1.3, rng));
    scene.add(makeBox(Vec3(opt.x_min + 8.0, -2.5, 0.75), Vec3(2.25, 0.9, 0.75), 0,
                      reflect(rng, 0.5, 0.95), Vec3(9.0, 0, 0)));
    scene.add(makeBox(Vec3(opt.x_min + 35.0, 2.5, 0.75), Vec3(2.25, 0.9, 0.75), 0,
                      reflect(rng, 0.5, 0.95), Vec3(-10.0, 0, 0)));
  }
  // Pedestrians on both sidewalks, walking either way.
  const int peds = static_cast<int>(std::ceil(opt.pedestrians_per_100m * span_x / 100.0));
  for (int i = 0; i < peds; ++i) {
    for (double y : {-(hw - 0.6), hw - 1.5}) {
      const double vx = (uniform(rng, 0, 1) < 0.5 ? -1.0 : 1.0) * uniform(rng, 0.9, 1.6);
      scene.add(pedestrian(Vec3(opt.x_min + uniform(rng, -10.0, span_x - 40.0), y, 0), vx, rng));
    }
  }
  return scene;
}

namespace {

/// Floor, ceiling and both side walls of a straight tube along x from xa to xb (corridor,
/// tunnel): half width hw, height H.
void addTube(Scene& scene, double xa, double xb, double hw, double H, float floor_refl,
             float ceiling_refl, float wall_refl) {
  const double L = xb - xa;
  const double xc = 0.5 * (xa + xb);
  const Vec3 ex = Vec3::UnitX(), ey = Vec3::UnitY(), ez = Vec3::UnitZ();
  scene.add(ground(xa, xb, hw, floor_refl));
  scene.add(makeRectangle(Vec3(xc, 0, H), span(ex, -ey), 0.5 * L, hw, ceiling_refl));
  scene.add(makeRectangle(Vec3(xc, hw, 0.5 * H), span(ex, ez), 0.5 * L, 0.5 * H, wall_refl));
  scene.add(makeRectangle(Vec3(xc, -hw, 0.5 * H), span(ex, -ez), 0.5 * L, 0.5 * H, wall_refl));
}

}  // namespace

Scene makeCorridorScene(const CorridorOptions& opt, std::mt19937_64& rng) {
  Scene scene("corridor");
  const double xa = opt.x_min - 4.0;
  const double xb = opt.x_max + 25.0;
  const double hw = opt.half_width;
  const double H = opt.height;
  const Vec3 ey = Vec3::UnitY(), ez = Vec3::UnitZ();
  addTube(scene, xa, xb, hw, H, 0.3f, 0.6f, 0.7f);
  scene.add(makeRectangle(Vec3(xa, 0, 0.5 * H), span(ey, ez), hw, 0.5 * H, 0.5f));  // end walls
  scene.add(makeRectangle(Vec3(xb, 0, 0.5 * H), span(-ey, ez), hw, 0.5 * H, 0.5f));
  // Pillars / door frames protruding from the walls, cabinets, ceiling lamps.
  for (double side : {-1.0, 1.0}) {
    for (double x = xa + uniform(rng, 0.5, 3.0); x < xb - 1.0; x += uniform(rng, 2.5, 6.0)) {
      const double w = uniform(rng, 0.2, 0.6);
      scene.add(makeBox(Vec3(x, side * (hw - 0.05), 0.5 * H), Vec3(0.5 * w, 0.2, 0.5 * H), 0,
                        reflect(rng, 0.4, 0.9)));
      if (uniform(rng, 0, 1) < 0.3) {
        const double h = uniform(rng, 0.8, 1.9);
        scene.add(makeBox(Vec3(x + 1.2, side * (hw - 0.2), 0.5 * h), Vec3(0.45, 0.2, 0.5 * h), 0,
                          reflect(rng, 0.3, 0.9)));
      }
    }
  }
  for (double x = xa + 2.0; x < xb - 1.0; x += uniform(rng, 3.0, 5.0)) {
    scene.add(makeBox(Vec3(x, 0, H - 0.05), Vec3(0.6, 0.15, 0.06), 0, 0.95f));
  }
  for (int i = 0; i < opt.pedestrians; ++i) {
    const double y = (i % 2 == 0 ? opt.pedestrian_offset : -opt.pedestrian_offset);
    const double vx = (i % 2 == 0 ? -1.0 : 1.0) * uniform(rng, 0.9, 1.4);
    scene.add(pedestrian(Vec3(opt.x_min + uniform(rng, 4.0, 15.0), y, 0), vx, rng));
  }
  return scene;
}

Scene makeTunnelScene(const TunnelOptions& opt, std::mt19937_64& rng) {
  Scene scene("tunnel");
  const double xa = opt.x_min - 60.0;
  const double xb = opt.x_max + 400.0;
  const double hw = opt.half_width;
  const double H = opt.height;
  addTube(scene, xa, xb, hw, H, 0.25f, 0.5f, 0.6f);
  if (opt.features_per_100m > 0) {
    // Ceiling lights, wall niches (recesses drawn as dark boxes against the wall) and signs.
    const double mean_gap = 100.0 / opt.features_per_100m;
    for (double x = xa + uniform(rng, 0, mean_gap); x < xb;
         x += uniform(rng, 0.5, 1.5) * mean_gap) {
      const double kind = uniform(rng, 0, 1);
      const double side = uniform(rng, 0, 1) < 0.5 ? -1.0 : 1.0;
      if (kind < 0.5) {
        scene.add(makeBox(Vec3(x, side * 0.3 * hw, H - 0.08), Vec3(0.6, 0.15, 0.08), 0, 0.95f));
      } else if (kind < 0.8) {
        scene.add(makeBox(Vec3(x, side * (hw - 0.1), 1.2), Vec3(uniform(rng, 0.5, 1.5), 0.1, 1.2),
                          0, reflect(rng, 0.1, 0.3)));
      } else {
        scene.add(makeBox(Vec3(x, side * (hw - 0.06), uniform(rng, 2.0, 0.8 * H)),
                          Vec3(0.6, 0.05, 0.35), 0, reflect(rng, 0.8, 1.0)));
      }
    }
  }
  return scene;
}

Scene makeOpenScene(const OpenOptions& opt, std::mt19937_64& rng) {
  Scene scene("open");
  const double xc = 0.5 * (opt.x_min + opt.x_max);
  scene.add(ground(xc - 600.0, xc + 600.0, 600.0, 0.2f));
  // Far buildings around, none closer than 40 m to the path's ends or 25 m to its side.
  for (int i = 0; i < 8; ++i) {
    const double ang = 2.0 * M_PI * (i + uniform(rng, 0.0, 0.6)) / 8.0;
    const double dist = uniform(rng, 50.0, 130.0);
    const double x = (std::cos(ang) > 0 ? opt.x_max : opt.x_min) + dist * std::cos(ang);
    const double y = (std::sin(ang) > 0 ? 25.0 : -25.0) + dist * std::sin(ang);
    const double h = uniform(rng, 6.0, 25.0);
    scene.add(makeBox(Vec3(x, y, 0.5 * h), Vec3(uniform(rng, 5, 20), uniform(rng, 5, 15), 0.5 * h),
                      uniform(rng, -1.0, 1.0), reflect(rng, 0.3, 0.8)));
  }
  // Silos and trees.
  for (int i = 0; i < 10; ++i) {
    const double x = opt.x_min + uniform(rng, -40.0, opt.x_max - opt.x_min + 100.0);
    const double y = (i % 2 == 0 ? 1.0 : -1.0) * uniform(rng, 15.0, 60.0);
    const double h = uniform(rng, 4.0, 14.0);
    scene.add(
        makeCylinder(Vec3(x, y, 0.5 * h), uniform(rng, 0.3, 3.0), 0.5 * h, reflect(rng, 0.2, 0.7)));
  }
  for (int i = 0; i < opt.pedestrians; ++i) {
    const double y = (i % 2 == 0 ? 1.0 : -1.0) * uniform(rng, 8.0, 14.0);
    const double vx = (i % 2 == 0 ? -1.0 : 1.0) * uniform(rng, 0.9, 1.5);
    scene.add(pedestrian(Vec3(opt.x_min + uniform(rng, 5.0, 25.0), y, 0), vx, rng));
  }
  return scene;
}

Scene makeParkingScene(const ParkingOptions& opt, std::mt19937_64& rng) {
  Scene scene("parking");
  const double xa = opt.x_min - 30.0;
  const double xb = opt.x_max + 60.0;
  const double a = opt.aisle_half_width;
  constexpr double kBay = 2.6;      // [m] bay width along x
  constexpr double kCarHalf = 2.3;  // [m] half length of a bay across the aisle
  const double row_depth = 2.0 * kCarHalf;
  scene.add(ground(xa - 80.0, xb + 80.0, 120.0, 0.2f));
  // Two rows of bays back to back on each side, cars parked across (long axis along y).
  for (double side : {-1.0, 1.0}) {
    for (int row = 0; row < 2; ++row) {
      const double y_c = side * (a + kCarHalf + row * row_depth);
      for (double x = xa; x < xb; x += kBay) {
        if (uniform(rng, 0, 1) >= opt.occupancy) continue;
        const bool van = uniform(rng, 0, 1) < 0.15;
        const double h = van ? uniform(rng, 2.0, 2.6) : uniform(rng, 1.35, 1.8);
        const double half_len = van ? uniform(rng, 2.3, 2.6) : uniform(rng, 2.0, 2.35);
        scene.add(makeBox(
            Vec3(x + uniform(rng, -0.15, 0.15),
                 y_c + side * (kCarHalf - half_len - 0.2 - uniform(rng, 0, 0.3)), 0.5 * h),
            Vec3(0.9, half_len, 0.5 * h), uniform(rng, -0.04, 0.04), reflect(rng, 0.3, 0.95)));
      }
    }
    // Lamp posts between the two rows, a building or a fence behind the far row.
    for (double x = xa + uniform(rng, 0, 10); x < xb; x += uniform(rng, 18.0, 30.0)) {
      scene.add(
          makeCylinder(Vec3(x, side * (a + row_depth), 4.0), 0.12, 4.0, reflect(rng, 0.5, 0.9)));
    }
    const double y_far = a + 2.0 * row_depth + 2.0 * a + uniform(rng, 0.0, 20.0);
    for (double x = xa - 10.0; x < xb + 10.0;) {
      const double len = uniform(rng, 15.0, 40.0);
      const double h = uniform(rng, 2.0, 20.0);
      scene.add(makeBox(Vec3(x + 0.5 * len, side * (y_far + 5.0), 0.5 * h),
                        Vec3(0.5 * len, 5.0, 0.5 * h), 0, reflect(rng, 0.3, 0.8)));
      x += len;
    }
  }
  for (double xe : {xa - 8.0, xb + 8.0}) {
    scene.add(makeBox(Vec3(xe, 0, 6.0), Vec3(5.0, 40.0, 6.0), 0, reflect(rng, 0.4, 0.7)));
  }
  // Cars driving in the parallel aisles (beyond the back-to-back rows), either way.
  const double y_aisle = a + 2.0 * row_depth + a;
  for (int i = 0; i < opt.moving_cars; ++i) {
    const double side = i % 2 == 0 ? 1.0 : -1.0;
    const double v = (uniform(rng, 0, 1) < 0.5 ? -1.0 : 1.0) * uniform(rng, 2.0, 6.0);
    const double h = uniform(rng, 1.4, 1.8);
    scene.add(makeBox(Vec3(opt.x_min + uniform(rng, -15.0, 40.0) - v * 0.5 * opt.duration,
                           side * y_aisle, 0.5 * h),
                      Vec3(2.25, 0.9, 0.5 * h), 0, reflect(rng, 0.4, 0.95), Vec3(v, 0, 0)));
  }
  // People walking along the parked cars of the platform's aisle.
  for (int i = 0; i < opt.pedestrians; ++i) {
    const double y = (i % 2 == 0 ? -1.0 : 1.0) * (a - 0.6);
    const double vx = (uniform(rng, 0, 1) < 0.5 ? -1.0 : 1.0) * uniform(rng, 0.8, 1.6);
    scene.add(pedestrian(Vec3(opt.x_min + uniform(rng, -10.0, 35.0), y, 0), vx, rng));
  }
  return scene;
}

}  // namespace freeinit::sim
