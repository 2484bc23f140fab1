// The importer and the per-scan Doppler fit on a real recording: the public TI mmWave radar +
// ADIS16448 IMU bag (shared test data; see its README for the facts checked here). The tests skip,
// saying so, when the file is absent.
//
// What the recording is: 8270 IMU samples (~205 Hz), 412 radar scans (10 Hz, 19-87 points, header
// stamps zero), 413 trigger messages on the IMU clock whose seq matches the scans' (the last
// trigger, seq 521, has no scan: the recording stopped within that frame). At rest for ~13 s, then
// carried by hand, near rest again from ~34 s.
#include <freeinit/app_support/app_config.h>
#include <freeinit/free_init.h>
#include <freeinit/mrpt_plugins/conversions.h>
#include <freeinit/mrpt_plugins/rawlog_reader.h>
#include <freeinit/ros1/bag_reader.h>
#include <freeinit/ros1/doppler_fit.h>
#include <freeinit/rotation.h>
#include <gtest/gtest.h>
#include <mrpt/obs/CObservationIMU.h>
#include <mrpt/obs/CObservationPointCloud.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "bag_import_app.h"
#include "joint/doppler_inertial_filter.h"
#include "ros_test_files.h"

using namespace freeinit;
namespace fs = std::filesystem;

namespace {

const std::string kSrc = FREEINIT_SOURCE_DIR;
const std::string kBag =
    std::string(FREEINIT_SHARED_DATA) + "/ti_mmwave_radar_imu/ti_mmwave_rospkg_demo.bag";
const std::string kIni = kSrc + "/ini/import_bag_ti_mmwave.ini";

#define SKIP_WITHOUT_THE_BAG()                                                                   \
  do {                                                                                           \
    if (!fs::is_regular_file(kBag))                                                              \
      GTEST_SKIP() << "the recording " << kBag                                                   \
                   << " is not here (shared test data; configure with -DFREEINIT_SHARED_DATA=)"; \
  } while (false)

std::string dir(const std::string& name) {
  return test::testFolder("freeinit_radar_bag_tests", name);
}

// The recording as read with the shipped INI (MRPT-free reader), once.
struct Recording {
  apps::BagImportSettings settings;
  ros1::BagSummary summary;
  std::vector<ImuSample> imu;
  std::vector<LidarFrame> scans;
  std::vector<ros1::DopplerFit> fits;
};

const Recording& recording() {
  static const Recording r = [] {
    Recording x;
    x.settings = apps::loadBagImportSettings(kIni);
    ros1::BagReadCallbacks cb;
    cb.imu = [&](const ImuSample& s) { x.imu.push_back(s); };
    cb.frame = [&](LidarFrame&& f) { x.scans.push_back(std::move(f)); };
    x.summary = ros1::readBag(kBag, x.settings.bag, cb);
    for (const auto& f : x.scans)
      x.fits.push_back(ros1::fitScanVelocity(f.points, x.settings.doppler_fit));
    return x;
  }();
  return r;
}

// Scans at rest and moving, by time after the first IMU sample: the README's "first ~12 s" and
// the handheld stretch (the fits show motion from 13.5 s to 33.4 s).
bool atRest(double t) { return t < recording().imu.front().t + 12.0; }
bool moving(double t) {
  const double t0 = recording().imu.front().t;
  return t > t0 + 14.0 && t < t0 + 33.0;
}

}  // namespace

// The shipped INI: trigger stamps, no per-point time (spread over the 18.5 ms frame), the
// README's extrinsics.
TEST(RadarBag, ShippedIni) {
  const auto s = apps::loadBagImportSettings(kIni);
  EXPECT_EQ(s.bag.stamp_source, ros1::StampSource::kTrigger);
  EXPECT_EQ(s.bag.trigger_topic, "/sensor_platform/radar_right/trigger");
  EXPECT_EQ(s.bag.cloud.time.field.name, "");
  EXPECT_EQ(s.bag.cloud.time.frame_duration, 0.0185);
  EXPECT_EQ(s.bag.cloud.line.name, "");
  EXPECT_EQ(s.bag.cloud.doppler.name, "velocity");
  EXPECT_EQ(s.extrinsics.p_bl, Vec3(0.03, 0.03, -0.06));
  // R_bl is the calibration's quaternion (x y z w) as a matrix, to the 9 digits written, after
  // the rotation from the cloud's axes to the calibration's radar frame (x = -y_cloud,
  // y = x_cloud, z = z_cloud: the rio estimator turns the TI clouds so before using them).
  const Quat q(-0.0746967504749, 0.923218461092, 0.375992995522, -0.0267831268675);
  Mat3 R_rl;
  R_rl << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  EXPECT_LT((s.extrinsics.R_bl - q.normalized().toRotationMatrix() * R_rl).cwiseAbs().maxCoeff(),
            1e-8);
  EXPECT_DOUBLE_EQ(s.doppler_fit.sigma_floor, 0.036);
}

