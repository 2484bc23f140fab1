// The MRPT-free input checks (freeinit/input_checks.h): each says what is wrong, or nothing.
#include <freeinit/free_init.h>
#include <freeinit/input_checks.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

using namespace freeinit;
using namespace freeinit::input;

namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();

ImuSample sample(double t, const Vec3& gyro = Vec3::Zero(),
                 const Vec3& accel = Vec3(0, 0, kGravity)) {
  ImuSample s;
  s.t = t;
  s.gyro = gyro;
  s.accel = accel;
  return s;
}

LidarFrame frame(double stamp, std::size_t n, float duration = 0.1f) {
  LidarFrame f;
  f.stamp = stamp;
  for (std::size_t i = 0; i < n; ++i) {
    DopplerPoint p;
    p.p_l = Eigen::Vector3f(10.f, static_cast<float>(i) * 0.01f, 1.f);
    p.doppler = -0.5f;
    p.time_offset = duration * static_cast<float>(i) / static_cast<float>(n);
    f.points.push_back(p);
  }
  return f;
}

// 200 Hz at rest with white noise of the given std on each axis (a fixed seed).
std::vector<ImuSample> restingImu(double gyro_sigma, double accel_sigma, unsigned seed = 3) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  std::vector<ImuSample> imu;
  const Vec3 b_g(0.01, -0.005, 0.008);
  for (int k = 0; k < 40; ++k)
    imu.push_back(sample(k * 0.005, b_g + gyro_sigma * Vec3(n(rng), n(rng), n(rng)),
                         Vec3(0.1, -0.05, kGravity) + accel_sigma * Vec3(n(rng), n(rng), n(rng))));
  return imu;
}

}  // namespace

TEST(InputChecks, ImuSamplesMustBeFiniteAndIncrease) {
  const ImuSample a = sample(1.0), b = sample(1.005);
  EXPECT_FALSE(imuSampleProblem(a, nullptr));
  EXPECT_FALSE(imuSampleProblem(b, &a));
  const auto dup = imuSampleProblem(a, &a);
  ASSERT_TRUE(dup);
  EXPECT_NE(dup->find("duplicated (1.000000 after 1.000000)"), std::string::npos) << *dup;
  ASSERT_TRUE(imuSampleProblem(a, &b));
  EXPECT_NE(imuSampleProblem(a, &b)->find("goes backwards"), std::string::npos);
  EXPECT_TRUE(imuSampleProblem(sample(2.0, Vec3(kNaN, 0, 0)), &a));
  EXPECT_TRUE(imuSampleProblem(sample(kNaN), nullptr));
}

TEST(InputChecks, FramesMustIncreaseBeSortedAndNotOverlap) {
  const LidarFrame f = frame(10.0, 100);
  EXPECT_FALSE(frameOrderProblem(f, std::nullopt, std::nullopt));
  EXPECT_FALSE(frameOrderProblem(f, 9.9, 9.999));
  EXPECT_NE(frameOrderProblem(f, 10.0, 9.0)->find("duplicated"), std::string::npos);
  EXPECT_NE(frameOrderProblem(f, 10.5, 9.0)->find("goes backwards"), std::string::npos);
  // The previous frame ends after this one's first point.
  EXPECT_NE(frameOrderProblem(f, 9.9, 10.01)->find("overlaps the previous one"), std::string::npos);
  LidarFrame unsorted = f;
  std::swap(unsorted.points[3].time_offset, unsorted.points[7].time_offset);
  EXPECT_NE(frameOrderProblem(unsorted, std::nullopt, std::nullopt)->find("not sorted"),
            std::string::npos);
  sortByTime(unsorted);
  EXPECT_FALSE(frameOrderProblem(unsorted, std::nullopt, std::nullopt));
  LidarFrame nan_time = f;
  nan_time.points[5].time_offset = static_cast<float>(kNaN);
  EXPECT_NE(frameOrderProblem(nan_time, std::nullopt, std::nullopt)->find("non-finite time"),
            std::string::npos);
  EXPECT_TRUE(invalidPoint(nan_time.points[5]));
  EXPECT_FALSE(invalidPoint(f.points[5]));
}

