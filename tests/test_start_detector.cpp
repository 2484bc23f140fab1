// The start decision on a platform moving at constant velocity (the IMU then sees gravity only)
// among returns from the world and from one object moving at its own constant velocity: the
// IMU cannot tell the two apart, only how much of the view each covers can.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "joint/start_detector.h"

namespace freeinit {
namespace {

constexpr double kPi = 3.14159265358979323846;

struct Scene {
  std::vector<ImuSample> imu;
  std::vector<StartPoint> points;
};

/// The j-th of 3000 returns over 0.1 s: its time and a direction of a 360 x 34 deg field of view
/// (elevation -23 to +11 deg), uniform in azimuth; the azimuth [rad, from -pi] as well.
StartPoint randomReturn(int j, std::mt19937& rng, double* azimuth = nullptr) {
  std::uniform_real_distribution<double> u01(0, 1);
  StartPoint p;
  p.t = 0.1 * j / 3000.0;
  const double az = -kPi + 2 * kPi * u01(rng);
  const double el = -0.4 + 0.6 * u01(rng);
  p.d_l = Vec3(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
  if (azimuth != nullptr) *azimuth = az;
  return p;
}

/// 0.1 s at 200 Hz, level, not rotating; `v_world` the LiDAR's velocity relative to the world
/// at the start, `v_object` relative to the object, which fills the azimuths below
/// `object_azimuth` [rad] (from -pi). Noise: gyro 0.002 rad/s, accelerometer 0.02 m/s^2, Doppler
/// 0.03 m/s. A platform in motion vibrates (`vibration` [m/s^2] at 12 Hz along x): one cruising
/// without any vibration would look to its IMU exactly like one standing.
Scene scene(const Vec3& v_world, const Vec3& v_object, double object_azimuth, unsigned seed,
            double vibration = 0.3, double imu_noise = 1.0) {
  constexpr double kOmega = 2 * 3.14159265358979323846 * 12;  // [rad/s]
  auto shake = [&](double t) -> Vec3 {                        // velocity change since t = 0
    return Vec3(vibration / kOmega * (1 - std::cos(kOmega * t)), 0, 0);
  };
  std::mt19937 rng(seed);
  std::normal_distribution<double> n01;
  Scene s;
  for (int i = 0; i <= 20; ++i) {
    ImuSample m;
    m.t = 50.0 + i / 200.0;
    m.gyro = imu_noise * 0.002 * Vec3(n01(rng), n01(rng), n01(rng));
    m.accel = Vec3(vibration * std::sin(kOmega * i / 200.0), 0, kGravity) +
              imu_noise * 0.02 * Vec3(n01(rng), n01(rng), n01(rng));
    s.imu.push_back(m);
  }
  for (int j = 0; j < 3000; ++j) {
    double az = 0;
    StartPoint p = randomReturn(j, rng, &az);
    const Vec3 v = (az < object_azimuth ? v_object : v_world) + shake(p.t);
    p.doppler = -p.d_l.dot(v) + 0.03 * n01(rng);
    s.points.push_back(p);
  }
  return s;
}

StartDecision decide(const Scene& s) {
  return decideStart(s.imu, 0, s.imu.size() - 1, s.points, Extrinsics{}, Vec3::Zero(),
                     StartDetectorParams{});
}

TEST(StartDetector, ReturnsOutOfTimeOrderAreRefused) {
  // The decision cuts the returns into the IMU intervals in one sweep: a return earlier than
  // the one before it is a caller's error, named.
  Scene s = scene(Vec3(5.0, 0.5, 0.0), Vec3::Zero(), -kPi, 2);
  std::swap(s.points[1000], s.points[1001]);
  try {
    decide(s);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("return 1001 is not in time order"), std::string::npos)
        << e.what();
  }
}

TEST(StartDetector, MovingThroughTheWorldPastASmallObject) {
  // A car passing (a tenth of the view, 8 m/s faster): the world is chosen, to its noise.
  const Vec3 v(5.0, 0.5, 0.0);
  const StartDecision d = decide(scene(v, v - Vec3(0, 8, 0), -kPi + 0.2 * kPi, 1));
  ASSERT_EQ(d.kind, StartDecision::Kind::Moving) << d.message;
  // 2,700 returns of 0.03 m/s: the velocity to well under 1 cm/s (a few sigma of the 6-dof fit
  // with gravity free over 0.1 s).
  EXPECT_LT((d.chosen.v_b0 - v).norm(), 0.02);
  EXPECT_LT((d.chosen.g_b0 - Vec3(0, 0, -kGravity)).norm(), 0.5);
  EXPECT_GT(d.chosen.coverage, 0.8);
}

TEST(StartDetector, AnObjectFillingMostOfTheViewIsAmbiguous) {
  // A bus alongside fills three quarters of the view: its motion covers more of it than the
  // world's, and the IMU, seeing only gravity, agrees with both. Choosing the bus would be a
  // confident 3 m/s error; the decision must say it cannot tell.
  const Vec3 v(4.0, 0.0, 0.0);
  const StartDecision d = decide(scene(v, v - Vec3(3, 1, 0), kPi / 2, 2));
  EXPECT_EQ(d.kind, StartDecision::Kind::Ambiguous) << d.message;
  EXPECT_NE(d.message.find("moving object"), std::string::npos) << d.message;
  ASSERT_GE(d.hypotheses.size(), 2u);
}

/// A scene with ranges, the sensor 1.5 m above level ground: a return below the horizon hits the
/// ground within 12 m (static), any other one a wall 12 m away (static), unless `object`
/// (azimuth, elevation [rad]) gives the range [m] at which an object moving with the platform's
/// velocity minus `v_object_rel` is hit first (<= 0: not hit). The IMU and noise as scene().
Scene sceneOverGround(const Vec3& v_world, const Vec3& v_object_rel, unsigned seed,
                      const std::function<double(double, double)>& object) {
  Scene s = scene(v_world, v_world, -kPi, seed);
  std::mt19937 rng(seed + 1000);
  std::normal_distribution<double> n01;
  constexpr double kHeight = 1.5, kWall = 12.0;
  for (StartPoint& p : s.points) {
    const double az = std::atan2(p.d_l.y(), p.d_l.x());
    const double el = std::asin(p.d_l.z());
    const double ground = el < 0 ? kHeight / std::sin(-el) : kWall;
    p.range = std::min(ground, kWall);
    const double r = object(az, el);
    if (r > 0 && r < p.range) {
      p.range = r;
      p.doppler = -p.d_l.dot(v_world - v_object_rel) + 0.03 * n01(rng);
    }
  }
  return s;
}

TEST(StartDetector, ATruckFillingTheViewAboveTheGroundIsAmbiguous) {
  // Walking at 1.5 m/s past a truck that drives by at 5 m/s 3 m away and fills the whole view
  // but for the ground in front of it (the lowest 14 % of the returns): the truck's motion
  // covers far more of the view than the world's, too much for the coverage rule to see a
  // contender; the IMU agrees with both. The ground does not move: the truck is not the world.
  const Vec3 v(1.5, 0.5, 0.0);
  const Scene s = sceneOverGround(
      v, Vec3(0, 5, 0), 4, [](double, double el) { return el > -0.33 ? 3.0 / std::cos(el) : 0.0; });
  const StartDecision d = decide(s);
  EXPECT_EQ(d.kind, StartDecision::Kind::Ambiguous) << d.message;
  EXPECT_NE(d.message.find("ground"), std::string::npos) << d.message;
  // Without the ground check, the truck's motion is the answer: 5 m/s off.
  StartDetectorParams no_ground;
  no_ground.ground_share = 0;
  const StartDecision w =
      decideStart(s.imu, 0, s.imu.size() - 1, s.points, Extrinsics{}, Vec3::Zero(), no_ground);
  ASSERT_EQ(w.kind, StartDecision::Kind::Moving) << w.message;
  EXPECT_GT((w.chosen.v_b0 - v).norm(), 4.0);
}

TEST(StartDetector, ACarDownToTheGroundIsNotTheWorld) {
  // A car passing 3 m away across a fifth of the azimuths, its body down to the ground: the
  // lowest returns are the ground's and the car's bottom, mixed. The world is chosen.
  const Vec3 v(1.5, 0.5, 0.0);
  const StartDecision d = decide(sceneOverGround(v, Vec3(0, 8, 0), 5, [](double az, double el) {
    if (az > -kPi + 0.4 * kPi || el > 0.2) return 0.0;
    return 3.0 / std::cos(el);  // a vertical side 3 m away, hit before the ground
  }));
  ASSERT_EQ(d.kind, StartDecision::Kind::Moving) << d.message;
  EXPECT_LT((d.chosen.v_b0 - v).norm(), 0.02);
}

TEST(StartDetector, RestWinsWhenTheImuShowsRestDespiteAWalker) {
  // Standing, with a person walking by across a fifth of the view: rest.
  const StartDecision d =
      decide(scene(Vec3::Zero(), Vec3(1.2, 0.4, 0), -kPi + 0.4 * kPi, 3, /*vibration=*/0.0));
  ASSERT_EQ(d.kind, StartDecision::Kind::Rest) << d.message;
  EXPECT_TRUE(d.imu_still);
  EXPECT_LT(d.chosen.v_b0.norm(), 1e-6);
}

TEST(StartDetector, RestWhateverTheImuNoiseLevel) {
  // The IMU 4x noisier or 4x quieter than configured (0.002 rad/s, 0.02 m/s^2): its samples are
  // still white, and rest is decided by that shape, not by the level. Standing with a walker
  // (seeds 3-12): rest every time.
  for (const double scale : {0.25, 4.0}) {
    for (unsigned seed = 3; seed < 13; ++seed) {
      const StartDecision d =
          decide(scene(Vec3::Zero(), Vec3(1.2, 0.4, 0), -kPi + 0.4 * kPi, seed, 0.0, scale));
      ASSERT_EQ(d.kind, StartDecision::Kind::Rest)
          << "x" << scale << " seed " << seed << ": " << d.message;
      EXPECT_TRUE(d.imu_still);
      // The span's 20 differences per axis give the level to ~16 % (1 sigma).
      EXPECT_NEAR(d.imu_rest.gyro.sigma() / (0.002 * scale), 1.0, 0.5) << seed;
      EXPECT_NEAR(d.imu_rest.accel.sigma() / (0.02 * scale), 1.0, 0.5) << seed;
    }
  }
}

TEST(StartDetector, AVibratingPlatformIsNotAtRestWhateverItsNoise) {
  // Cruising at 4 m/s with a 12 Hz vibration of 0.3 m/s^2 and an IMU 4x noisier than
  // configured (0.08 m/s^2, still a quarter of the vibration): the samples are not white, the
  // IMU does not show rest, and the world's motion is chosen.
  const Vec3 v(4.0, 0.0, 0.0);
  const StartDecision d = decide(scene(v, v - Vec3(0, 8, 0), -kPi + 0.2 * kPi, 1, 0.3, 4.0));
  EXPECT_FALSE(d.imu_rest.accel_white);
  EXPECT_FALSE(d.imu_still);
  ASSERT_EQ(d.kind, StartDecision::Kind::Moving) << d.message;
  EXPECT_LT((d.chosen.v_b0 - v).norm(), 0.02);
}

TEST(StartDetector, TurningWithAGyroBiasAndALeverArm) {
  // 0.1 s at 200 Hz driving at 10 m/s through a left turn of 0.8 rad/s, the LiDAR mounted
  // 0.5 m from the IMU and turned by 90 degrees about z, the gyro off by 0.02 rad/s about z (the
  // detector is told no bias). The returns see the body velocity turn by 4.6 degrees over the
  // span and the lever arm add 0.36 m/s; the heading the gyro integrates drifts by 2 mrad, a
  // velocity change linear in time that the fit's gravity and gyro-bias terms take up.
  constexpr double kOmega = 2 * kPi * 12;  // [rad/s] vibration, 0.3 m/s^2 along x
  constexpr double kVib = 0.3;
  const Vec3 omega(0, 0, 0.8), v0(10, 0, 0), b_g(0, 0, 0.02);
  Extrinsics ext;
  ext.R_bl = Eigen::AngleAxisd(kPi / 2, Vec3::UnitZ()).toRotationMatrix();
  ext.p_bl = Vec3(0.4, -0.2, 0.3);
  // Body-frame velocity v0 + s(t) e_x, constant rotation about the vertical: the specific force
  // is ds/dt e_x + omega x v_b - g_b with g_b = (0, 0, -g) throughout.
  auto v_b = [&](double t) {
    return Vec3(v0 + Vec3(kVib / kOmega * (1 - std::cos(kOmega * t)), 0, 0));
  };
  std::mt19937 rng(5);
  std::normal_distribution<double> n01;
  std::vector<ImuSample> imu;
  for (int i = 0; i <= 22; ++i) {
    const double t = i / 200.0;
    ImuSample m;
    m.t = 50.0 + t;
    m.gyro = omega + b_g + 0.002 * Vec3(n01(rng), n01(rng), n01(rng));
    m.accel = Vec3(kVib * std::sin(kOmega * t), 0, 0) + omega.cross(v_b(t)) + Vec3(0, 0, kGravity) +
              0.02 * Vec3(n01(rng), n01(rng), n01(rng));
    imu.push_back(m);
  }
  std::vector<StartPoint> points;
  for (int j = 0; j < 3000; ++j) {
    StartPoint p = randomReturn(j, rng);
    const Vec3 v_lidar_b = v_b(p.t) + omega.cross(ext.p_bl);  // LiDAR velocity, body axes
    p.doppler = -(ext.R_bl * p.d_l).dot(v_lidar_b) + 0.03 * n01(rng);
    points.push_back(p);
  }
  const StartDecision d = decideStart(imu, 0, 20, points, ext, Vec3::Zero(), StartDetectorParams{});
  ASSERT_EQ(d.kind, StartDecision::Kind::Moving) << d.message;
  // Within 4 of the decision's own sigmas per axis (its covariance carries the bias).
  for (int k = 0; k < 3; ++k)
    EXPECT_LT(std::abs(d.chosen.v_b0(k) - v0(k)), 4 * std::sqrt(d.chosen.cov(k, k))) << k;
  EXPECT_LT((d.chosen.g_b0 - Vec3(0, 0, -kGravity)).norm(), 0.5);
}

TEST(StartDetector, TheNoiseOfAFitWithTheClockOffset) {
  // Driving at 10 m/s with a 9 Hz vibration of 4 m/s^2, the LiDAR clock 10 ms ahead of the
  // IMU's (undeclared, prior std 10 ms): a fit that ignores the offset leaves residuals of up to
  // 0.04 m/s on top of the 0.03 m/s Doppler noise, and its robust scale comes out 8 % high. The
  // motion fitted with the offset reports the noise of its own residuals (the filter starts
  // from it) within 6 % (4 times the ~1.5 % of a robust scale of ~2,900 residuals), and the
  // offset within 3 of its sigmas.
  constexpr double kOmega = 2 * kPi * 9, kVib = 4.0, kOffset = 0.010;
  const Vec3 v0(10, 0, 0);
  auto v_b = [&](double t) {
    return Vec3(v0 + Vec3(kVib / kOmega * (1 - std::cos(kOmega * t)), 0, 0));
  };
  std::mt19937 rng(8);
  std::normal_distribution<double> n01;
  std::vector<ImuSample> imu;
  for (int i = 0; i <= 24; ++i) {
    const double t = i / 200.0;
    ImuSample m;
    m.t = 50.0 + t;
    m.gyro = 0.002 * Vec3(n01(rng), n01(rng), n01(rng));
    m.accel =
        Vec3(kVib * std::sin(kOmega * t), 0, kGravity) + 0.02 * Vec3(n01(rng), n01(rng), n01(rng));
    imu.push_back(m);
  }
  std::vector<StartPoint> points;
  for (int j = 0; j < 3000; ++j) {
    StartPoint p = randomReturn(j, rng);  // p.t: the LiDAR's stamp, kOffset after the truth
    p.doppler = -p.d_l.dot(v_b(p.t - kOffset)) + 0.03 * n01(rng);
    points.push_back(p);
  }
  StartDetectorParams params;
  params.time_offset_sigma = 0.01;
  const StartDecision d = decideStart(imu, 0, 20, points, Extrinsics{}, Vec3::Zero(), params);
  ASSERT_EQ(d.kind, StartDecision::Kind::Moving) << d.message;
  ASSERT_GT(d.chosen.time_offset_sigma, 0.0);
  EXPECT_LT(std::abs(d.chosen.time_offset - kOffset), 3 * d.chosen.time_offset_sigma)
      << d.chosen.time_offset << " s, sigma " << d.chosen.time_offset_sigma;
  EXPECT_NEAR(d.chosen.residual_scale / 0.03, 1.0, 0.06) << d.chosen.residual_scale;
}

TEST(StartDetector, AFastTurnBetweenTwoImuSamples) {
  // A tight turn at 12 to 14 rad/s sampled by the IMU at 20 Hz: over 0.6 rad between two
  // samples, beyond what the series of the rotation within an interval covers (the sine and the
  // cosine take over). The body velocity is 3 m/s along x throughout and the rate grows linearly
  // about the vertical (what the IMU's cubic interpolation follows exactly), the LiDAR 0.3 m ahead
  // of the IMU. (A constant rate would look to the IMU like rest.)
  const Vec3 v_b(3, 0, 0);
  const auto omega = [](double t) { return Vec3(0, 0, 12 + 20 * t); };
  Extrinsics ext;
  ext.p_bl = Vec3(0.3, 0, 0);
  std::vector<ImuSample> imu;
  for (int i = 0; i <= 4; ++i) {
    ImuSample m;
    m.t = 50.0 + i / 20.0;
    m.gyro = omega(i / 20.0);
    m.accel = m.gyro.cross(v_b) + Vec3(0, 0, kGravity);
    imu.push_back(m);
  }
  std::mt19937 rng(6);
  std::normal_distribution<double> n01;
  std::vector<StartPoint> points;
  for (int j = 0; j < 3000; ++j) {
    StartPoint p = randomReturn(j, rng);
    p.doppler = -p.d_l.dot(v_b + omega(p.t).cross(ext.p_bl)) + 0.03 * n01(rng);
    points.push_back(p);
  }
  const StartDecision d = decideStart(imu, 0, 2, points, ext, Vec3::Zero(), StartDetectorParams{});
  ASSERT_EQ(d.kind, StartDecision::Kind::Moving) << d.message;
  EXPECT_LT((d.chosen.v_b0 - v_b).norm(), 0.02);
  EXPECT_LT((d.chosen.g_b0 - Vec3(0, 0, -kGravity)).norm(), 0.5);
}

TEST(StartDetector, ReturnsInOnePlaneAreDegenerate) {
  // Every return in the horizontal plane: the vertical velocity is not constrained.
  Scene s = scene(Vec3(3, 0, 0), Vec3(3, 0, 0), -kPi, 4, /*vibration=*/0.0);
  for (StartPoint& p : s.points) {
    p.d_l.z() = 0;
    p.d_l.normalize();
    p.doppler = -p.d_l.dot(Vec3(3, 0, 0));
  }
  EXPECT_EQ(decide(s).kind, StartDecision::Kind::Degenerate);
}

}  // namespace
}  // namespace freeinit