// Every IMU sample and every scan with a trigger imports: 8270 and 412 (413 triggers, the last
// without a scan); stamps on the IMU clock (the trigger's), increasing; the scans within the IMU
// span; the points 19-87 per scan, offsets spread over the 18.5 ms frame.
TEST(RadarBag, ImportsWithTriggerStamps) {
  SKIP_WITHOUT_THE_BAG();
  const Recording& r = recording();
  EXPECT_EQ(r.summary.imu.in_bag, 8270u);
  EXPECT_EQ(r.summary.imu.imported, 8270u);
  EXPECT_EQ(r.summary.lidar.in_bag, 412u);
  EXPECT_EQ(r.summary.lidar.imported, 412u);
  EXPECT_EQ(r.summary.lidar.skipped(), 0u);
  EXPECT_EQ(r.summary.trigger.in_bag, 413u);
  EXPECT_EQ(r.summary.trigger.used, 412u);
  EXPECT_EQ(r.summary.trigger.repeated_seq, 0u);
  ASSERT_EQ(r.scans.size(), 412u);
  ASSERT_EQ(r.imu.size(), 8270u);
  for (std::size_t i = 1; i < r.imu.size(); ++i) ASSERT_GT(r.imu[i].t, r.imu[i - 1].t) << i;
  std::size_t min_points = 1000, max_points = 0;
  for (std::size_t k = 0; k < r.scans.size(); ++k) {
    const LidarFrame& f = r.scans[k];
    if (k > 0) {
      ASSERT_GT(f.stamp, r.scans[k - 1].stamp) << k;
    }
    EXPECT_GT(f.stamp, r.imu.front().t) << k;
    EXPECT_LT(f.stamp, r.imu.back().t) << k;
    min_points = std::min(min_points, f.points.size());
    max_points = std::max(max_points, f.points.size());
    const std::size_t n = f.points.size();
    EXPECT_FLOAT_EQ(f.points.front().time_offset, static_cast<float>(0.0185 * 0.5 / n)) << k;
    EXPECT_FLOAT_EQ(f.points.back().time_offset, static_cast<float>(0.0185 * (n - 0.5) / n)) << k;
  }
  EXPECT_EQ(min_points, 19u);
  EXPECT_EQ(max_points, 87u);
  // The 10.24 Hz radar: consecutive triggers 97.7 ms apart, no gap.
  EXPECT_NEAR(r.summary.lidar.median_interval, 0.0977, 0.0005);
  EXPECT_EQ(r.summary.lidar.gaps, 0u);
}

// At rest: the README's means over the first 200 samples (given to its last digit, so within half
// a unit of it), and every Doppler exactly 0 (the radar's velocity bins).
TEST(RadarBag, RestMeansMatchTheReadme) {
  SKIP_WITHOUT_THE_BAG();
  const Recording& r = recording();
  Vec3 gyro = Vec3::Zero(), accel = Vec3::Zero();
  for (int i = 0; i < 200; ++i) {
    gyro += r.imu[i].gyro / 200;
    accel += r.imu[i].accel / 200;
  }
  EXPECT_NEAR(gyro.x(), -0.00084, 0.000005);
  EXPECT_NEAR(gyro.y(), -0.00073, 0.000005);
  EXPECT_NEAR(gyro.z(), -0.00759, 0.000005);
  EXPECT_NEAR(accel.x(), 0.390, 0.0005);
  EXPECT_NEAR(accel.y(), -0.040, 0.0005);
  EXPECT_NEAR(accel.z(), 9.890, 0.0005);
  EXPECT_NEAR(accel.norm(), 9.897, 0.0005);
  std::size_t rest_points = 0;
  for (const auto& f : r.scans) {
    if (!atRest(f.stamp)) continue;
    for (const auto& p : f.points) ASSERT_EQ(p.doppler, 0.0f);
    rest_points += f.points.size();
  }
  EXPECT_GT(rest_points, 4000u);
}

