#include <freeinit/accel_unit.h>
#include <freeinit/mrpt/conversions.h>
#include <freeinit/mrpt/input_validator.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

namespace freeinit::mrpt_glue {
namespace {

bool labelMatches(const std::string& wanted, const std::string& label) {
  return wanted.empty() || wanted == label;
}

std::string fmt(double x) {
  std::ostringstream os;
  os.precision(10);
  os << x;
  return os.str();
}

}  // namespace

std::optional<std::string> dopplerProblem(const std::vector<DopplerPoint>& points) {
  const bool any_doppler = std::any_of(points.begin(), points.end(), [](const DopplerPoint& p) {
    return std::isfinite(p.doppler) && p.doppler != 0.0f;
  });
  if (any_doppler) return std::nullopt;
  return std::string(
      "the Doppler field is zero for every point (an ego-motion-compensated sensor? Free-Init "
      "needs the raw range rate)");
}

std::optional<std::string> imuRateProblem(const std::vector<ImuSample>& imu, double min_rate) {
  if (imu.size() < 2) return std::nullopt;
  // IMU rate from the median sample interval.
  std::vector<double> dts;
  for (std::size_t i = 1; i < imu.size(); ++i) dts.push_back(imu[i].t - imu[i - 1].t);
  std::nth_element(dts.begin(), dts.begin() + static_cast<std::ptrdiff_t>(dts.size() / 2),
                   dts.end());
  const double rate = 1.0 / dts[dts.size() / 2];
  if (rate >= min_rate) return std::nullopt;
  return "IMU rate " + fmt(rate) + " Hz is below [input] min_imu_rate = " + fmt(min_rate) + " Hz";
}

std::optional<std::string> accelUnitProblem(const std::vector<ImuSample>& imu, bool declared_g) {
  if (imu.empty()) return std::nullopt;
  // Units: the specific force averages to about 9.81 m/s^2 (1 g) over any short stretch.
  Vec3 mean = Vec3::Zero();
  const std::size_t n_mean = std::min(imu.size(), kImuCheckSamples);
  for (std::size_t i = 0; i < n_mean; ++i) mean += imu[i].accel;
  const double g_seen = (mean / static_cast<double>(n_mean)).norm();
  switch (accelUnitMismatch(g_seen, declared_g)) {
    case AccelUnitMismatch::kDataInG:
      return "the mean accelerometer magnitude is " + fmt(g_seen) +
             ", the IMU reports g, not m/s^2: set [input] imu_accel_in_g = true";
    case AccelUnitMismatch::kDataInMs2:
      return "[input] imu_accel_in_g = true but the accelerations are already in m/s^2 (mean "
             "magnitude " +
             fmt(g_seen) + " after conversion)";
    case AccelUnitMismatch::kNone:
      break;
  }
  return std::nullopt;
}

ValidatedInput validateInput(const std::vector<RawlogRecord>& records, const AppConfig& config,
                             const std::string& file) {
  ValidatedInput in;
  const double accel_scale = config.input.imu_accel_in_g ? kGravity : 1.0;
  auto fail = [&](std::size_t record, const std::string& what) -> InputError {
    return InputError(file + ": record " + std::to_string(record) + ": " + what);
  };
  std::map<std::string, int> ignored;  // "class 'label'" -> count
  std::optional<mrpt::poses::CPose3D> imu_pose;
  std::size_t first_imu_record = 0, first_cloud_record = 0;

  for (const auto& r : records) {
    const auto& obs = *r.obs;
    if (const auto* imu = dynamic_cast<const mrpt::obs::CObservationIMU*>(&obs);
        imu != nullptr && labelMatches(config.input.imu_label, obs.sensorLabel)) {
      ImuSample s;
      try {
        s = imuFromObservation(*imu, accel_scale);
      } catch (const std::exception& e) {
        throw fail(r.index, e.what());
      }
      if (!s.gyro.allFinite() || !s.accel.allFinite())
        throw fail(r.index, "IMU sample with NaN or infinite values");
      if (!in.imu.empty() && s.t <= in.imu.back().t)
        throw fail(r.index, std::string("IMU timestamp ") +
                                (s.t == in.imu.back().t ? "duplicated" : "goes backwards") + " (" +
                                fmt(s.t) + " after " + fmt(in.imu.back().t) + ")");
      if (in.imu.empty()) {
        first_imu_record = r.index;
        imu_pose = imu->sensorPose;
      }
      in.imu.push_back(s);
    } else if (const auto* pc = dynamic_cast<const mrpt::obs::CObservationPointCloud*>(&obs);
               pc != nullptr && labelMatches(config.input.lidar_label, obs.sensorLabel)) {
      LidarFrame f;
      try {
        f = frameFromObservation(*pc);
      } catch (const std::exception& e) {
        throw fail(r.index, e.what());
      }
      if (f.points.empty()) throw fail(r.index, "empty point cloud");
      const auto bad = std::count_if(f.points.begin(), f.points.end(), [](const DopplerPoint& p) {
        return !p.p_l.allFinite() || !std::isfinite(p.doppler) || !std::isfinite(p.time_offset);
      });
      if (bad > 0) {
        if (!config.input.drop_invalid_points)
          throw fail(r.index, std::to_string(bad) + " of " + std::to_string(f.points.size()) +
                                  " points have NaN or infinite coordinates, Doppler or time "
                                  "(set [input] drop_invalid_points = true to drop them)");
        in.invalid_points_dropped += static_cast<std::size_t>(bad);
        f.points.erase(std::remove_if(f.points.begin(), f.points.end(),
                                      [](const DopplerPoint& p) {
                                        return !p.p_l.allFinite() || !std::isfinite(p.doppler) ||
                                               !std::isfinite(p.time_offset);
                                      }),
                       f.points.end());
        if (f.points.empty()) throw fail(r.index, "no valid point left in the cloud");
      }
      if (const auto problem = dopplerProblem(f.points)) throw fail(r.index, *problem);
      if (!in.frames.empty() && f.stamp <= in.frames.back().stamp)
        throw fail(r.index,
                   std::string("point cloud timestamp ") +
                       (f.stamp == in.frames.back().stamp ? "duplicated" : "goes backwards") +
                       " (" + fmt(f.stamp) + " after " + fmt(in.frames.back().stamp) + ")");
      if (in.frames.empty()) {
        first_cloud_record = r.index;
        const mrpt::poses::CPose3D imu_p = imu_pose ? *imu_pose : mrpt::poses::CPose3D();
        in.sensor_pose_extrinsics = extrinsicsFromPose(pc->sensorPose - imu_p);  // imu^-1 (+) lidar
      }
      in.frames.push_back(std::move(f));
    } else {
      ++ignored[std::string(obs.GetRuntimeClass()->className) + " '" + obs.sensorLabel + "'"];
    }
  }
  for (const auto& [what, n] : ignored)
    in.warnings.push_back("ignored " + std::to_string(n) + " observation(s) of " + what);

  auto seen = [&] {
    std::string s;
    for (const auto& [what, n] : ignored) s += (s.empty() ? "" : ", ") + what;
    return s.empty() ? std::string("none") : s;
  };
  if (in.imu.empty())
    throw InputError(file + ": no CObservationIMU with sensorLabel '" + config.input.imu_label +
                     "' ([input] imu_label); other observations: " + seen());
  if (in.frames.empty())
    throw InputError(file + ": no CObservationPointCloud with sensorLabel '" +
                     config.input.lidar_label +
                     "' ([input] lidar_label); other observations: " + seen());
  if (in.imu.size() < 2)
    throw InputError(file + ": record " + std::to_string(first_imu_record) +
                     ": a single IMU sample");

  const std::string at_first_imu = file + ": record " + std::to_string(first_imu_record) + ": ";
  if (const auto problem = imuRateProblem(in.imu, config.input.min_imu_rate))
    throw InputError(at_first_imu + *problem);
  if (const auto problem = accelUnitProblem(in.imu, config.input.imu_accel_in_g))
    throw InputError(at_first_imu + *problem);

  // The window (from the first IMU sample once the LiDAR has started) must be covered.
  const double t_lidar = in.frames.front().stamp;
  const auto first =
      static_cast<std::size_t>(std::find_if(in.imu.begin(), in.imu.end(),
                                            [&](const ImuSample& s) { return s.t >= t_lidar; }) -
                               in.imu.begin());
  const double window = config.core.window.duration;
  if (window > 0 && !windowLastSample(in.imu, first, window)) {
    std::ostringstream os;
    os << file << ": recording shorter than the window: "
       << (first < in.imu.size() ? in.imu.back().t - in.imu[first].t : 0.0)
       << " s of IMU samples after the first point cloud (record " << first_cloud_record
       << "), [window] duration = " << window << " s";
    throw InputError(os.str());
  }
  return in;
}

}  // namespace freeinit::mrpt_glue
