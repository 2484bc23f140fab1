// Free-Init's behaviour beyond accuracy: a start that begins moving inside the window, expected
// failures with a clear status, outlier and dynamic-point gating, the streaming interface, and the
// baselines' failure on dynamic starts (the paper's point).
#include <freeinit/baselines.h>
#include <freeinit/free_init.h>
#include <freeinit/sim/evaluation.h>
#include <freeinit/sim/simulator.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>

namespace freeinit {
namespace {

sim::Recording simulatePreset(const std::string& name, double duration, int points = 30000,
                              std::uint64_t seed = 1) {
  auto sc = sim::preset(name, seed);
  sc.duration = duration;
  sc.points_per_frame = points;
  return sim::simulate(sc);
}

FreeInitConfig configFor(const sim::Recording& rec) {
  FreeInitConfig cfg;
  cfg.extrinsics = rec.extrinsics;
  return cfg;
}

/// Drops everything before `t_start` (UNIX s): the recording then starts at that instant.
void cropBefore(sim::Recording& rec, double t_start) {
  rec.imu.erase(std::remove_if(rec.imu.begin(), rec.imu.end(),
                               [&](const ImuSample& s) { return s.t < t_start; }),
                rec.imu.end());
  std::vector<LidarFrame> frames;
  for (const auto& f : rec.frames)
    if (f.stamp >= t_start) frames.push_back(f);
  rec.frames = frames;
}

// stat_03 stands still for 1.0 s then starts moving smoothly. Starting the recording at 0.8 s puts
// the start of motion 0.2 s into the 0.5 s window: the zero-velocity mode must end there and the
// velocity at the window end must still be right.
TEST(FreeInitBehaviour, MotionStartingInsideTheWindow) {
  sim::Recording rec = simulatePreset("stat_03", 1.6, 30000);
  cropBefore(rec, rec.config.t0 + 0.8);
  const InitResult r = FreeInit::run(configFor(rec), rec.imu, rec.frames);
  ASSERT_TRUE(r.state.ok()) << r.state.message;
  EXPECT_TRUE(r.diag.static_start);
  // Left the zero-velocity mode after the motion started (0.2 s) but well before the end.
  EXPECT_GT(r.diag.static_duration, 0.15);
  EXPECT_LT(r.diag.static_duration, 0.45);
  const auto e = sim::evaluate(r.state, rec);
  EXPECT_GT(e.vel_b_true_norm, 0.05);
  EXPECT_LE(e.vel_b, 0.05);
  EXPECT_LE(e.gravity_deg, e.gravity_deg_from_bias + 0.1);
  EXPECT_LE(e.gyro_bias, 0.002);
}

TEST(FreeInitBehaviour, RecordingShorterThanTheWindowIsNotEnoughData) {
  const sim::Recording rec = simulatePreset("dyna_01", 0.3, 5000);
  const InitResult r = FreeInit::run(configFor(rec), rec.imu, rec.frames);
  EXPECT_EQ(r.state.status, InitStatus::NotEnoughData);
  EXPECT_FALSE(r.state.message.empty());
}

// A seed pass longer than the window covers the window: with a 0.2 s window the default seed
// length (0.3 s) and 0 (the whole window) are the same configuration and give the same result.
TEST(FreeInitBehaviour, SeedLongerThanTheWindowIsTheWholeWindow) {
  const sim::Recording rec = simulatePreset("dyna_01", 0.5, 5000);
  FreeInitConfig cfg = configFor(rec);
  cfg.window.duration = 0.2;
  ASSERT_GT(cfg.paper_passes.seed_duration, cfg.window.duration);
  const InitResult a = FreeInit::run(cfg, rec.imu, rec.frames);
  cfg.paper_passes.seed_duration = 0;
  const InitResult b = FreeInit::run(cfg, rec.imu, rec.frames);
  ASSERT_TRUE(a.state.ok()) << a.state.message;
  EXPECT_EQ(a.state.v_w, b.state.v_w);
  EXPECT_EQ(a.state.b_a, b.state.b_a);
  EXPECT_EQ(a.state.q_wb.coeffs(), b.state.q_wb.coeffs());
}

TEST(FreeInitBehaviour, NoLidarIsNotEnoughData) {
  const sim::Recording rec = simulatePreset("dyna_01", 0.7, 5000);
  const InitResult r = FreeInit::run(configFor(rec), rec.imu, {});
  EXPECT_EQ(r.state.status, InitStatus::NotEnoughData);
}

TEST(FreeInitBehaviour, EgoCompensatedDopplerIsRefused) {
  const sim::Recording rec = simulatePreset("dyna_01", 0.7, 5000);
  FreeInitConfig cfg = configFor(rec);
  cfg.doppler.doppler_ego_compensated = true;
  const InitResult r = FreeInit::run(cfg, rec.imu, rec.frames);
  EXPECT_EQ(r.state.status, InitStatus::NoDoppler);
}

// All returns from one direction cannot give a 3-D velocity: not a confident wrong answer.
TEST(FreeInitBehaviour, DegenerateDirectionsAreReported) {
  sim::Recording rec = simulatePreset("dyna_01", 0.7, 5000);
  for (auto& f : rec.frames)
    for (auto& p : f.points) p.p_l = Eigen::Vector3f(10, 0, 0);
  const InitResult r = FreeInit::run(configFor(rec), rec.imu, rec.frames);
  EXPECT_EQ(r.state.status, InitStatus::DegenerateGeometry);
}

// About 1 % of the points are gross Doppler outliers and 5-20 % belong to moving objects in the
// street presets: the gate must reject at least the outliers and keep nearly all static points.
TEST(FreeInitBehaviour, GatingRejectsOutliersAndMovingObjects) {
  const sim::Recording rec = simulatePreset("dyna_05", 0.7, 30000);
  FreeInitConfig cfg = configFor(rec);
  cfg.doppler.point_stride = 1;  // every point is gated: comparable with the labels
  const InitResult r = FreeInit::run(cfg, rec.imu, rec.frames);
  ASSERT_TRUE(r.state.ok());
  std::size_t in_window = 0, non_static = 0;
  const double t_end = r.state.timestamp, t_begin = r.trajectory.front().t;
  for (std::size_t f = 0; f < rec.frames.size(); ++f)
    for (std::size_t i = 0; i < rec.frames[f].points.size(); ++i) {
      const double t = rec.frames[f].stamp + rec.frames[f].points[i].time_offset;
      if (t < t_begin || t > t_end) continue;
      ++in_window;
      if (rec.labels[f][i] != sim::PointLabel::Static) ++non_static;
    }
  const double rejected = static_cast<double>(r.diag.points_rejected);
  EXPECT_GE(rejected, 0.8 * static_cast<double>(non_static));
  EXPECT_LE(rejected, static_cast<double>(non_static) + 0.02 * static_cast<double>(in_window));
  EXPECT_EQ(r.diag.points_used + r.diag.points_rejected + r.diag.points_skipped,
            r.diag.points_seen);
}

// The early smoothing (the final one's starting point, ~1 ms on a 300,000-return window) runs in
// a call before the one that closes the window, for a sensor at 10 Hz or faster, whatever the
// window's phase against the frames: the frame that brings the end of its data is not the one
// the window's last node waits for. At 80 % of the window it was, for a window that starts with
// a frame at 10 Hz (phase 0 here).
TEST(FreeInitBehaviour, TheEarlySmoothingComesBeforeTheClosingFrame) {
  for (const double rate : {10.0, 20.0}) {
    for (const double phase : {0.0, 0.1, 0.3, 0.5, 0.7, 0.9}) {
      auto sc = sim::preset("dyna_05", 1);
      sc.duration = 1.0;
      sc.points_per_frame = 5000;
      sc.frame_rate = rate;
      sim::Recording rec = sim::simulate(sc);
      // The recording starts `phase` periods into a frame: the points and IMU samples before
      // that instant dropped.
      const double t_start = rec.config.t0 + 2.0 / rate + phase / rate;
      cropBefore(rec, t_start - 1.0 / rate);
      LidarFrame& first = rec.frames.front();
      first.points.erase(std::remove_if(first.points.begin(), first.points.end(),
                                        [&](const DopplerPoint& p) {
                                          return first.stamp + p.time_offset < t_start;
                                        }),
                         first.points.end());
      rec.imu.erase(std::remove_if(rec.imu.begin(), rec.imu.end(),
                                   [&](const ImuSample& s) { return s.t < t_start; }),
                    rec.imu.end());
      const std::string tag = std::to_string(rate) + " Hz, phase " + std::to_string(phase);
      const InitResult r = FreeInit::run(configFor(rec), rec.imu, rec.frames);
      ASSERT_TRUE(r.state.ok()) << tag << ": " << r.state.message;
      ASSERT_GT(r.diag.early_smoothing_to, 0.0) << tag;
      const double t_ref = r.state.timestamp - r.diag.window_duration;
      // A node is taken once a frame reaching the end of its data has arrived: the early
      // smoothing's last node with the first frame ending at or after t_ref + early_smoothing_to,
      // the window's last node only with a frame ending after the state's time. (A frame without
      // points, as the first one at phase 0, brings none.)
      auto end = [](const LidarFrame& f) {
        return f.points.empty() ? -std::numeric_limits<double>::infinity()
                                : f.stamp + f.points.back().time_offset;
      };
      std::size_t brought = 0;
      while (brought < rec.frames.size() &&
             end(rec.frames[brought]) < t_ref + r.diag.early_smoothing_to)
        ++brought;
      ASSERT_LT(brought, rec.frames.size()) << tag;
      EXPECT_LT(end(rec.frames[brought]), r.state.timestamp) << tag;
    }
  }
}

// Data may arrive in any interleaving: IMU far ahead of the LiDAR, or the LiDAR ahead.
TEST(FreeInitBehaviour, StreamingOrderDoesNotChangeTheResult) {
  const sim::Recording rec = simulatePreset("dyna_04", 0.7, 10000);
  const FreeInitConfig cfg = configFor(rec);
  const InitResult batch = FreeInit::run(cfg, rec.imu, rec.frames);
  FreeInit imu_first(cfg);
  for (const auto& s : rec.imu) imu_first.addImu(s);
  for (const auto& f : rec.frames) imu_first.addFrame(f);
  imu_first.finish();
  FreeInit lidar_first(cfg);
  for (const auto& f : rec.frames) lidar_first.addFrame(f);
  EXPECT_FALSE(lidar_first.ready());
  for (const auto& s : rec.imu) lidar_first.addImu(s);
  lidar_first.finish();
  ASSERT_TRUE(batch.state.ok());
  for (const FreeInit* fi : {&imu_first, &lidar_first}) {
    ASSERT_TRUE(fi->ready());
    EXPECT_NEAR((fi->result().state.v_w - batch.state.v_w).norm(), 0.0, 1e-9);
    EXPECT_NEAR((fi->result().state.b_a - batch.state.b_a).norm(), 0.0, 1e-9);
    EXPECT_EQ(fi->result().diag.points_used, batch.diag.points_used);
  }
}

// The state is out before the map: at ready() everything but the map is final; the first
// result() builds the map, the same as the batch run's, point for point.
TEST(FreeInitBehaviour, TheStateComesBeforeTheMap) {
  const sim::Recording rec = simulatePreset("dyna_04", 0.7, 10000);
  const FreeInitConfig cfg = configFor(rec);
  const InitResult batch = FreeInit::run(cfg, rec.imu, rec.frames);
  ASSERT_TRUE(batch.state.ok());
  ASSERT_GT(batch.static_map.size(), 1000u);
  FreeInit fi(cfg);
  std::size_t k = 0;
  for (const auto& f : rec.frames) {
    while (k < rec.imu.size() && rec.imu[k].t <= f.stamp + f.points.back().time_offset)
      fi.addImu(rec.imu[k++]);
    if (fi.ready()) break;
    fi.addFrame(f);
    if (fi.ready()) break;
  }
  while (k < rec.imu.size() && !fi.ready()) fi.addImu(rec.imu[k++]);
  ASSERT_TRUE(fi.ready());
  const InitResult& early = fi.resultBeforeMap();
  EXPECT_TRUE(early.static_map.empty());
  EXPECT_TRUE(early.rejected.empty());
  EXPECT_EQ(early.state.v_w, batch.state.v_w);
  EXPECT_EQ(early.state.cov, batch.state.cov);
  EXPECT_EQ(early.trajectory.size(), batch.trajectory.size());
  const InitResult& full = fi.result();
  ASSERT_EQ(full.static_map.size(), batch.static_map.size());
  EXPECT_EQ(full.rejected.size(), batch.rejected.size());
  for (std::size_t i = 0; i < full.static_map.size(); i += 97)
    EXPECT_EQ(full.static_map[i].p_w, batch.static_map[i].p_w) << "map point " << i;
  EXPECT_GT(full.diag.time_map, 0.0);
  EXPECT_EQ(&fi.result(), &full);  // built once
  EXPECT_EQ(fi.result().static_map.size(), batch.static_map.size());
}

TEST(FreeInitBehaviour, TimeGoingBackwardsIsAnError) {
  const sim::Recording rec = simulatePreset("dyna_01", 0.7, 2000);
  FreeInit fi(configFor(rec));
  fi.addImu(rec.imu[1]);
  EXPECT_THROW(fi.addImu(rec.imu[0]), std::invalid_argument);
  EXPECT_THROW(fi.addImu(rec.imu[1]), std::invalid_argument);  // duplicated
  fi.addFrame(rec.frames[1]);
  EXPECT_THROW(fi.addFrame(rec.frames[0]), std::invalid_argument);
}

// A NaN time offset or a frame reaching back into the previous one would break the time order
// of the points: refused, not silently mis-ordered.
TEST(FreeInitBehaviour, NonFiniteTimeOffsetsAndOverlappingFramesAreErrors) {
  const sim::Recording rec = simulatePreset("dyna_01", 0.7, 2000);
  FreeInit fi(configFor(rec));
  LidarFrame bad = rec.frames[0];
  bad.points[5].time_offset = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(fi.addFrame(bad), std::invalid_argument);
  fi.addFrame(rec.frames[0]);
  LidarFrame overlapping = rec.frames[1];
  for (auto& p : overlapping.points) p.time_offset -= 0.05f;  // starts inside frame 0
  EXPECT_THROW(fi.addFrame(overlapping), std::invalid_argument);
  EXPECT_NO_THROW(fi.addFrame(rec.frames[1]));
}

TEST(FreeInitBehaviour, InvalidConfigurationNamesTheKey) {
  FreeInitConfig cfg;
  cfg.doppler.doppler_sigma = -1;
  try {
    FreeInit fi(cfg);
    FAIL() << "expected an exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("doppler.doppler_sigma"), std::string::npos);
  }
  cfg = FreeInitConfig();
  cfg.extrinsics.R_bl(0, 0) = 2;
  EXPECT_THROW(FreeInit{cfg}, std::invalid_argument);
}

// The paper's point: initializers that assume a platform at rest fail dynamic starts, and are
// comparable on static ones.
TEST(FreeInitBehaviour, StaticMeanBaselinesFailDynamicStartsAndMatchOnStaticOnes) {
  for (const char* name : {"dyna_01", "dyna_05"}) {
    const sim::Recording rec = simulatePreset(name, 0.7, 20000);
    const auto fi = sim::evaluate(FreeInit::run(configFor(rec), rec.imu, rec.frames).state, rec);
    const auto fl = sim::evaluate(baselines::fastLio2(rec.imu).state, rec);
    ASSERT_TRUE(fi.valid && fl.valid);
    EXPECT_GT(fl.vel_b, 20 * fi.vel_b) << name;  // it assumes zero velocity
    EXPECT_GT(fl.vel_b, 1.0) << name;
  }
  {
    const sim::Recording rec = simulatePreset("dyna_01", 0.7, 20000);
    const auto fl = sim::evaluate(baselines::fastLio2(rec.imu).state, rec);
    EXPECT_GT(fl.gravity_deg, 2.0);  // the mean accelerometer is not gravity while shaking
  }
  const sim::Recording rec = simulatePreset("stat_01", 0.7, 20000);
  const auto fi = sim::evaluate(FreeInit::run(configFor(rec), rec.imu, rec.frames).state, rec);
  const auto fl = sim::evaluate(baselines::fastLio2(rec.imu).state, rec);
  ASSERT_TRUE(fi.valid && fl.valid);
  EXPECT_NEAR(fl.gravity_deg, fi.gravity_deg, 0.1);
  EXPECT_NEAR(fl.gyro_bias, fi.gyro_bias, 0.001);
}

// Each map point carries its return's Doppler and time (from the state's timestamp), in both
// forms of the estimator: put back where the truth had the LiDAR at that time, the Doppler is
// what a static point there would read, to the Doppler noise: the median misfit is 0.020 m/s,
// that of |N(0, 0.03^2)| (0.6745 sigma). A time off by 10 ms on dyna_01 (up to 5 rad/s) gives
// 0.028, a Doppler from another return far more.
/// The median over the map of |a point's Doppler - the Doppler a static point there would have|,
/// the point put into the truth's world through the estimated state's pose (the map's world is
/// the estimator's); and the earliest and latest point times.
struct MapMisfit {
  double median = 0;
  float earliest = 0, latest = -1;
};
MapMisfit mapMisfit(const sim::Recording& rec, const InitResult& r) {
  const Mat3 R_est = r.state.q_wb.toRotationMatrix();
  const auto at_state = sim::stateTruth(rec, r.state.timestamp);
  std::vector<double> misfit;
  MapMisfit out;
  for (const MapPoint& m : r.static_map) {
    out.earliest = std::min(out.earliest, m.time);
    out.latest = std::max(out.latest, m.time);
    const Vec3 p_b = R_est.transpose() * (m.p_w.cast<double>() - r.state.p_w);
    const Vec3 p_w = at_state.R_wb() * p_b + at_state.p_w;
    const auto x = sim::stateTruth(rec, r.state.timestamp + m.time);
    const Vec3 p_wl = x.p_w + x.R_wb() * rec.extrinsics.p_bl;
    const Vec3 v_wl = x.v_w + x.R_wb() * x.omega_b.cross(rec.extrinsics.p_bl);
    const Vec3 d = (p_w - p_wl).normalized();
    misfit.push_back(std::abs(m.doppler + d.dot(v_wl)));
  }
  if (misfit.empty()) return out;
  std::nth_element(misfit.begin(), misfit.begin() + misfit.size() / 2, misfit.end());
  out.median = misfit[misfit.size() / 2];
  return out;
}

TEST(FreeInitBehaviour, MapPointsCarryTheirDopplerAndTime) {
  const sim::Recording rec = simulatePreset("dyna_01", 0.7, 10000);
  for (const auto method : {EstimatorParams::Method::Joint, EstimatorParams::Method::Paper}) {
    FreeInitConfig cfg = configFor(rec);
    cfg.estimator.method = method;
    const InitResult r = FreeInit::run(cfg, rec.imu, rec.frames);
    ASSERT_TRUE(r.state.ok()) << r.state.message;
    ASSERT_GT(r.static_map.size(), 1000u);
    const MapMisfit m = mapMisfit(rec, r);
    EXPECT_LT(m.median, 0.024) << "median |Doppler - static prediction|";
    EXPECT_LE(m.latest, 1e-6F);
    EXPECT_GT(m.earliest, -0.52F);  // the 0.5 s window
    EXPECT_LT(m.earliest, -0.45F);
  }
}

// The recorder sizes its buffer for the window from the frames seen before the start. A sensor
// that then returns ten times as many points per frame overflows it: the buffer grows, and every
// return used must still reach the map whole. Each map point's Doppler is one of the input's
// (a multiset: no return lost to a copy, none twice), and the map is as consistent with the
// truth's motion as the map of the same sensor dense from the start.
TEST(FreeInitBehaviour, ASensorDenserThanItsStartIsMappedWhole) {
  const sim::Recording dense = simulatePreset("dyna_05", 0.7, 20000);
  sim::Recording rec = dense;
  const double t_dense = rec.frames.front().stamp + 0.08;
  for (auto& f : rec.frames) {
    if (f.stamp >= t_dense) continue;
    std::vector<DopplerPoint> thinned;
    for (std::size_t i = 0; i < f.points.size(); i += 10) thinned.push_back(f.points[i]);
    f.points = thinned;
  }
  const InitResult r = FreeInit::run(configFor(rec), rec.imu, rec.frames);
  ASSERT_TRUE(r.state.ok()) << r.state.message;
  ASSERT_GT(r.static_map.size(), 50000u);  // far beyond the start's rate (~2,000 per frame)
  EXPECT_EQ(r.static_map.size(), r.diag.points_used);
  std::vector<float> input, mapped;
  for (const auto& f : rec.frames)
    for (const auto& p : f.points) input.push_back(p.doppler);
  for (const MapPoint& m : r.static_map) mapped.push_back(m.doppler);
  std::sort(input.begin(), input.end());
  std::sort(mapped.begin(), mapped.end());
  EXPECT_TRUE(std::includes(input.begin(), input.end(), mapped.begin(), mapped.end()));
  const InitResult reference = FreeInit::run(configFor(dense), dense.imu, dense.frames);
  ASSERT_TRUE(reference.state.ok()) << reference.state.message;
  const MapMisfit m = mapMisfit(rec, r);
  EXPECT_LT(m.median, 1.2 * mapMisfit(dense, reference).median)
      << "median |Doppler - static prediction|";
  EXPECT_LE(m.latest, 1e-6F);
  EXPECT_LT(m.earliest, -0.45F);
}

}  // namespace
}  // namespace freeinit