// The shipped estimator INI declares the radar's Doppler bin ([input] doppler_resolution): every
// Doppler of the recording is a whole number of bins (float32 values: within 1e-5 of one), moving
// or not, and many scans read zero everywhere while the rig moves slowly, which the bin makes
// legitimate (without it, the app refuses them: tests/ros1/CMakeLists.txt runs it along the
// recording).
TEST(RadarBag, DopplerIsWholeBinsAsTheIniDeclares) {
  SKIP_WITHOUT_THE_BAG();
  const double bin =
      app_support::loadAppConfig(kSrc + "/ini/freeinit_radar.ini").input.doppler_resolution;
  ASSERT_GT(bin, 0);
  std::size_t nonzero = 0, zero_scans_moving = 0;
  for (const auto& f : recording().scans) {
    bool all_zero = true;
    for (const auto& p : f.points) {
      const double k = p.doppler / bin;
      ASSERT_NEAR(k, std::round(k), 1e-4) << "Doppler " << p.doppler << " at " << f.stamp;
      if (p.doppler != 0.0f) {
        ++nonzero;
        all_zero = false;
      }
    }
    if (all_zero && !atRest(f.stamp)) ++zero_scans_moving;
  }
  EXPECT_GT(nonzero, 5000u);
  EXPECT_GT(zero_scans_moving, 20u);
}

// The per-scan Doppler-only fit at rest: every scan fits, its velocity is zero within its sigma
// (chi-square, 3 dof, 99.9 %), and the sigma is the quantization floor's (0.036 m/s per point over
// ~40 directions: 0.005-0.06 m/s per axis; never 0).
TEST(RadarBag, DopplerFitAtRestIsZeroWithinItsSigma) {
  SKIP_WITHOUT_THE_BAG();
  const Recording& r = recording();
  std::size_t n = 0;
  for (std::size_t k = 0; k < r.scans.size(); ++k) {
    if (!atRest(r.scans[k].stamp)) continue;
    const ros1::DopplerFit& f = r.fits[k];
    ASSERT_TRUE(f.ok) << k << ": " << f.message;
    EXPECT_LT(f.v_l.dot(f.cov.inverse() * f.v_l), 16.27) << k;
    for (int i = 0; i < 3; ++i) {
      EXPECT_GT(std::sqrt(f.cov(i, i)), 0.005) << k;
      EXPECT_LT(std::sqrt(f.cov(i, i)), 0.06) << k;
    }
    ++n;
  }
  EXPECT_GT(n, 100u);
}

