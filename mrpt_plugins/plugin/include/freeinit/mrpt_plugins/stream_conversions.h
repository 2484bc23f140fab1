// Between the live stream's messages (freeinit::net, MRPT-free) and the MRPT observations the
// offline path reads: CObservationIMU and CObservationPointCloud holding a CPointsMapDoppler.
// Timestamps cross exactly: integer nanoseconds <-> mrpt::Clock's 100 ns ticks.
#pragma once

#include <freeinit/net/stream_receiver.h>
#include <freeinit/net/wire_format.h>
#include <mrpt/core/Clock.h>
#include <mrpt/obs/CObservation.h>
#include <mrpt/obs/CObservationIMU.h>
#include <mrpt/obs/CObservationPointCloud.h>

#include <string>

namespace freeinit::mrpt_plugins {

/// [ns] since the UNIX epoch, exact (a Clock tick is 100 ns). Throws std::invalid_argument for
/// INVALID_TIMESTAMP and for times the wire cannot carry (outside [0, net::kMaxStampNs)).
std::int64_t toUnixNs(mrpt::Clock::time_point t);
/// Rounds to the nearest 100 ns tick (halves away from zero); defined for every int64.
mrpt::Clock::time_point fromUnixNs(std::int64_t ns);

/// sensorLabel of the observations built from a stream.
struct StreamLabels {
  std::string imu = "IMU";
  std::string lidar = "LIDAR";
};

/// Throws std::invalid_argument as imuFromObservation / frameFromObservation do.
net::ImuMessage imuMessage(const mrpt::obs::CObservationIMU& obs);
net::FrameMessage frameMessage(const mrpt::obs::CObservationPointCloud& obs,
                               const Extrinsics& extrinsics);

/// The observation for an Imu or Frame event (nullptr for the other kinds). The point cloud's
/// sensorPose carries the frame's extrinsics (the IMU at the robot origin), as freeinit-sim writes.
mrpt::obs::CObservation::Ptr toObservation(const net::StreamEvent& e, const StreamLabels& labels);

}  // namespace freeinit::mrpt_plugins
