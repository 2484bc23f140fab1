#include <freeinit/app_support/icp_slam_bridge.h>
#include <freeinit/io/config_section.h>
#include <freeinit/mrpt_plugins/conversions.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/poses/CPose3DPDFGaussian.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace freeinit::app_support {
namespace {

double yawOf(const Mat3& R) { return std::atan2(R(1, 0), R(0, 0)); }

}  // namespace

const config::Section<ScanSliceParams>& scanSliceSection() {
  using P = ScanSliceParams;
  using config::between;
  static const auto s =
      config::Section<P>("freeinit_scan",
                         "the horizontal slice each LiDAR frame is reduced to for icp-slam")
          .number("z_min", &P::z_min, "m", between(-100, 100),
                  "slice bottom, above the body (IMU) origin in the levelled frame")
          .number("z_max", &P::z_max, "m", between(-100, 100), "slice top")
          .number("bins", &P::bins, "-", between(3, 100000), "bearing bins over 180 deg")
          .number("max_range", &P::max_range, "m", config::aboveUpTo(0, 1e4),
                  "farther points are dropped")
          .number("min_range", &P::min_range, "m", between(0, 1e3), "closer points are dropped")
          .flag("deskew_with_odometry", &P::deskew_with_odometry,
                "odometry mode: move every point to the frame's mean time through the "
                "Doppler-inertial odometry")
          .check([](const P& p, const config::Checker& c) {
            if (!(p.z_max > p.z_min)) c.fail("z_max", "must be greater than z_min");
            if (!(p.max_range > p.min_range)) c.fail("max_range", "must be greater than min_range");
          });
  return s;
}

ScanSliceParams loadScanSliceParams(const std::string& file) {
  const std::string section = scanSliceSection().name();
  const auto ini = config::IniFile::load(file, {{section}});
  ScanSliceParams p;
  scanSliceSection().load(ini, p);
  return p;
}

const char* toString(IcpSeedMode m) {
  switch (m) {
    case IcpSeedMode::Plain:
      return "plain";
    case IcpSeedMode::Seeded:
      return "seeded";
    case IcpSeedMode::Odometry:
      return "odometry";
  }
  return "?";
}

IcpSeedMode seedModeFromString(const std::string& s) {
  for (auto m : {IcpSeedMode::Plain, IcpSeedMode::Seeded, IcpSeedMode::Odometry})
    if (s == toString(m)) return m;
  throw std::invalid_argument("unknown icp-slam mode '" + s + "' (plain, seeded or odometry)");
}

mrpt::math::TPose2D planarPose(const Quat& q_wb, const Vec3& p_w) {
  return {p_w.x(), p_w.y(), yawOf(q_wb.toRotationMatrix())};
}

Mat3 levellingRotation(const Quat& q_wb) {
  const Mat3 R = q_wb.toRotationMatrix();
  return Eigen::AngleAxisd(-yawOf(R), Vec3::UnitZ()).toRotationMatrix() * R;
}

