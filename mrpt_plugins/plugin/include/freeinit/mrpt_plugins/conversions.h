// Conversions between MRPT observations and the core's types.
//   CObservationIMU        <-> freeinit::ImuSample   (gyro in rawMeasurements is z, y, x order!)
//   CObservationPointCloud <-> freeinit::LidarFrame  (the cloud is a CPointsMapDoppler)
//   mrpt::Clock            <-> UNIX seconds
//   mrpt::poses::CPose3D   <-> freeinit::Extrinsics
#pragma once

#include <freeinit/types.h>
#include <mrpt/core/Clock.h>
#include <mrpt/obs/CObservationIMU.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/poses/CPose3D.h>

#include <string>

namespace freeinit::mrpt_plugins {

/// [s] UNIX time of an mrpt::Clock time point.
double toUnix(mrpt::Clock::time_point t);
mrpt::Clock::time_point fromUnix(double t);

/// Throws std::invalid_argument if the gyro or accelerometer fields are not all present.
/// `accel_scale` multiplies the accelerations (9.81 when the IMU reports g).
ImuSample imuFromObservation(const mrpt::obs::CObservationIMU& obs, double accel_scale = 1.0);
mrpt::obs::CObservationIMU::Ptr imuToObservation(const ImuSample& s, const std::string& label);

/// Throws std::invalid_argument if the cloud is missing or has no Doppler field (any class other
/// than CPointsMapDoppler). Points are returned sorted by time offset.
LidarFrame frameFromObservation(const mrpt::obs::CObservationPointCloud& obs);
/// The observation's sensorPose is set from the extrinsics (IMU at the robot origin).
mrpt::obs::CObservationPointCloud::Ptr frameToObservation(const LidarFrame& f,
                                                          const Extrinsics& extrinsics,
                                                          const std::string& label);
/// The same from a frame's stamp [UNIX s] and points, without copying them into a LidarFrame.
mrpt::obs::CObservationPointCloud::Ptr frameToObservation(double stamp,
                                                          const std::vector<DopplerPoint>& points,
                                                          const Extrinsics& extrinsics,
                                                          const std::string& label);

Extrinsics extrinsicsFromPose(const mrpt::poses::CPose3D& pose_bl);
mrpt::poses::CPose3D poseFromExtrinsics(const Extrinsics& e);

}  // namespace freeinit::mrpt_plugins