// While moving, the fits are checked against the IMU, which they never saw: from one scan's fitted
// velocity, the IMU predicts the next scan's (body-frame kinematics v_b' = f_b + g_b - omega x v_b,
// g_b carried along by the gyro from the mean specific force at rest, gyro bias = its mean at
// rest, v_b = R_bl v_l - omega x p_bl). The prediction's own error over a scan interval (0.1 s):
// gravity direction ~1 deg off after the whole motion (measured: g_b carried through the 40 s
// ends 0.97 deg from the specific force at rest there) and an accelerometer bias up to 0.09 m/s^2
// (|f| at rest is 9.897, not 9.81), i.e. 0.017 and 0.009 m/s: 0.02 m/s per axis. The next fit
// must agree with the prediction within that and the two fits' covariances (chi-square 3 dof,
// 99 %) more often than not (measured: 142 of 194 pairs, 73 %; the fits' sigmas are thus
// optimistic on this recording: 1.5x them gives 86 %), and the prediction must explain most of
// the scan-to-scan change (median miss 0.085 m/s for a median change of 0.132 m/s; with the
// calibration's rotation applied to the cloud's axes as they are, 0.19 m/s: see the INI).
// Magnitudes are those of a rig carried by hand: under 3 m/s.
TEST(RadarBag, DopplerFitWhileMovingAgreesWithTheImu) {
  SKIP_WITHOUT_THE_BAG();
  const Recording& r = recording();
  const Extrinsics& e = r.settings.extrinsics;
  Vec3 bias = Vec3::Zero(), f_rest = Vec3::Zero();
  std::size_t rest = 0;
  for (const auto& s : r.imu)
    if (atRest(s.t)) {
      bias += s.gyro;
      f_rest += s.accel;
      ++rest;
    }
  bias /= static_cast<double>(rest);
  f_rest /= static_cast<double>(rest);

  // Gravity in the body frame at every IMU sample: g_b(t_i).
  std::vector<Vec3> g_b(r.imu.size());
  g_b[0] = -f_rest;
  for (std::size_t i = 1; i < r.imu.size(); ++i) {
    const Vec3 w = 0.5 * (r.imu[i - 1].gyro + r.imu[i].gyro) - bias;
    const double dt = r.imu[i].t - r.imu[i - 1].t;
    const double angle = w.norm() * dt;
    const Mat3 R =
        angle > 0 ? Eigen::AngleAxisd(angle, w.normalized()).toRotationMatrix() : Mat3::Identity();
    g_b[i] = R.transpose() * g_b[i - 1];  // R_b(i-1)b(i)^T: the fixed vector seen from the new pose
  }
  auto index = [&](double t) {  // last IMU sample at or before t
    const auto it = std::upper_bound(r.imu.begin(), r.imu.end(), t,
                                     [](double x, const ImuSample& s) { return x < s.t; });
    return static_cast<std::size_t>(std::max<std::ptrdiff_t>(it - r.imu.begin() - 1, 0));
  };
  auto omega = [&](double t) { return r.imu[index(t)].gyro - bias; };

  // The shipped estimator INI's doppler_sigma is this test's measurement: with the fits'
  // covariances scaled by its ratio to their residuals' 0.044 m/s, the chi-square has its mean.
  const double scale =
      app_support::loadAppConfig(kSrc + "/ini/freeinit_radar.ini").core.doppler.doppler_sigma /
      0.044;
  double chi2_scaled = 0;
  std::size_t pairs = 0, agree = 0;
  std::vector<double> change, miss, speed;
  for (std::size_t k = 0; k + 1 < r.scans.size(); ++k) {
    const double t0 = r.scans[k].stamp + r.fits[k].mean_time_offset;
    const double t1 = r.scans[k + 1].stamp + r.fits[k + 1].mean_time_offset;
    if (!moving(t0) || !moving(t1)) continue;
    ASSERT_TRUE(r.fits[k].ok && r.fits[k + 1].ok)
        << k << ": " << r.fits[k].message << " / " << r.fits[k + 1].message;
    const Vec3 v0 = e.R_bl * r.fits[k].v_l - omega(t0).cross(e.p_bl);
    const Vec3 v1 = e.R_bl * r.fits[k + 1].v_l - omega(t1).cross(e.p_bl);
    // Integrate the body velocity over the IMU samples between the two times.
    Vec3 v = v0;
    double t = t0;
    for (std::size_t i = index(t0) + 1; i < r.imu.size() && t < t1; ++i) {
      const double t_next = std::min(r.imu[i].t, t1);
      const std::size_t j = i - 1;
      const Vec3 w = r.imu[j].gyro - bias;
      v += (t_next - t) * (r.imu[j].accel + g_b[j] - w.cross(v));
      t = t_next;
    }
    const Mat3 C = e.R_bl * (r.fits[k].cov + r.fits[k + 1].cov) * e.R_bl.transpose() +
                   0.02 * 0.02 * Mat3::Identity();
    const Vec3 d = v1 - v;
    ++pairs;
    if (d.dot(C.inverse() * d) < 11.34) ++agree;
    const Mat3 C_scaled =
        scale * scale * e.R_bl * (r.fits[k].cov + r.fits[k + 1].cov) * e.R_bl.transpose() +
        0.02 * 0.02 * Mat3::Identity();
    chi2_scaled += d.dot(C_scaled.inverse() * d);
    change.push_back((v1 - v0).norm());
    miss.push_back(d.norm());
    speed.push_back(r.fits[k].v_l.norm());
  }
  ASSERT_GT(pairs, 150u);
  auto median = [](std::vector<double> x) {
    std::nth_element(x.begin(), x.begin() + static_cast<std::ptrdiff_t>(x.size() / 2), x.end());
    return x[x.size() / 2];
  };
  EXPECT_GT(static_cast<double>(agree) / static_cast<double>(pairs), 0.5)
      << agree << " of " << pairs << " pairs agree; median change " << median(change)
      << " m/s, median miss " << median(miss) << " m/s";
  EXPECT_LT(median(miss), 0.8 * median(change));
  // Mean of chi-square with 3 dof (measured: 2.99 at 2.5x); 194 pairs give it a ~10 % spread.
  EXPECT_NEAR(chi2_scaled / static_cast<double>(pairs), 3.0, 0.5) << "scale " << scale;
  EXPECT_LT(*std::max_element(speed.begin(), speed.end()), 3.0);
  EXPECT_GT(median(speed), 0.3);
}

