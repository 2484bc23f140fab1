#include <freeinit/accel_unit.h>
#include <freeinit/input_checks.h>
#include <freeinit/io/number_format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace freeinit::input {
namespace {

/// "duplicated (t after t)" or "goes backwards (t after t_prev)", with the digits it takes for
/// two different stamps to print differently (MRPT's clock counts 100 ns).
std::string orderWords(double t, double previous) {
  std::string a = formatStamp(t), b = formatStamp(previous);
  for (int digits = 7; a == b && t != previous && digits <= 9; ++digits) {
    a = formatFixed(t, digits);
    b = formatFixed(previous, digits);
  }
  return std::string(t == previous ? "duplicated" : "goes backwards") + " (" + a + " after " + b +
         ")";
}

/// Whether the time offsets are all finite and do not decrease: a chain -max <= t_0 <= t_1 <= ...
/// <= t_last <= max of finite floats, which a NaN (no comparison holds) or an infinity breaks.
/// No branch per point (a frame holds up to ~100,000): the offsets of a block of points are
/// gathered, then compared with their predecessors in a loop the compiler vectorizes. Where the
/// chain breaks, the caller's loop finds the first offending point.
bool finiteAndSorted(const std::vector<DopplerPoint>& points) {
  constexpr float kMax = std::numeric_limits<float>::max();
  constexpr std::size_t kBlock = 64;
  float t[kBlock + 1];
  t[0] = -kMax;  // each block's predecessor
  int ordered = 1;
  for (std::size_t b = 0; b < points.size(); b += kBlock) {
    const std::size_t m = std::min(kBlock, points.size() - b);
    for (std::size_t k = 0; k < m; ++k) t[k + 1] = points[b + k].time_offset;
    for (std::size_t k = 0; k < m; ++k) ordered &= t[k + 1] >= t[k] ? 1 : 0;
    t[0] = t[m];
  }
  return ordered != 0 && t[0] <= kMax;
}

}  // namespace

std::string formatStamp(double t) { return formatFixed(t, 6); }

std::optional<std::string> imuSampleProblem(const ImuSample& s, const ImuSample* previous) {
  if (!std::isfinite(s.t)) return std::string("IMU timestamp is not finite");
  if (!s.gyro.allFinite() || !s.accel.allFinite())
    return std::string("IMU sample with NaN or infinite values");
  if (previous != nullptr && !(s.t > previous->t))
    return "IMU timestamp " + orderWords(s.t, previous->t);
  return std::nullopt;
}

bool invalidPoint(const DopplerPoint& p) {
  return !p.p_l.allFinite() || !std::isfinite(p.doppler) || !std::isfinite(p.time_offset);
}

void sortByTime(LidarFrame& f) {
  const auto earlier = [](const DopplerPoint& a, const DopplerPoint& b) {
    return a.time_offset < b.time_offset;
  };
  if (!std::is_sorted(f.points.begin(), f.points.end(), earlier))
    std::stable_sort(f.points.begin(), f.points.end(), earlier);
}

FrameSpan frameSpan(const LidarFrame& f) {
  if (f.points.empty()) return {f.stamp, f.stamp};
  return {f.stamp + f.points.front().time_offset, f.stamp + f.points.back().time_offset};
}

std::optional<std::string> frameOrderProblem(const LidarFrame& f,
                                             const std::optional<double>& previous_stamp,
                                             const std::optional<double>& previous_end) {
  if (!std::isfinite(f.stamp)) return std::string("point cloud timestamp is not finite");
  if (previous_stamp && !(f.stamp > *previous_stamp))
    return "point cloud timestamp " + orderWords(f.stamp, *previous_stamp);
  if (!finiteAndSorted(f.points)) {
    for (std::size_t i = 0; i < f.points.size(); ++i) {
      if (!std::isfinite(f.points[i].time_offset))
        return "point " + std::to_string(i) + " has a non-finite time offset";
      if (i > 0 && f.points[i].time_offset < f.points[i - 1].time_offset)
        return "points are not sorted by time (point " + std::to_string(i) + ")";
    }
  }
  // Points are processed in time order across frames: a frame may not reach back into the
  // previous one.
  if (previous_end && !f.points.empty() && frameSpan(f).begin < *previous_end)
    return "the point cloud overlaps the previous one in time (first point at " +
           formatStamp(frameSpan(f).begin) + ", the previous cloud ends at " +
           formatStamp(*previous_end) + ")";
  return std::nullopt;
}

bool dopplerAllZero(const std::vector<DopplerPoint>& points) {
  return std::none_of(points.begin(), points.end(), [](const DopplerPoint& p) {
    return std::isfinite(p.doppler) && p.doppler != 0.0f;
  });
}

