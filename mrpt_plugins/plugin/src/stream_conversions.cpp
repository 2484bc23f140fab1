#include <freeinit/mrpt_plugins/conversions.h>
#include <freeinit/mrpt_plugins/stream_conversions.h>
#include <mrpt/system/datetime.h>

#include <stdexcept>
#include <string>

namespace freeinit::mrpt_plugins {
namespace {
// mrpt::Clock counts 100 ns ticks from 1601-01-01; this many ticks lie before the UNIX epoch.
constexpr std::int64_t kUnixEpochTicks = 116444736000000000LL;
}  // namespace

std::int64_t toUnixNs(mrpt::Clock::time_point t) {
  if (t == INVALID_TIMESTAMP) throw std::invalid_argument("observation has no timestamp");
  // Range check on ticks first, so that the multiplication below cannot overflow.
  const std::int64_t ticks = static_cast<std::int64_t>(t.time_since_epoch().count());
  constexpr std::int64_t kMaxTicks = (net::kMaxStampNs - 1) / 100 + kUnixEpochTicks;
  if (ticks < kUnixEpochTicks || ticks > kMaxTicks)
    throw std::invalid_argument("timestamp " + std::to_string(ticks) +
                                " (100 ns ticks since 1601) is outside the stream's range "
                                "1970 .. 2116");
  return (ticks - kUnixEpochTicks) * 100;
}

mrpt::Clock::time_point fromUnixNs(std::int64_t ns) {
  // Round to the nearest tick, halves away from zero, without forming ns +/- 50.
  std::int64_t q = ns / 100;
  const std::int64_t r = ns % 100;  // same sign as ns
  if (r >= 50) ++q;
  if (r <= -50) --q;
  // |q| <= 9.3e16 and the epoch offset is 1.2e17: the sum fits easily.
  return mrpt::Clock::time_point(mrpt::Clock::duration(q + kUnixEpochTicks));
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

}  // namespace freeinit::mrpt_plugins