mrpt::obs::CObservation2DRangeScan::Ptr scanFromFrame(const LidarFrame& frame,
                                                      const Extrinsics& extrinsics,
                                                      const Mat3& R_level,
                                                      const ScanSliceParams& params,
                                                      const std::string& label,
                                                      const std::vector<OdometrySample>* deskew) {
  double t_sum = 0;
  for (const auto& pt : frame.points) t_sum += pt.time_offset;
  const double t_mean =
      frame.stamp + (frame.points.empty() ? 0.0 : t_sum / static_cast<double>(frame.points.size()));
  const bool moving = deskew && !deskew->empty() && !frame.points.empty() &&
                      frame.stamp + frame.points.front().time_offset >= deskew->front().t &&
                      frame.stamp + frame.points.back().time_offset <= deskew->back().t;
  // Deskewing: every point is moved into the body frame at the mean time through the odometry
  // poses at its own time, p_m = R_m^T (R_p p_b + p_p - p_m); the frame is then levelled with its
  // own attitude at the mean time.
  std::optional<BodyPose> mid;
  if (moving) mid = bodyPoseAt(*deskew, t_mean);
  const Mat3 R_lev = mid ? levellingRotation(mid->q_wb) : R_level;
  const Vec3 origin = R_lev * extrinsics.p_bl;  // the LiDAR in the levelled body frame
  const int n = params.bins;
  const double step = M_PI / (n - 1);
  std::vector<float> range(static_cast<std::size_t>(n), std::numeric_limits<float>::infinity());
  for (const auto& pt : frame.points) {
    if (!pt.p_l.allFinite()) continue;
    Vec3 p_b = extrinsics.R_bl * pt.p_l.cast<double>() + extrinsics.p_bl;
    if (mid) {
      const BodyPose at = bodyPoseAt(*deskew, frame.stamp + pt.time_offset);
      p_b = mid->q_wb.conjugate() * (at.q_wb * p_b + at.p_w - mid->p_w);
    }
    const Vec3 p = R_lev * p_b;  // levelled body frame
    if (p.z() < params.z_min || p.z() > params.z_max) continue;
    const double dx = p.x() - origin.x(), dy = p.y() - origin.y();
    const double r = std::hypot(dx, dy);
    if (r < params.min_range || r > params.max_range) continue;
    const double bearing = std::atan2(dy, dx);
    if (std::abs(bearing) > M_PI / 2) continue;
    const auto i = static_cast<std::size_t>(std::lround((bearing + M_PI / 2) / step));
    range[i] = std::min(range[i], static_cast<float>(r));
  }
  auto scan = mrpt::obs::CObservation2DRangeScan::Create();
  scan->sensorLabel = label;
  scan->timestamp = mrpt_plugins::fromUnix(t_mean);
  scan->aperture = static_cast<float>(M_PI);
  scan->rightToLeft = true;
  scan->maxRange = static_cast<float>(params.max_range);
  scan->stdError = 0.02f;
  scan->sensorPose = mrpt::poses::CPose3D(origin.x(), origin.y(), origin.z(), 0, 0, 0);
  scan->resizeScan(static_cast<std::size_t>(n));
  for (std::size_t i = 0; i < range.size(); ++i) {
    const bool valid = std::isfinite(range[i]);
    scan->setScanRange(i, valid ? range[i] : scan->maxRange);
    scan->setScanRangeValidity(i, valid);
  }
  return scan;
}

IcpSeed makeIcpSeed(const InitResult& result, const ScanSliceParams& params) {
  const InitialState& s = result.state;
  if (!s.ok()) throw std::invalid_argument("icp-slam seed: Free-Init did not initialize");
  IcpSeed seed;
  seed.timestamp = s.timestamp;
  auto points = mrpt::maps::CSimplePointsMap::Create();
  const double z0 = s.p_w.z();
  for (const auto& m : result.static_map) {
    const double dz = m.p_w.z() - z0;
    const double r = std::hypot(m.p_w.x() - s.p_w.x(), m.p_w.y() - s.p_w.y());
    if (dz < params.z_min || dz > params.z_max || r > params.max_range) continue;
    points->insertPointFast(m.p_w.x(), m.p_w.y(), m.p_w.z());
  }
  points->mark_as_modified();
  seed.map_points = points->size();
  auto obs = mrpt::obs::CObservationPointCloud::Create();
  obs->sensorLabel = "FREEINIT_STATIC_MAP";
  obs->timestamp = mrpt_plugins::fromUnix(s.timestamp);
  obs->pointcloud = points;  // in w: sensorPose and keyframe pose stay the identity
  auto sf = mrpt::obs::CSensoryFrame::Create();
  sf->insert(obs);
  seed.map_observation = obs;
  seed.map.insert(mrpt::poses::CPose3DPDFGaussian::Create(), sf);

  const Mat3 R_wb = s.q_wb.toRotationMatrix();
  seed.pose.mean = mrpt::poses::CPose2D(planarPose(s.q_wb, s.p_w));
  // (x, y, yaw) = J [dtheta p ...]: yaw error = z of the world-frame rotation error R_wb dtheta.
  Eigen::Matrix<double, 3, 18> J = Eigen::Matrix<double, 3, 18>::Zero();
  J(0, kPos) = 1;
  J(1, kPos + 1) = 1;
  J.block<1, 3>(2, kTheta) = R_wb.row(2);
  const Mat3 C = J * s.cov * J.transpose();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) seed.pose.cov(r, c) = 0.5 * (C(r, c) + C(c, r));
  // Velocity in the SE(2) robot frame: the levelled body frame's x, y; yaw rate about w's z.
  const double yaw = seed.pose.mean.phi();
  const Vec3 v_h = Eigen::AngleAxisd(-yaw, Vec3::UnitZ()) * s.v_w;
  seed.velocity_local = {v_h.x(), v_h.y(), 0.0};
  if (!result.velocities.empty())
    seed.velocity_local.omega = (R_wb * result.velocities.back().omega_b).z();
  return seed;
}