// The importer app on the recording: the rawlog it writes is read back by freeinit's reader with
// every record (8270 IMU, 412 clouds with the extrinsics as sensor pose), and the CSV of
// --doppler-fit-csv holds one row per scan, equal to the fit of the decoded points.
TEST(RadarBag, ImporterAppWritesARawlogAndTheFits) {
  SKIP_WITHOUT_THE_BAG();
  const std::string d = dir("import");
  apps::BagImportApp app;
  app.params.bag = kBag;
  app.params.config_file = kIni;
  app.params.output = d + "/ti.rawlog";
  app.params.doppler_fit_csv = d + "/fits.csv";
  app.params.progress = false;
  std::ostringstream log;
  ASSERT_EQ(app.run(log), 0) << log.str();
  EXPECT_NE(log.str().find("413 triggers, 412 used, 1 without a cloud"), std::string::npos)
      << log.str();
  const auto records = mrpt_plugins::readRawlog(d + "/ti.rawlog");
  std::size_t imu = 0, clouds = 0;
  for (const auto& rec : records) {
    if (dynamic_cast<const mrpt::obs::CObservationIMU*>(rec.obs.get())) ++imu;
    if (const auto* pc = dynamic_cast<const mrpt::obs::CObservationPointCloud*>(rec.obs.get())) {
      const LidarFrame f = mrpt_plugins::frameFromObservation(*pc);
      EXPECT_EQ(f.points.size(), recording().scans[clouds].points.size());
      ++clouds;
    }
  }
  EXPECT_EQ(imu, 8270u);
  EXPECT_EQ(clouds, 412u);

  std::ifstream csv(d + "/fits.csv");
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, apps::kDopplerFitCsvHeader);
  std::size_t rows = 0;
  while (std::getline(csv, line)) {
    std::stringstream ss(line);
    std::string cell;
    std::vector<double> v;
    while (std::getline(ss, cell, ',')) v.push_back(std::stod(cell));
    ASSERT_EQ(v.size(), 15u) << line;
    const auto& fit = recording().fits[rows];
    EXPECT_NEAR(v[0], recording().scans[rows].stamp, 1e-6);
    EXPECT_EQ(v[4], fit.ok ? 1 : 0);
    if (fit.ok) {
      for (int i = 0; i < 3; ++i)
        EXPECT_NEAR(v[5 + i], fit.v_l(i), 1e-5 + 1e-5 * std::abs(fit.v_l(i)));
    }
    ++rows;
  }
  EXPECT_EQ(rows, 412u);
}

// Bag (receive) times with the declared clock offset: the scan stamps then differ from the
// trigger stamps only by the recorder's jitter. The offset is the median the trigger import
// measures, so the median difference is zero; the spread is the jitter (within 20 ms).
TEST(RadarBag, BagTimeStampsWithADeclaredClockOffset) {
  SKIP_WITHOUT_THE_BAG();
  auto config = recording().settings.bag;
  config.stamp_source = ros1::StampSource::kBagTime;
  config.trigger_topic.clear();
  config.lidar_time_offset = -recording().summary.trigger.median_bag_delay;
  std::vector<double> stamps;
  ros1::BagReadCallbacks cb;
  cb.imu = [](const ImuSample&) {};
  cb.frame = [&](LidarFrame&& f) { stamps.push_back(f.stamp); };
  ros1::readBag(kBag, config, cb);
  ASSERT_EQ(stamps.size(), 412u);
  std::vector<double> diff;
  for (std::size_t k = 0; k < stamps.size(); ++k)
    diff.push_back(stamps[k] - recording().scans[k].stamp);
  std::sort(diff.begin(), diff.end());
  EXPECT_NEAR(diff[diff.size() / 2], 0.0, 1e-6);
  EXPECT_GT(diff.front(), -0.02);
  EXPECT_LT(diff.back(), 0.02);
}

// The radar configuration of the estimator loads with today's keys: a window of 2 s (410 IMU
// samples of the recording, 20 scans) whose seed passes span all of it.
TEST(RadarBag, EstimatorIniLoads) {
  const auto c = app_support::loadAppConfig(kSrc + "/ini/freeinit_radar.ini");
  EXPECT_DOUBLE_EQ(c.core.doppler.doppler_sigma, 0.11);
  EXPECT_EQ(c.core.paper_bootstrap.points, 40);
  EXPECT_DOUBLE_EQ(c.core.window.duration, 2.0);
  EXPECT_DOUBLE_EQ(c.core.paper_passes.seed_duration, 0.0);
  EXPECT_EQ(c.core.paper_passes.seed_pass_stride, 1);
}

// The estimator on the recording, as `freeinit ini/freeinit_radar.ini --start T` runs it: the
// records from T on, the shipped radar INI, the calibration from the import INI.
namespace {

InitResult initializeAt(double seconds_after_start) {
  const Recording& r = recording();
  const double t = r.imu.front().t + seconds_after_start;
  FreeInitConfig cfg = app_support::loadAppConfig(kSrc + "/ini/freeinit_radar.ini").core;
  cfg.extrinsics = r.settings.extrinsics;
  std::vector<ImuSample> imu;
  for (const auto& s : r.imu)
    if (s.t >= t) imu.push_back(s);
  std::vector<LidarFrame> scans;
  for (const auto& f : r.scans)
    if (f.stamp >= t) scans.push_back(f);
  return FreeInit::run(cfg, imu, scans);
}

}  // namespace