// FreeInit refuses what the checks refuse, with the same words.
TEST(InputChecks, FreeInitEnforcesTheSameChecks) {
  FreeInit fi(FreeInitConfig{});
  fi.addImu(sample(10.0));
  try {
    fi.addImu(sample(10.0));
    FAIL() << "a duplicated IMU stamp was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("IMU timestamp duplicated"), std::string::npos);
  }
  fi.addFrame(frame(10.0, 50));
  try {
    fi.addFrame(frame(10.05, 50));
    FAIL() << "an overlapping frame was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("overlaps the previous one"), std::string::npos);
  }
}

TEST(InputChecks, DopplerAllZeroIgnoresNonFiniteValues) {
  LidarFrame f = frame(0, 10);
  EXPECT_FALSE(dopplerAllZero(f.points));
  for (auto& p : f.points) p.doppler = 0;
  EXPECT_TRUE(dopplerAllZero(f.points));
  f.points[2].doppler = std::numeric_limits<float>::quiet_NaN();
  EXPECT_TRUE(dopplerAllZero(f.points));
  f.points[3].doppler = 0.02f;
  EXPECT_FALSE(dopplerAllZero(f.points));
}

// Rest: a MEMS IMU's noise (ADIS16448-like: 0.005 rad/s, 0.05 m/s^2 per sample) and a gyro bias
// pass; motion of a hand-held platform does not.
TEST(InputChecks, RestFromTheImu) {
  const RestParams p = restParams(FreeInitConfig{});
  EXPECT_FALSE(motionProblem(restingImu(0.005, 0.05), p));
  EXPECT_FALSE(zeroDopplerProblem(restingImu(0.002, 0.02), p));

  auto turning = restingImu(0.002, 0.02);
  for (std::size_t k = 0; k < turning.size(); ++k) turning[k].gyro.z() += 0.5 * std::sin(0.3 * k);
  const auto moving = zeroDopplerProblem(turning, p);
  ASSERT_TRUE(moving);
  EXPECT_NE(moving->find("the gyro varies by"), std::string::npos) << *moving;
  EXPECT_NE(moving->find("ego-motion-compensated"), std::string::npos) << *moving;

  auto constant_turn = restingImu(0.002, 0.02);
  for (auto& s : constant_turn) s.gyro.z() += 0.3;  // a steady turn: constant, not the bias
  EXPECT_NE(motionProblem(constant_turn, p)->find("the gyro reads"), std::string::npos);

  auto shaken = restingImu(0.002, 0.02);
  for (std::size_t k = 0; k < shaken.size(); ++k) shaken[k].accel.x() += (k % 2 ? 1.0 : -1.0);
  EXPECT_NE(motionProblem(shaken, p)->find("specific force varies"), std::string::npos);

  auto falling = restingImu(0.002, 0.02);
  for (auto& s : falling) s.accel.z() -= 3.0;  // a steady vertical acceleration
  EXPECT_NE(motionProblem(falling, p)->find("specific force is"), std::string::npos);

  EXPECT_NE(zeroDopplerProblem({sample(0)}, p)->find("fewer than 2 IMU samples"),
            std::string::npos);
}

TEST(InputChecks, ImuRateAndAccelerometerUnit) {
  std::vector<ImuSample> slow;
  for (int k = 0; k < 30; ++k) slow.push_back(sample(k * 0.05));
  EXPECT_NE(imuRateProblem(slow, 50)->find("IMU rate 20 Hz is below"), std::string::npos);
  EXPECT_FALSE(imuRateProblem(slow, 10));
  std::vector<ImuSample> in_g;
  for (int k = 0; k < 30; ++k) in_g.push_back(sample(k * 0.005, Vec3::Zero(), Vec3(0, 0, 1)));
  EXPECT_NE(accelUnitProblem(in_g, false)->find("imu_accel_in_g = true"), std::string::npos);
  // Accelerations are passed after the declared unit's conversion.
  EXPECT_FALSE(accelUnitProblem(slow, false));
  EXPECT_FALSE(accelUnitProblem(slow, true));  // 1 g declared as g, times 9.81
  std::vector<ImuSample> twice;                // m/s^2 declared as g, times 9.81
  for (int k = 0; k < 30; ++k)
    twice.push_back(sample(k * 0.005, Vec3::Zero(), Vec3(0, 0, kGravity * kGravity)));
  EXPECT_NE(accelUnitProblem(twice, true)->find("already in m/s^2"), std::string::npos);
}