BodyPose bodyPoseAt(const std::vector<OdometrySample>& odometry, double t) {
  if (odometry.empty() || t < odometry.front().t || t > odometry.back().t)
    throw std::out_of_range("odometry: time " + std::to_string(t) + " is not covered");
  auto it = std::lower_bound(odometry.begin(), odometry.end(), t,
                             [](const OdometrySample& o, double x) { return o.t < x; });
  const OdometrySample& b = *it;
  const OdometrySample& a = it == odometry.begin() ? b : *(it - 1);
  BodyPose p;
  p.u = b.t > a.t ? (t - a.t) / (b.t - a.t) : 0.0;
  p.q_wb = a.q_wb.slerp(p.u, b.q_wb);
  p.p_w = (1 - p.u) * a.p_w + p.u * b.p_w;
  p.v_b = (1 - p.u) * a.v_b + p.u * b.v_b;
  p.omega_b = (1 - p.u) * a.omega_b + p.u * b.omega_b;
  return p;
}

mrpt::obs::CObservation::Ptr odometryAt(const std::vector<OdometrySample>& odometry, double t,
                                        const mrpt::math::TPose2D& frame_origin) {
  const BodyPose b = bodyPoseAt(odometry, t);
  const auto pose = planarPose(b.q_wb, b.p_w);
  const Vec3 v_w = b.q_wb * b.v_b;
  const Vec3 w_w = b.q_wb * b.omega_b;
  const Vec3 v_h = Eigen::AngleAxisd(-pose.phi, Vec3::UnitZ()) * v_w;

  auto obs = mrpt::obs::CObservationOdometry::Create();
  obs->sensorLabel = "FREEINIT_ODOMETRY";
  obs->timestamp = mrpt_plugins::fromUnix(t);
  obs->odometry = mrpt::poses::CPose2D(pose) - mrpt::poses::CPose2D(frame_origin);
  obs->hasVelocities = true;
  obs->velocityLocal = {v_h.x(), v_h.y(), w_w.z()};
  return obs;
}

PathErrors comparePathWithTruth(const std::vector<PlanarPathSample>& path,
                                const std::vector<TruthSample>& truth, double t_from, double t_to) {
  std::vector<Eigen::Vector2d> est, ref;
  for (const auto& s : path) {
    if (s.t < t_from || s.t > t_to) continue;
    const auto gt = truthAt(truth, s.t);
    if (!gt) continue;
    est.emplace_back(s.pose.x, s.pose.y);
    ref.emplace_back(gt->p_w.x(), gt->p_w.y());
  }
  if (est.size() < 2)
    throw std::runtime_error("trajectory comparison: fewer than 2 poses covered by the truth");
  // Best SE(2) alignment ref ~ R est + t (closed form: centroids, then the angle of the
  // cross-covariance).
  Eigen::Vector2d ce = Eigen::Vector2d::Zero(), cr = Eigen::Vector2d::Zero();
  for (std::size_t i = 0; i < est.size(); ++i) {
    ce += est[i];
    cr += ref[i];
  }
  ce /= static_cast<double>(est.size());
  cr /= static_cast<double>(est.size());
  double sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < est.size(); ++i) {
    const Eigen::Vector2d a = est[i] - ce, b = ref[i] - cr;
    sxx += a.dot(b);
    sxy += a.x() * b.y() - a.y() * b.x();
  }
  const double th = std::atan2(sxy, sxx);
  const Eigen::Rotation2Dd R(th);
  const Eigen::Vector2d tr = cr - R * ce;
  PathErrors e;
  e.samples = est.size();
  e.alignment = {tr.x(), tr.y(), th};
  double sum2 = 0;
  for (std::size_t i = 0; i < est.size(); ++i) {
    const double d = (R * est[i] + tr - ref[i]).norm();
    sum2 += d * d;
    if (i > 0) e.length += (ref[i] - ref[i - 1]).norm();
  }
  e.ate_rmse = std::sqrt(sum2 / static_cast<double>(est.size()));
  e.end_point = (R * est.back() + tr - ref.back()).norm();
  return e;
}

}  // namespace freeinit::app_support