// At rest (the first 2 s window): a static start; the gyro bias is the window's mean gyro within
// the state's sigma and that mean's own noise, and gravity points against the mean specific force
// (the estimator's b_a is what separates them: the horizontal part is not observable at rest).
TEST(RadarBag, EstimatorAtRestFindsTheMeanGyroAndGravity) {
  SKIP_WITHOUT_THE_BAG();
  const InitResult res = initializeAt(0.0);
  ASSERT_TRUE(res.state.ok()) << res.state.message;
  EXPECT_TRUE(res.diag.static_start);
  EXPECT_LT(res.state.v_b().norm(), 0.01);
  // ~2 returns per IMU sample: the state says it rests on few Doppler measurements.
  ASSERT_FALSE(res.state.warnings.empty());
  EXPECT_NE(res.state.warnings.front().find("few Doppler measurements"), std::string::npos)
      << res.state.warnings.front();
  const Recording& r = recording();
  Vec3 gyro = Vec3::Zero(), f = Vec3::Zero();
  std::size_t n = 0;
  for (const auto& s : r.imu)
    if (s.t >= res.trajectory.front().t && s.t <= res.state.timestamp) {
      gyro += s.gyro;
      f += s.accel;
      ++n;
    }
  ASSERT_GT(n, 300u);
  gyro /= static_cast<double>(n);
  f /= static_cast<double>(n);
  const Mat3 P_bg = res.state.cov.block<3, 3>(kBg, kBg);
  for (int i = 0; i < 3; ++i) {
    const double sigma = std::sqrt(P_bg(i, i) + 0.0024 * 0.0024 / static_cast<double>(n));
    EXPECT_NEAR(res.state.b_g(i), gyro(i), 3 * sigma) << "axis " << i;
  }
  const Vec3 g_b = res.state.q_wb.conjugate() * res.state.g_w;
  const Vec3 f_corrected = f - res.state.b_a;
  const double angle =
      std::acos(std::clamp(-g_b.normalized().dot(f_corrected.normalized()), -1.0, 1.0));
  EXPECT_LT(angle * 180.0 / 3.14159265358979323846, 0.1);
}

// Carried by hand: every start either says why it cannot initialize, or gives a body velocity
// that agrees with the Doppler-only fit of the scan nearest its state time (no IMU in that fit)
// within their covariances (chi-square 3 dof, 99 %: 11.34), with the fits' sigmas 1.5x as
// measured above and 0.03 m/s for the velocity change between the scan and the state time.
TEST(RadarBag, EstimatorWhileMovingAgreesWithTheDopplerFits) {
  SKIP_WITHOUT_THE_BAG();
  const Recording& r = recording();
  const Extrinsics& e = r.settings.extrinsics;
  int states = 0;
  for (double T : {15.0, 20.0, 25.0, 30.0}) {
    const InitResult res = initializeAt(T);
    if (!res.state.ok()) {
      EXPECT_FALSE(res.state.message.empty()) << "start " << T;
      continue;
    }
    ++states;
    const double t = res.state.timestamp;
    std::size_t best = 0;
    double best_dt = 1e9;
    for (std::size_t k = 0; k < r.scans.size(); ++k) {
      const double dt = std::abs(r.scans[k].stamp + r.fits[k].mean_time_offset - t);
      if (r.fits[k].ok && dt < best_dt) {
        best_dt = dt;
        best = k;
      }
    }
    ASSERT_LT(best_dt, 0.1) << "start " << T;
    const Vec3 omega = res.velocities.back().omega_b;
    const Vec3 v_fit = e.R_bl * r.fits[best].v_l - omega.cross(e.p_bl);
    const Mat3 R_bw = res.state.q_wb.conjugate().toRotationMatrix();
    const Mat3 C = 2.25 * e.R_bl * r.fits[best].cov * e.R_bl.transpose() +
                   R_bw * res.state.cov.block<3, 3>(kVel, kVel) * R_bw.transpose() +
                   0.03 * 0.03 * Mat3::Identity();
    const Vec3 d = res.state.v_b() - v_fit;
    EXPECT_LT(d.dot(C.inverse() * d), 11.34)
        << "start " << T << ": state " << res.state.v_b().transpose() << ", fit "
        << v_fit.transpose();
  }
  EXPECT_GE(states, 2);
}

