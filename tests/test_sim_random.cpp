// Randomized scenarios: deterministic per seed, drawn as documented in random_scenario.h, and as
// exactly consistent with their ground truth as the presets (IMU at every rate, Doppler of static
// and moving points, labels, clock offset, declared calibration); the misdeclaration an
// evaluation draws per run, apart from the scenario.
#include <freeinit/sim/random_scenario.h>
#include <freeinit/sim/scenario_ini.h>
#include <freeinit/sim/scene.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "test_sim_imu_integration.h"
#include "test_sim_recording_hash.h"

namespace freeinit::sim {
namespace {

constexpr double kDeg = M_PI / 180.0;

struct Stats {
  long n = 0;
  double sum = 0, sum2 = 0;
  void add(double x) {
    ++n;
    sum += x;
    sum2 += x * x;
  }
  double mean() const { return sum / static_cast<double>(n); }
  double std() const { return std::sqrt(sum2 / static_cast<double>(n) - mean() * mean()); }
};

/// A count of n Bernoulli(p) draws within 4 standard deviations of n p.
void expectShare(long count, long n, double p, const std::string& what) {
  const double sd = std::sqrt(n * p * (1 - p));
  EXPECT_NEAR(static_cast<double>(count), n * p, 4.0 * sd) << what << ": " << count << " of " << n;
}

ScenarioConfig small(std::uint64_t seed, double duration, int max_points) {
  ScenarioConfig c = randomScenario(seed);
  c.duration = duration;
  c.points_per_frame = std::min(c.points_per_frame, max_points);
  return c;
}

/// The first seeds (from 1) whose draw satisfies pred.
template <typename Pred>
std::vector<std::uint64_t> seedsWhere(Pred pred, std::size_t count, std::uint64_t limit = 2000) {
  std::vector<std::uint64_t> out;
  for (std::uint64_t s = 1; s < limit && out.size() < count; ++s)
    if (pred(drawRandomScenario(s))) out.push_back(s);
  return out;
}

TEST(SimRandom, DeterministicPerSeed) {
  for (std::uint64_t s : {5u, 77u}) {
    const RandomScenario a = drawRandomScenario(s), b = drawRandomScenario(s);
    EXPECT_EQ(scenarioIni(a.config), scenarioIni(b.config));
    EXPECT_EQ(describe(a.info), describe(b.info));
    const ScenarioConfig c = small(s, 0.3, 3000);
    EXPECT_EQ(test::firstDifference(simulate(c), simulate(c)), "") << s;
  }
  const ScenarioConfig c5 = randomScenario(5), c6 = randomScenario(6);
  EXPECT_NE(scenarioIni(c5), scenarioIni(c6));
  EXPECT_NE(c5.b_g, c6.b_g);
  EXPECT_EQ(c5.name, "random");
  EXPECT_EQ(c5.seed, 5u);
}

// What an evaluation hands the estimator instead of the truth: deterministic per seed, exactly a
// fixed value, log-uniform factors and uniform offsets of either sign over their ranges, each
// quantity's draw independent of the other ranges, and the scenario (so the recording) untouched.
TEST(SimRandom, MisdeclarationIsDrawnApartFromTheScenario) {
  MisdeclarationRanges ranges;
  ranges.imu_noise_factor = {0.25, 4};
  ranges.doppler_noise_factor = {0.5, 2};
  ranges.time_offset = {0.001, 0.01};
  const Misdeclaration a = drawMisdeclaration(7, ranges), b = drawMisdeclaration(7, ranges);
  EXPECT_EQ(a.imu_noise_factor, b.imu_noise_factor);
  EXPECT_EQ(a.doppler_noise_factor, b.doppler_noise_factor);
  EXPECT_EQ(a.time_offset, b.time_offset);
  // The defaults: the truth.
  const Misdeclaration none = drawMisdeclaration(7, {});
  EXPECT_EQ(none.imu_noise_factor, 1.0);
  EXPECT_EQ(none.doppler_noise_factor, 1.0);
  EXPECT_EQ(none.time_offset, 0.0);
  Stats log_imu, log_doppler;
  long positive = 0, n = 0;
  for (std::uint64_t seed = 1; seed <= 2000; ++seed, ++n) {
    const Misdeclaration m = drawMisdeclaration(seed, ranges);
    ASSERT_GE(m.imu_noise_factor, 0.25);
    ASSERT_LE(m.imu_noise_factor, 4.0);
    ASSERT_GE(m.doppler_noise_factor, 0.5);
    ASSERT_LE(m.doppler_noise_factor, 2.0);
    ASSERT_GE(std::abs(m.time_offset), 0.001);
    ASSERT_LE(std::abs(m.time_offset), 0.01);
    log_imu.add(std::log(m.imu_noise_factor));
    log_doppler.add(std::log(m.doppler_noise_factor));
    if (m.time_offset > 0) ++positive;
    // Another Doppler range or a fixed offset leaves the IMU factor of the seed as it was.
    MisdeclarationRanges other = ranges;
    other.doppler_noise_factor = {3, 3};
    other.time_offset = {0.008, 0.008};
    const Misdeclaration o = drawMisdeclaration(seed, other);
    ASSERT_EQ(o.imu_noise_factor, m.imu_noise_factor);
    ASSERT_EQ(o.doppler_noise_factor, 3.0);
    ASSERT_EQ(std::abs(o.time_offset), 0.008);
    ASSERT_EQ(o.time_offset > 0, m.time_offset > 0);
  }
  // log f uniform over [log lo, log hi]: mean at the log of the geometric mean, sd range/sqrt(12).
  const double sd_imu = std::log(16.0) / std::sqrt(12.0),
               sd_doppler = std::log(4.0) / std::sqrt(12.0);
  EXPECT_NEAR(log_imu.mean(), 0.0, 4 * sd_imu / std::sqrt(2000.0));
  EXPECT_NEAR(log_imu.std(), sd_imu, 0.05 * sd_imu);
  EXPECT_NEAR(log_doppler.mean(), 0.0, 4 * sd_doppler / std::sqrt(2000.0));
  expectShare(positive, n, 0.5, "positive offsets");
  // Bad ranges.
  for (const DrawRange bad : {DrawRange{2, 1}, DrawRange{0, 1}, DrawRange{std::nan(""), 1}}) {
    MisdeclarationRanges r;
    r.imu_noise_factor = bad;
    EXPECT_THROW(drawMisdeclaration(1, r), std::invalid_argument);
  }
  MisdeclarationRanges r;
  r.time_offset = {-0.001, 0.001};
  EXPECT_THROW(drawMisdeclaration(1, r), std::invalid_argument);
  // The scenario of a seed is not drawn from this stream: the same before and after.
  const std::string before = scenarioIni(randomScenario(7));
  drawMisdeclaration(7, ranges);
  EXPECT_EQ(scenarioIni(randomScenario(7)), before);
}

// 300 draws (no simulation): shares within 4 binomial sigmas of the documented probabilities,
// every range respected and covered.
TEST(SimRandom, DistributionCoversWhatItClaims) {
  constexpr long kN = 300;
  std::map<std::string, long> platform, start, order;
  std::map<std::string, std::set<std::string>> scenes;
  std::set<double> imu_rates, frame_rates;
  std::set<int> lines;
  long static_starts = 0, with_movers = 0, wrong = 0, quick = 0, wrong_time = 0, wrong_rot = 0,
       wrong_pos = 0, forward = 0, fast_hand = 0, rotating = 0;
  double max_tilt[3] = {0, 0, 0}, max_peak = 0, max_peak_hand = 0, max_speed[3] = {0, 0, 0};
  int min_points = 1 << 30, max_points = 0;
  Stats bg, ba, rbl;
  std::vector<double> extrinsic_angles;
  for (long s = 1; s <= kN; ++s) {
    const RandomScenario r = drawRandomScenario(static_cast<std::uint64_t>(s));
    const RandomScenarioInfo& i = r.info;
    const ScenarioConfig& c = r.config;
    const int k = static_cast<int>(i.platform);
    ++platform[platformName(i.platform)];
    ++start[i.start];
    scenes[platformName(i.platform)].insert(i.scene);
    static_starts += i.static_start;
    with_movers += i.dynamic_near_standing_sensor;
    EXPECT_EQ(i.static_start, i.rest_duration >= 0.6) << s;
    EXPECT_GE(i.rest_duration, 0.0);
    EXPECT_LE(i.rest_duration, 2.0);
    if (i.start == "starting" && i.rest_duration < 0.5) ++quick;
    if (i.start == "moving") {
      EXPECT_LE(c.motion.blend_duration, 0.0) << s;  // moving at once
    }
    EXPECT_LE(i.base_tilt_deg, 30.0 + 1e-9) << s;
    max_tilt[k] = std::max(max_tilt[k], i.base_tilt_deg);
    EXPECT_LE(i.peak_angular_rate, 12.0) << s;
    max_peak = std::max(max_peak, i.peak_angular_rate);
    if (i.motion == "rotating") {
      ++rotating;
      fast_hand += i.peak_angular_rate > 6.0;
      max_peak_hand = std::max(max_peak_hand, i.peak_angular_rate);
    }
    max_speed[k] = std::max(max_speed[k], i.speed);
    EXPECT_LE(i.speed, 30.0);
    // Scan.
    lines.insert(c.lines);
    ++order[std::to_string(static_cast<int>(c.line_order))];
    forward += c.line_direction == LineDirection::Forward;
    min_points = std::min(min_points, c.points_per_frame);
    max_points = std::max(max_points, c.points_per_frame);
    frame_rates.insert(c.frame_rate);
    EXPECT_GE(c.hfov_deg, 90.0);
    EXPECT_LE(c.hfov_deg, 125.0);
    EXPECT_GE(c.vfov_deg, 20.0);
    EXPECT_LE(c.vfov_deg, 40.0);
    // IMU: white noise densities and biases within the documented ranges.
    imu_rates.insert(c.imu_rate);
    const double root = std::sqrt(c.imu_rate);
    EXPECT_GE(c.gyro_sigma / root, 5e-5 * (1 - 1e-12));
    EXPECT_LE(c.gyro_sigma / root, 3e-4 * (1 + 1e-12));
    EXPECT_GE(c.accel_sigma / root, 6e-4 * (1 - 1e-12));
    EXPECT_LE(c.accel_sigma / root, 3e-3 * (1 + 1e-12));
    EXPECT_GE(std::min(c.gyro_sigma_scale.minCoeff(), c.accel_sigma_scale.minCoeff()), 0.8);
    EXPECT_LE(std::max(c.gyro_sigma_scale.maxCoeff(), c.accel_sigma_scale.maxCoeff()), 1.2);
    EXPECT_FALSE(c.random_biases);
    for (int a = 0; a < 3; ++a) {
      EXPECT_LE(std::abs(c.b_g[a]), 2 * 0.015);  // 2 x gyro_bias_sigma0
      EXPECT_LE(std::abs(c.b_a[a]), 2 * 0.1);    // 2 x accel_bias_prior_sigma
      bg.add(c.b_g[a]);
      ba.add(c.b_a[a]);
    }
    // Calibration.
    extrinsic_angles.push_back(i.extrinsic_rotation_deg);
    rbl.add(i.extrinsic_rotation_deg);
    EXPECT_LE(i.lever_arm, 0.3 + 1e-12);
    EXPECT_GE(i.lever_arm, 0.02 - 1e-12);
    wrong += i.calibration_wrong;
    if (i.calibration_wrong) {
      EXPECT_TRUE(i.lidar_time_offset != 0 || i.rotation_error_deg > 0 || i.position_error > 0);
      wrong_time += i.lidar_time_offset != 0;
      wrong_rot += i.rotation_error_deg > 0;
      wrong_pos += i.position_error > 0;
    } else {
      EXPECT_EQ(i.lidar_time_offset, 0.0);
      EXPECT_EQ(i.rotation_error_deg, 0.0);
      EXPECT_EQ(i.position_error, 0.0);
    }
    EXPECT_LE(std::abs(i.lidar_time_offset), 0.010);
    EXPECT_LE(i.rotation_error_deg, 2.0 + 1e-9);
    EXPECT_LE(i.position_error, 0.03 + 1e-12);
  }
  std::printf(
      "platforms: handheld %ld, wheeled %ld, vehicular %ld; static starts %ld (%ld with "
      "movers in view); wrong calibration %ld\n",
      platform["handheld"], platform["wheeled"], platform["vehicular"], static_starts, with_movers,
      wrong);
  expectShare(platform["handheld"], kN, 0.4, "handheld");
  expectShare(platform["wheeled"], kN, 0.3, "wheeled");
  expectShare(platform["vehicular"], kN, 0.3, "vehicular");
  for (const auto& [name, n] : platform) EXPECT_GE(n, kN / 5) << name;  // every class >= 20 %
  expectShare(start["moving"], kN, 0.4, "moving from the first instant");
  expectShare(start["starting"], kN, 0.2, "starting within 0.6 s");
  expectShare(static_starts, kN, 0.4, "static starts");
  EXPECT_GE(static_starts, kN / 4);
  EXPECT_GE(with_movers, 50);
  EXPECT_GT(with_movers, static_starts / 2);  // most static starts
  EXPECT_GT(quick, 0);
  EXPECT_EQ(scenes["handheld"].size(), 5u);
  EXPECT_EQ(scenes["wheeled"].size(), 5u);
  EXPECT_EQ(scenes["vehicular"], (std::set<std::string>{"street", "parking", "tunnel", "open"}));
  EXPECT_GT(max_tilt[0], 25.0);  // handheld up to 30 deg
  EXPECT_LE(max_tilt[1], 12.0 + 1e-9);
  EXPECT_LE(max_tilt[2], 8.0 + 1e-9);
  EXPECT_GT(max_peak_hand, 10.0);
  EXPECT_GT(fast_hand, rotating / 5);
  EXPECT_GT(max_speed[2], 25.0);
  EXPECT_LE(max_speed[1], 5.0);
  EXPECT_EQ(lines, (std::set<int>{16, 32, 48, 64, 96, 128}));
  EXPECT_GE(min_points, 10000);
  EXPECT_LE(max_points, 120000);
  EXPECT_LT(min_points, 12000);
  EXPECT_GT(max_points, 100000);
  EXPECT_EQ(frame_rates, (std::set<double>{10.0, 12.5, 15.0, 20.0}));
  EXPECT_EQ(imu_rates, (std::set<double>{100.0, 150.0, 200.0, 250.0, 400.0}));
  EXPECT_EQ(order.size(), 3u);
  expectShare(forward, kN, 0.4, "every line the same way");
  // N(0, s) truncated at 2 s has std 0.880 s; 900 draws: standard error ~2.4 %.
  EXPECT_NEAR(bg.std(), 0.880 * 0.015, 0.1 * 0.880 * 0.015);
  EXPECT_NEAR(ba.std(), 0.880 * 0.1, 0.1 * 0.880 * 0.1);
  expectShare(wrong, kN, 0.25, "wrong calibration");
  EXPECT_GT(std::min({wrong_time, wrong_rot, wrong_pos}), 0);
  std::sort(extrinsic_angles.begin(), extrinsic_angles.end());
  EXPECT_GT(extrinsic_angles[kN / 2], 20.0);  // tens of degrees
  EXPECT_LT(extrinsic_angles.back(), 75.0);
}

/// A primitive containing q (inflated by margin) at relative time tau.
bool inside(const Primitive& p, const Vec3& q, double tau, double margin) {
  const Vec3 c = p.centerAt(tau);
  if (p.type == PrimitiveType::Box)
    return ((p.R_wo.transpose() * (q - c)).cwiseAbs() - p.half_size).maxCoeff() < margin;
  if (p.type == PrimitiveType::Cylinder)
    return std::hypot(q.x() - c.x(), q.y() - c.y()) < p.half_size.x() + margin &&
           std::abs(q.z() - c.z()) < p.half_size.z() + margin;
  return false;
}

// The IMU and the LiDAR never sit inside an object, and moving objects keep clear of them, over
// the default 3 s of 300 scenarios.
TEST(SimRandom, SensorsStayClearOfTheScene) {
  for (std::uint64_t s = 1; s <= 300; ++s) {
    const ScenarioConfig c = randomScenario(s);
    const auto traj = makeTrajectory(c);
    const auto scene = makeScene(c, *traj);
    const Extrinsics e = makeExtrinsics(c);
    for (double tau = 0; tau <= c.duration; tau += 0.1) {
      const TruthState st = traj->at(c.t0 + tau);
      for (const Vec3& q : {st.p_w, Vec3(st.p_w + st.R_wb * e.p_bl)}) {
        for (const Primitive& p : scene->primitives()) {
          ASSERT_FALSE(inside(p, q, tau, p.isDynamic() ? 0.25 : 0.0))
              << "seed " << s << " tau " << tau << " " << describe(drawRandomScenario(s).info)[0];
        }
      }
    }
  }
}

// A standing sensor among people or vehicles placed to move through its view: it is at rest and
// its first 0.6 s hold points on them (the descriptor's promise, checked by simulating).
TEST(SimRandom, StaticStartsAmongMoversSeeThemMove) {
  const auto seeds =
      seedsWhere([](const RandomScenario& r) { return r.info.dynamic_near_standing_sensor; }, 8);
  ASSERT_EQ(seeds.size(), 8u);
  int close_people = 0;
  for (std::uint64_t s : seeds) {
    const Recording rec = simulate(small(s, 0.6, 8000));
    const double t0 = rec.config.t0;
    for (const ImuSample& m : rec.imu) {
      const TruthState st = rec.truth(m.t);
      EXPECT_EQ(st.v_w, Vec3::Zero()) << s;
      EXPECT_EQ(st.omega_b, Vec3::Zero()) << s;
    }
    const double share = movingPointShare(rec, t0, t0 + 0.6);
    std::printf("seed %llu: %s; moving share %.4f\n", static_cast<unsigned long long>(s),
                describe(drawRandomScenario(s).info)[0].c_str(), share);
    EXPECT_GT(share, 0.0) << s;
    // People crossing within 5 m: their points are that close.
    bool person_close = false;
    const TruthState s0 = rec.truth(t0);
    for (const SceneObject& o : rec.config.scene.objects) {
      if (o.label != "person") continue;
      const Vec3 c = o.center + 0.3 * o.velocity;
      Vec3 d = c - s0.p_w;  // path frame (heading turns the world, not the distance)
      d.z() = 0;
      person_close = person_close || d.norm() < 5.0;
    }
    if (!person_close) continue;
    ++close_people;
    long close_moving = 0;
    for (std::size_t f = 0; f < rec.frames.size(); ++f)
      for (std::size_t i = 0; i < rec.frames[f].points.size(); ++i)
        close_moving +=
            rec.labels[f][i] == PointLabel::Dynamic && rec.frames[f].points[i].p_l.norm() < 6.0f;
    EXPECT_GT(close_moving, 0) << s;
  }
  EXPECT_GT(close_people, 0);
}

// Every point re-cast from the true LiDAR pose at its true time (the stamp minus the clock offset
// plus its time offset) hits the primitive its label says (moving: Dynamic), and its Doppler is
// the true range rate, moving objects included, up to the injected N(0, doppler_sigma).
void checkPointsAgainstTruth(std::uint64_t seed) {
  const Recording rec = simulate(small(seed, 0.4, 6000));
  const Scene& scene = *rec.scene;
  const Extrinsics& e = rec.extrinsics;
  const double sigma = rec.config.doppler_sigma;
  Stats stat, moving;
  long mismatched = 0, n = 0;
  for (std::size_t f = 0; f < rec.frames.size(); ++f) {
    const LidarFrame& fr = rec.frames[f];
    for (std::size_t i = 0; i < fr.points.size(); ++i) {
      const DopplerPoint& pt = fr.points[i];
      const PointLabel label = rec.labels[f][i];
      if (label == PointLabel::Outlier) continue;
      ++n;
      const double t = rec.pointTime(fr, pt);
      const TruthState s = rec.truth(t);
      const Mat3 R_wl = s.R_wb * e.R_bl;
      const Vec3 p_wl = s.p_w + s.R_wb * e.p_bl;
      const Vec3 v_wl = s.v_w + s.R_wb * s.omega_b.cross(e.p_bl);
      const Vec3 d_w = R_wl * pt.p_l.cast<double>().normalized();
      RayHit hit;
      if (!scene.castRay(p_wl, d_w, t - rec.config.t0, rec.config.max_range + 1.0, hit)) {
        ++mismatched;
        continue;
      }
      const Primitive& prim = scene.primitives()[static_cast<std::size_t>(hit.primitive)];
      if (prim.isDynamic() != (label == PointLabel::Dynamic) ||
          std::abs(hit.range - pt.p_l.cast<double>().norm()) > 8.0 * rec.config.range_sigma) {
        ++mismatched;  // a float-rounded direction grazing an edge can switch surfaces
        continue;
      }
      const double r = pt.doppler - d_w.dot(prim.v_w - v_wl);
      (label == PointLabel::Dynamic ? moving : stat).add(r);
    }
  }
  std::printf(
      "seed %llu (clock offset %.4f s): %ld points, %ld moving; static residual std %.5f, "
      "moving %.5f (sigma %.5f); %ld mismatched\n",
      static_cast<unsigned long long>(seed), rec.lidar_time_offset, n, moving.n, stat.std(),
      moving.n > 0 ? moving.std() : 0.0, sigma, mismatched);
  ASSERT_GT(stat.n, 10000);
  EXPECT_LT(static_cast<double>(mismatched) / n, 1e-3);
  // Sample std: relative standard error 1/sqrt(2N) < 0.7 %; mean: 5 standard errors.
  EXPECT_NEAR(stat.std(), sigma, 0.05 * sigma);
  EXPECT_LT(std::abs(stat.mean()), 5.0 * sigma / std::sqrt(static_cast<double>(stat.n)));
  if (moving.n > 200) {
    EXPECT_NEAR(moving.std(), sigma, 0.25 * sigma);
    EXPECT_LT(std::abs(moving.mean()), 5.0 * sigma / std::sqrt(static_cast<double>(moving.n)));
  }
}

TEST(SimRandom, PointsMatchTheTruthMovingPlatformWithClockOffset) {
  const auto seeds = seedsWhere(
      [](const RandomScenario& r) {
        return r.info.lidar_time_offset != 0 && r.info.movers_in_view > 0 && !r.info.static_start &&
               r.info.speed > 1.0;
      },
      1);
  ASSERT_EQ(seeds.size(), 1u);
  checkPointsAgainstTruth(seeds[0]);
}

TEST(SimRandom, PointsMatchTheTruthRotatingByHand) {
  const auto seeds = seedsWhere(
      [](const RandomScenario& r) {
        return r.info.motion == "rotating" && r.info.start == "moving" &&
               r.info.peak_angular_rate > 8.0;
      },
      1);
  ASSERT_EQ(seeds.size(), 1u);
  checkPointsAgainstTruth(seeds[0]);
}

TEST(SimRandom, PointsMatchTheTruthStandingAmongMovers) {
  const auto seeds =
      seedsWhere([](const RandomScenario& r) { return r.info.dynamic_near_standing_sensor; }, 1);
  checkPointsAgainstTruth(seeds.at(0));
}

// The recording's LiDAR stamps are on the LiDAR clock, its declared extrinsics off by the drawn
// errors; the truth stays in extrinsics.
TEST(SimRandom, DeclaredCalibrationAndClockOffset) {
  const auto seeds = seedsWhere(
      [](const RandomScenario& r) {
        return r.info.lidar_time_offset != 0 && r.info.rotation_error_deg > 0 &&
               r.info.position_error > 0;
      },
      1);
  ASSERT_EQ(seeds.size(), 1u);
  const RandomScenario r = drawRandomScenario(seeds[0]);
  const Recording rec = simulate(small(seeds[0], 0.3, 500));
  EXPECT_EQ(rec.lidar_time_offset, r.config.lidar_time_offset);
  for (std::size_t f = 0; f < rec.frames.size(); ++f) {
    EXPECT_EQ(rec.frames[f].stamp, rec.config.t0 + static_cast<double>(f) / rec.config.frame_rate +
                                       rec.lidar_time_offset);
  }
  const Extrinsics truth = makeExtrinsics(rec.config);
  EXPECT_EQ(rec.extrinsics.R_bl, truth.R_bl);
  EXPECT_EQ(rec.extrinsics.p_bl, truth.p_bl);
  const double angle =
      Eigen::AngleAxisd(rec.extrinsics.R_bl.transpose() * rec.declared_extrinsics.R_bl).angle();
  EXPECT_NEAR(angle / kDeg, r.config.declared_rotation_error_deg.norm(), 1e-9);
  EXPECT_NEAR(angle / kDeg, r.info.rotation_error_deg, 1e-9);
  EXPECT_LT((rec.declared_extrinsics.p_bl - rec.extrinsics.p_bl - r.config.declared_position_error)
                .norm(),
            1e-15);
  // A preset declares the truth on one clock.
  ScenarioConfig p = preset("dyna_01", 2);
  p.duration = 0.2;
  p.points_per_frame = 100;
  const Recording prec = simulate(p);
  EXPECT_EQ(prec.declared_extrinsics.R_bl, prec.extrinsics.R_bl);
  EXPECT_EQ(prec.declared_extrinsics.p_bl, prec.extrinsics.p_bl);
  EXPECT_EQ(prec.lidar_time_offset, 0.0);
}

// Noise off, at each IMU rate: every sample is the analytic truth, and integrating the samples
// reproduces the trajectory, with an error that vanishes as the rate grows (so the samples are
// consistent with the trajectory at any rate, not just close at one). Per rate, the hardest draws
// among the first 300: the fastest hand rotation and the first vibrating vehicle or robot. The
// integration error of the RK4 scheme with interpolated mid-step signals (test_sim_imu.cpp) falls
// ~8x per doubling of the rate here; required: >= 4x. At the drawn rate the error is that of any
// integrator at that rate (15 Hz vibration sampled at 100 Hz: up to ~0.012 m/s over 1 s); bounds
// ~4x the worst measured.
TEST(SimRandom, ImuIsExactAtEveryRate) {
  std::map<double, std::uint64_t> fastest_hand, vibrating;
  std::map<double, double> fastest_rate;
  for (std::uint64_t s = 1; s <= 300; ++s) {
    const RandomScenario r = drawRandomScenario(s);
    const double rate = r.config.imu_rate;
    if (r.info.motion == "rotating" && r.info.start == "moving" &&
        r.info.peak_angular_rate > fastest_rate[rate]) {
      fastest_rate[rate] = r.info.peak_angular_rate;
      fastest_hand[rate] = s;
    }
    if (r.info.platform != PlatformClass::Handheld && r.info.start == "moving" &&
        !vibrating.count(rate))
      vibrating[rate] = s;
  }
  ASSERT_EQ(fastest_hand.size(), 5u);
  ASSERT_EQ(vibrating.size(), 5u);
  for (const auto* chosen : {&fastest_hand, &vibrating}) {
    for (const auto& [rate, seed] : *chosen) {
      test::IntegrationError e[3];
      for (int k = 0; k < 3; ++k) {
        ScenarioConfig c = small(seed, 1.0, 0);
        c.imu_rate = rate * (1 << k);
        c.gyro_sigma = 0;
        c.accel_sigma = 0;
        const Recording rec = simulate(c);
        ASSERT_EQ(rec.imu.size(), static_cast<std::size_t>(std::lround(c.imu_rate)) + 1);
        for (const ImuSample& m : rec.imu) {
          const TruthState s = rec.truth(m.t);
          ASSERT_LT((m.gyro - rec.b_g - s.omega_b).norm(), 1e-12);
          ASSERT_LT((m.accel - rec.b_a - s.R_wb.transpose() * (s.a_w - rec.g_w)).norm(), 1e-12);
        }
        e[k] = test::integrate(rec, 1.0);
      }
      std::printf(
          "seed %llu at %.0f / %.0f / %.0f Hz: attitude %.2g / %.2g / %.2g rad, velocity "
          "%.2g / %.2g / %.2g m/s\n",
          static_cast<unsigned long long>(seed), rate, 2 * rate, 4 * rate, e[0].attitude,
          e[1].attitude, e[2].attitude, e[0].velocity, e[1].velocity, e[2].velocity);
      EXPECT_LT(e[0].attitude, 1e-3) << seed;
      EXPECT_LT(e[0].velocity, 0.05) << seed;
      EXPECT_LT(e[0].position, 0.05) << seed;
      for (int k = 1; k < 3; ++k) {
        EXPECT_LT(e[k].attitude, e[k - 1].attitude / 4) << seed << " " << rate;
        EXPECT_LT(e[k].velocity, e[k - 1].velocity / 4) << seed << " " << rate;
        EXPECT_LT(e[k].position, e[k - 1].position / 4) << seed << " " << rate;
      }
    }
  }
}

// Each axis of the IMU carries its own white noise sigma (gyro_sigma x gyro_sigma_scale): at
// rest for 10 s, the residuals' sample std per axis matches it (N >= 1000 per axis: relative
// standard error <= 2.3 %; tolerance 10 %).
TEST(SimRandom, PerAxisImuNoise) {
  ScenarioConfig c = randomScenario(3);
  c.motion.still_until = 100;
  c.motion.blend_duration = 1;
  c.duration = 10;
  c.points_per_frame = 0;
  const Recording rec = simulate(c);
  const Vec3 gs = c.gyroSigmaPerAxis(), as = c.accelSigmaPerAxis();
  Stats g[3], a[3];
  const TruthState s = rec.truth(c.t0);
  const Vec3 f_true = s.R_wb.transpose() * (s.a_w - rec.g_w);
  for (const ImuSample& m : rec.imu) {
    for (int k = 0; k < 3; ++k) {
      g[k].add(m.gyro[k] - rec.b_g[k]);
      a[k].add(m.accel[k] - rec.b_a[k] - f_true[k]);
    }
  }
  ASSERT_GE(rec.imu.size(), 1000u);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(g[k].std(), gs[k], 0.1 * gs[k]) << k;
    EXPECT_NEAR(a[k].std(), as[k], 0.1 * as[k]) << k;
  }
}

// Line order and direction: the scan slots measure the lines in the configured order, each line
// sweeping its azimuth the configured way.
TEST(SimRandom, ScanPatterns) {
  for (LineOrder order : {LineOrder::TopDown, LineOrder::BottomUp, LineOrder::Interleaved}) {
    for (LineDirection dir : {LineDirection::Alternating, LineDirection::Forward}) {
      ScenarioConfig c = preset("tunnel_handheld", 1);  // every ray hits (no line at elevation 0)
      c.duration = 0.1;
      c.lines = 8;
      c.points_per_frame = 800;
      c.line_order = order;
      c.line_direction = dir;
      const Recording rec = simulate(c);
      const LidarFrame& fr = rec.frames.at(0);
      ASSERT_EQ(fr.points.size(), 800u);
      std::vector<int> sequence;
      for (std::size_t i = 0; i < fr.points.size(); ++i) {
        const DopplerPoint& p = fr.points[i];
        if (i % 100 == 0) sequence.push_back(p.line);
        if (i % 100 == 0) continue;
        const DopplerPoint& q = fr.points[i - 1];
        EXPECT_EQ(p.line, q.line);
        EXPECT_GE(p.time_offset, q.time_offset);
        const bool backwards = dir == LineDirection::Alternating && (i / 100) % 2 == 1;
        const double az_p = std::atan2(p.p_l.y(), p.p_l.x()),
                     az_q = std::atan2(q.p_l.y(), q.p_l.x());
        EXPECT_EQ(az_p > az_q, !backwards) << i;
      }
      const std::vector<int> expected =
          order == LineOrder::TopDown    ? std::vector<int>{0, 1, 2, 3, 4, 5, 6, 7}
          : order == LineOrder::BottomUp ? std::vector<int>{7, 6, 5, 4, 3, 2, 1, 0}
                                         : std::vector<int>{0, 2, 4, 6, 1, 3, 5, 7};
      EXPECT_EQ(sequence, expected);
    }
  }
}

}  // namespace
}  // namespace freeinit::sim
