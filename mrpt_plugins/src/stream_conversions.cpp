#include <freeinit/mrpt/conversions.h>
#include <freeinit/mrpt/stream_conversions.h>

namespace freeinit::mrpt_glue {
namespace {
// mrpt::Clock counts 100 ns ticks from 1601-01-01; this many ticks lie before the UNIX epoch.
constexpr std::int64_t kUnixEpochTicks = 116444736000000000LL;
}  // namespace

std::int64_t toUnixNs(mrpt::Clock::time_point t) {
  return (static_cast<std::int64_t>(t.time_since_epoch().count()) - kUnixEpochTicks) * 100;
}

mrpt::Clock::time_point fromUnixNs(std::int64_t ns) {
  const std::int64_t ticks = (ns >= 0 ? ns + 50 : ns - 50) / 100 + kUnixEpochTicks;
  return mrpt::Clock::time_point(mrpt::Clock::duration(ticks));
}

net::ImuMessage imuMessage(const mrpt::obs::CObservationIMU& obs) {
  const ImuSample s = imuFromObservation(obs);
  net::ImuMessage m;
  m.stamp_ns = toUnixNs(obs.timestamp);
  m.gyro = s.gyro;
  m.accel = s.accel;
  return m;
}

net::FrameMessage frameMessage(const mrpt::obs::CObservationPointCloud& obs,
                               const Extrinsics& extrinsics) {
  LidarFrame f = frameFromObservation(obs);
  net::FrameMessage m;
  m.stamp_ns = toUnixNs(obs.timestamp);
  m.extrinsics = extrinsics;
  m.points = std::move(f.points);
  return m;
}

mrpt::obs::CObservation::Ptr toObservation(const net::StreamEvent& e, const StreamLabels& labels) {
  using Kind = net::StreamEvent::Kind;
  if (e.kind == Kind::Imu) {
    ImuSample s;
    s.gyro = e.imu.gyro;
    s.accel = e.imu.accel;
    auto obs = imuToObservation(s, labels.imu);
    obs->timestamp = fromUnixNs(e.imu.stamp_ns);
    return obs;
  }
  if (e.kind == Kind::Frame) {
    auto obs = frameToObservation(0.0, e.frame.points, e.frame.extrinsics, labels.lidar);
    obs->timestamp = fromUnixNs(e.frame.stamp_ns);
    return obs;
  }
  return nullptr;
}

}  // namespace freeinit::mrpt_glue