// Along the whole recording (a start every second, as `--every 1`): each state, propagated with
// the IMU to the next start's state time (its own biases, the IMU noise as process noise),
// agrees with that start's state in what does not depend on the world frame (body velocity,
// gravity direction in the body, both biases) within their covariances, or one of the two says
// why it could not initialize. Chi-square, 11 dof, 99.9 %: 31.26, for nine pairs in ten. The two
// windows share a second of data, so their errors are correlated and the difference varies less
// than the sum of the covariances says: the test is lenient by that, and it is still the one that
// tells an honest covariance here. Measured: 35 of 37 pairs agree, no start declines; the worst
// pair is at chi-square 71. With the Doppler noise of the fits' residuals (0.044 m/s, counting each
// return of a scan as independent) 15 of 33 agree: the covariance was 2-3x optimistic in sigma,
// what the scan-to-scan test above measures. On simulated recordings the same check passes on every
// pair.
TEST(RadarBag, EstimatorAlongTheRecordingIsSelfConsistent) {
  SKIP_WITHOUT_THE_BAG();
  using F = DopplerInertialFilter;
  const Recording& r = recording();
  const FreeInitConfig cfg = app_support::loadAppConfig(kSrc + "/ini/freeinit_radar.ini").core;
  const double duration = r.imu.back().t - r.imu.front().t;
  std::vector<InitResult> starts;
  for (double T = 0; T + 3.0 < duration; T += 1.0) starts.push_back(initializeAt(T));
  auto sampleAt = [&](double t) {
    const auto it = std::lower_bound(r.imu.begin(), r.imu.end(), t - 1e-7,
                                     [](const ImuSample& s, double x) { return s.t < x; });
    return static_cast<std::size_t>(it - r.imu.begin());
  };
  int pairs = 0, agree = 0, declined = 0;
  std::string worst;
  double worst_d2 = 0;
  for (std::size_t i = 0; i + 1 < starts.size(); ++i) {
    const InitialState& a = starts[i].state;
    const InitialState& b = starts[i + 1].state;
    if (!a.ok() || !b.ok()) {
      ++declined;
      continue;
    }
    // Propagate a to b's time.
    std::size_t k = sampleAt(a.timestamp);
    const std::size_t k_end = sampleAt(b.timestamp);
    ASSERT_NEAR(r.imu[k].t, a.timestamp, 1e-6);
    ASSERT_NEAR(r.imu[k_end].t, b.timestamp, 1e-6);
    FilterState x;
    x.t = a.timestamp;
    x.R_wb = a.q_wb.toRotationMatrix();
    x.p_w = a.p_w;
    x.v_w = a.v_w;
    x.b_g = a.b_g;
    x.b_a = a.b_a;
    F::MatS P = F::MatS::Zero();
    P.topLeftCorner<15, 15>() = a.cov.topLeftCorner<15, 15>();
    for (; k < k_end; ++k) {
      const F::MatS J = F::transitionJacobian(x, r.imu, k);
      const double dt = r.imu[k + 1].t - r.imu[k].t;
      x = F::propagate(x, r.imu, k);
      P = J * P * J.transpose();
      const double qg = std::pow(cfg.imu.gyro_sigma * dt, 2);
      const double qa = std::pow(cfg.imu.accel_sigma * dt, 2);
      for (int j = 0; j < 3; ++j) {
        P(F::kTheta + j, F::kTheta + j) += qg;
        P(F::kVel + j, F::kVel + j) += qa;
        P(F::kBg + j, F::kBg + j) += 1e-8 * dt;  // the filter's bias random walks
        P(F::kBa + j, F::kBa + j) += 1e-6 * dt;
      }
    }
    // The frame-free quantities and their Jacobians w.r.t. each state's error.
    auto bodyVelocity = [](const Mat3& R, const Vec3& v_w, Eigen::Matrix<double, 3, 15>& J) {
      J.setZero();
      const Vec3 v_b = R.transpose() * v_w;
      J.block<3, 3>(0, 0) = skew(v_b);
      J.block<3, 3>(0, 6) = R.transpose();
      return v_b;
    };
    const Mat3 R_b = b.q_wb.toRotationMatrix();
    Eigen::Matrix<double, 3, 15> Jva, Jvb;
    const Vec3 va = bodyVelocity(x.R_wb, x.v_w, Jva);
    const Vec3 vb = bodyVelocity(R_b, b.v_w, Jvb);
    const Vec3 ua = (x.R_wb.transpose() * b.g_w).normalized();
    const Vec3 ub = (R_b.transpose() * b.g_w).normalized();
    Eigen::Matrix<double, 3, 2> T;  // a basis across b's gravity
    T.col(0) = ub.unitOrthogonal();
    T.col(1) = ub.cross(T.col(0));
    Eigen::Matrix<double, 11, 1> e;
    e << va - vb, T.transpose() * (ua - ub), x.b_g - b.b_g, x.b_a - b.b_a;
    Eigen::Matrix<double, 11, 15> Ja = Eigen::Matrix<double, 11, 15>::Zero(), Jb = Ja;
    Ja.topRows<3>() = Jva;
    Jb.topRows<3>() = -Jvb;
    Ja.block<2, 3>(3, 0) = T.transpose() * skew(ua);
    Jb.block<2, 3>(3, 0) = -T.transpose() * skew(ub);
    Ja.block<3, 3>(5, 9) = Mat3::Identity();
    Jb.block<3, 3>(5, 9) = -Mat3::Identity();
    Ja.block<3, 3>(8, 12) = Mat3::Identity();
    Jb.block<3, 3>(8, 12) = -Mat3::Identity();
    const Eigen::Matrix<double, 11, 11> C = Ja * P.topLeftCorner<15, 15>() * Ja.transpose() +
                                            Jb * b.cov.topLeftCorner<15, 15>() * Jb.transpose();
    const double d2 = e.dot(C.ldlt().solve(e));
    ++pairs;
    if (d2 < 31.26) ++agree;
    if (d2 > worst_d2) {
      worst_d2 = d2;
      std::ostringstream os;
      os << "start " << i << " s -> " << i + 1 << " s: chi2 " << d2 << ", v_b " << va.transpose()
         << " vs " << vb.transpose() << ", b_g " << x.b_g.transpose() << " vs "
         << b.b_g.transpose();
      worst = os.str();
    }
  }
  std::printf("%d pairs, %d agree, %d with a start that declined; worst: %s\n", pairs, agree,
              declined, worst.c_str());
  EXPECT_GE(pairs, 20);
  EXPECT_GE(agree, pairs - pairs / 10) << worst;
  // The noise each start reports. The sensor stands for the first ~12 s: those starts read the
  // IMU's white noise from their rest samples (measured: 12 starts, gyro 0.00180-0.00211 rad/s,
  // each to 2.5 % (1 sigma), against the configured 0.0024; accelerometer 0.0223-0.0246 m/s^2,
  // 0.026-0.030 where the rest is cut short). They agree with their median to 15 % (gyro) and,
  // where the rest filled the window (relative sigma under 3 %), 10 % (accelerometer). Moving
  // starts read it where the motion leaves their samples' high differences to the noise
  // (measured: 6 of 26 for the gyro, 0.00211-0.0024 rad/s): the same sensor, within 25 % of the
  // standing starts' median (each estimate to ~3 %, 1 sigma, and a value within 10 % of the one
  // in use is kept). Every start keeps the configured Doppler noise: the radar's sparse scans
  // (~2 returns per IMU sample) cannot show their shared error, which 0.11 m/s holds.
  std::vector<double> gyro, accel, gyro_moving;
  for (std::size_t i = 0; i < starts.size(); ++i) {
    const NoiseReport& n = starts[i].diag.noise;
    std::printf("start %zu s: %s gyro %.5f (%s, +-%.3f), accel %.4f (%s), Doppler %.4f (%s)\n", i,
                toString(starts[i].state.status), n.gyro.value, toString(n.gyro.source),
                n.gyro.rel_sigma, n.accel.value, toString(n.accel.source), n.doppler.value,
                toString(n.doppler.source));
    EXPECT_EQ(n.doppler.source, NoiseUsed::Source::Declared) << "start " << i;
    if (n.gyro.source == NoiseUsed::Source::DataMoving) gyro_moving.push_back(n.gyro.value);
    if (n.gyro.source != NoiseUsed::Source::DataRest) continue;
    gyro.push_back(n.gyro.value);
    if (n.accel.rel_sigma < 0.03) accel.push_back(n.accel.value);
  }
  ASSERT_GE(gyro.size(), 10u);
  ASSERT_GE(accel.size(), 8u);
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  };
  const double mg = median(gyro), ma = median(accel);
  for (const double g : gyro) EXPECT_NEAR(g / mg, 1.0, 0.15);
  for (const double a : accel) EXPECT_NEAR(a / ma, 1.0, 0.10);
  EXPECT_GE(gyro_moving.size(), 3u);
  for (const double g : gyro_moving) EXPECT_NEAR(g / mg, 1.0, 0.25);
}
