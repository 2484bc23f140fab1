#include <freeinit/sim/scenario.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "preset_definitions.h"
#include "random_stream.h"

namespace freeinit::sim {
namespace {

constexpr double kDeg = M_PI / 180.0;

Mat3 rotationZyx(const Vec3& rpy_rad) {
  return (Eigen::AngleAxisd(rpy_rad.z(), Vec3::UnitZ()) *
          Eigen::AngleAxisd(rpy_rad.y(), Vec3::UnitY()) *
          Eigen::AngleAxisd(rpy_rad.x(), Vec3::UnitX()))
      .toRotationMatrix();
}

TrajectoryParams trajectoryParams(const ScenarioConfig& c, bool with_heading) {
  const MotionConfig& m = c.motion;
  TrajectoryParams p;
  p.t0 = c.t0;
  p.p_start_w = m.start_position;
  p.rpy_start = m.start_rpy_deg * kDeg;
  p.pos = m.pos;
  p.rpy = m.rpy;
  p.still_until = m.still_until;
  p.blend_duration = m.blend_duration;
  p.ramp_poly = m.ramp_poly;
  if (!m.imu_mount_rpy_deg.isZero(0.0)) p.R_rb = rotationZyx(m.imu_mount_rpy_deg * kDeg);
  if (with_heading) p.heading = m.heading_deg * kDeg;
  return p;
}

Primitive toPrimitive(const SceneObject& o) {
  const auto refl = static_cast<float>(o.reflectivity);
  if (o.shape == ObjectShape::Cylinder) {
    return makeCylinder(o.center, o.half_size.x(), o.half_size.z(), refl, o.velocity);
  }
  return makeBox(o.center, o.half_size, o.yaw, refl, o.velocity);
}

}  // namespace

ScenarioConfig::ScenarioConfig() { detail::definePreset(name, *this); }

std::shared_ptr<const AnalyticTrajectory> makeTrajectory(const ScenarioConfig& config) {
  return std::make_shared<AnalyticTrajectory>(trajectoryParams(config, true));
}

std::shared_ptr<const Scene> makeScene(const ScenarioConfig& config, const Trajectory& trajectory) {
  const SceneConfig& sc = config.scene;
  double x_min = sc.x_min, x_max = sc.x_max, horizon = sc.horizon;
  if (sc.auto_extent) {
    // The stretch of the path the body covers within the duration (in the path frame).
    const bool turned = config.motion.heading_deg != 0.0;
    const AnalyticTrajectory unturned(trajectoryParams(config, false));
    const Trajectory& path = turned ? static_cast<const Trajectory&>(unturned) : trajectory;
    x_min = 1e300;
    x_max = -1e300;
    const int n = std::max(2, static_cast<int>(std::ceil(config.duration * 20.0)) + 1);
    for (int i = 0; i < n; ++i) {
      const double x = path.at(config.t0 + config.duration * i / (n - 1)).p_w.x();
      x_min = std::min(x_min, x);
      x_max = std::max(x_max, x);
    }
    horizon = config.duration;
  }
  std::mt19937_64 rng = detail::randomStream(config.seed, detail::Stream::Scene);
  Scene scene;
  if (sc.kind == "street") {
    StreetOptions o = sc.street;
    o.x_min = x_min;
    o.x_max = x_max;
    o.duration = horizon;
    scene = makeStreetScene(o, rng);
  } else if (sc.kind == "corridor") {
    CorridorOptions o = sc.corridor;
    o.x_min = x_min;
    o.x_max = x_max;
    scene = makeCorridorScene(o, rng);
  } else if (sc.kind == "tunnel") {
    TunnelOptions o = sc.tunnel;
    o.x_min = x_min;
    o.x_max = x_max;
    scene = makeTunnelScene(o, rng);
  } else if (sc.kind == "parking") {
    ParkingOptions o = sc.parking;
    o.x_min = x_min;
    o.x_max = x_max;
    o.duration = horizon;
    scene = makeParkingScene(o, rng);
  } else {
    OpenOptions o = sc.open;
    o.x_min = x_min;
    o.x_max = x_max;
    scene = makeOpenScene(o, rng);
  }
  for (const SceneObject& o : sc.objects) scene.add(toPrimitive(o));
  if (config.motion.heading_deg == 0.0) return std::make_shared<Scene>(std::move(scene));
  // Turn the whole layout with the path frame.
  const Mat3 Rz =
      Eigen::AngleAxisd(config.motion.heading_deg * kDeg, Vec3::UnitZ()).toRotationMatrix();
  auto turned = std::make_shared<Scene>(scene.kind());
  for (Primitive p : scene.primitives()) {
    p.center_w = Rz * p.center_w;
    p.R_wo = Rz * p.R_wo;
    p.v_w = Rz * p.v_w;
    turned->add(p);
  }
  return turned;
}

Extrinsics makeExtrinsics(const ScenarioConfig& config) {
  double roll = config.lidar_rpy_deg.x() * kDeg;
  double pitch = config.lidar_rpy_deg.y() * kDeg;
  double yaw = config.lidar_rpy_deg.z() * kDeg;
  Vec3 p_bl = config.lidar_position;
  if (config.lidar_rpy_jitter_deg > 0 || config.lidar_position_jitter > 0) {
    std::mt19937_64 rng = detail::randomStream(config.seed, detail::Stream::Extrinsics);
    const double a = config.lidar_rpy_jitter_deg * kDeg, l = config.lidar_position_jitter;
    std::uniform_real_distribution<double> ang(-a, a), lev(-l, l);
    roll += ang(rng);
    pitch += ang(rng);
    yaw += ang(rng);
    // Drawn z first: the order the preset reference recordings were made with.
    const double dz = lev(rng);
    const double dy = lev(rng);
    const double dx = lev(rng);
    p_bl = Vec3(p_bl.x() + dx, p_bl.y() + dy, p_bl.z() + dz);
  }
  Extrinsics e;
  e.R_bl = (Eigen::AngleAxisd(yaw, Vec3::UnitZ()) * Eigen::AngleAxisd(pitch, Vec3::UnitY()) *
            Eigen::AngleAxisd(roll, Vec3::UnitX()))
               .toRotationMatrix();
  e.p_bl = p_bl;
  return e;
}

Extrinsics declaredExtrinsics(const ScenarioConfig& config, const Extrinsics& truth) {
  Extrinsics d = truth;
  const Vec3 err = config.declared_rotation_error_deg * kDeg;
  if (!err.isZero(0.0)) {
    d.R_bl = truth.R_bl * Eigen::AngleAxisd(err.norm(), err.normalized()).toRotationMatrix();
  }
  d.p_bl = truth.p_bl + config.declared_position_error;
  return d;
}

}  // namespace freeinit::sim