std::optional<std::string> imuRateProblem(const std::vector<ImuSample>& imu, double min_rate) {
  if (imu.size() < 2) return std::nullopt;
  // IMU rate from the median sample interval.
  std::vector<double> dts;
  dts.reserve(imu.size() - 1);
  for (std::size_t i = 1; i < imu.size(); ++i) dts.push_back(imu[i].t - imu[i - 1].t);
  std::nth_element(dts.begin(), dts.begin() + static_cast<std::ptrdiff_t>(dts.size() / 2),
                   dts.end());
  const double rate = 1.0 / dts[dts.size() / 2];
  if (rate >= min_rate) return std::nullopt;
  return "IMU rate " + formatSignificant(rate, 4) +
         " Hz is below [input] min_imu_rate = " + formatSignificant(min_rate, 4) + " Hz";
}

std::optional<std::string> accelUnitProblem(const std::vector<ImuSample>& imu, bool declared_g) {
  if (imu.empty()) return std::nullopt;
  // Units: the specific force averages to about 9.81 m/s^2 (1 g) over any short stretch.
  Vec3 mean = Vec3::Zero();
  const std::size_t n_mean = std::min(imu.size(), kRecordingImuCheckSamples);
  for (std::size_t i = 0; i < n_mean; ++i) mean += imu[i].accel;
  const double g_seen = (mean / static_cast<double>(n_mean)).norm();
  switch (accelUnitMismatch(g_seen, declared_g)) {
    case AccelUnitMismatch::kDataInG:
      return "the mean accelerometer magnitude is " + formatSignificant(g_seen, 4) +
             ", the IMU reports g, not m/s^2: set [input] imu_accel_in_g = true";
    case AccelUnitMismatch::kDataInMs2:
      return "[input] imu_accel_in_g = true but the accelerations are already in m/s^2 (mean "
             "magnitude " +
             formatSignificant(g_seen, 4) + " after conversion)";
    case AccelUnitMismatch::kNone:
      break;
  }
  return std::nullopt;
}

RestParams restParams(const FreeInitConfig& config) {
  RestParams p;
  const ImuParams& imu = config.imu;
  p.max_gyro_dev = config.paper_rest.max_gyro_dev;
  p.max_gyro_bias = p.max_gyro_dev + 3.0 * imu.gyro_bias_sigma0;
  p.gyro_bias_prior = imu.gyro_bias_prior;
  p.max_accel_dev = std::max(0.3, 6.0 * imu.accel_sigma);
  p.max_accel_bias = std::sqrt(3.0) * imu.accel_bias_bound;
  return p;
}

std::optional<std::string> motionProblem(const std::vector<ImuSample>& imu, const RestParams& p) {
  if (imu.size() < 2)
    return "fewer than 2 IMU samples within " + formatSignificant(kRestMargin, 4) +
           " s of its points to tell rest from motion";
  Vec3 w_mean = Vec3::Zero(), f_mean = Vec3::Zero();
  for (const auto& s : imu) {
    w_mean += s.gyro;
    f_mean += s.accel;
  }
  w_mean /= static_cast<double>(imu.size());
  f_mean /= static_cast<double>(imu.size());
  double w_dev = 0, f_dev = 0;
  for (const auto& s : imu) {
    w_dev = std::max(w_dev, (s.gyro - w_mean).norm());
    f_dev = std::max(f_dev, (s.accel - f_mean).norm());
  }
  const double w_bias = (w_mean - p.gyro_bias_prior).norm();
  const double g_dev = std::abs(f_mean.norm() - kGravity);
  if (w_dev > p.max_gyro_dev)
    return "the gyro varies by " + formatSignificant(w_dev, 4) + " rad/s (at rest: below " +
           formatSignificant(p.max_gyro_dev, 4) + ")";
  if (w_bias > p.max_gyro_bias)
    return "the gyro reads " + formatSignificant(w_mean.norm(), 4) +
           " rad/s (at rest: its bias, below " + formatSignificant(p.max_gyro_bias, 4) + ")";
  if (f_dev > p.max_accel_dev)
    return "the specific force varies by " + formatSignificant(f_dev, 4) +
           " m/s^2 (at rest: below " + formatSignificant(p.max_accel_dev, 4) + ")";
  if (g_dev > p.max_accel_bias)
    return "the specific force is " + formatSignificant(f_mean.norm(), 4) +
           " m/s^2 (at rest: 1 g within " + formatSignificant(p.max_accel_bias, 4) + ")";
  return std::nullopt;
}

std::optional<std::string> zeroDopplerProblem(const std::vector<ImuSample>& imu,
                                              const RestParams& p) {
  const auto motion = motionProblem(imu, p);
  if (!motion) return std::nullopt;
  const std::string why = imu.size() < 2
                              ? "the Doppler field is zero for every point and " + *motion
                              : "the Doppler field is zero for every point while the "
                                "IMU shows motion: " +
                                    *motion;
  return why +
         " (an ego-motion-compensated sensor, or a driver that leaves the field at zero? "
         "Free-Init needs the raw range rate; a sensor with Doppler bins reads zero when "
         "moving slowly: declare [input] doppler_resolution)";
}

}  // namespace freeinit::input
