#include <freeinit/input_checks.h>
#include <freeinit/mrpt_plugins/conversions.h>
#include <freeinit/mrpt_plugins/points_map_doppler.h>
#include <mrpt/math/CMatrixFixed.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <numeric>
#include <stdexcept>

namespace freeinit::mrpt_plugins {

using mrpt::obs::CObservationIMU;
using mrpt::obs::CObservationPointCloud;

double toUnix(mrpt::Clock::time_point t) { return mrpt::Clock::toDouble(t); }
mrpt::Clock::time_point fromUnix(double t) { return mrpt::Clock::fromDouble(t); }

ImuSample imuFromObservation(const CObservationIMU& obs, double accel_scale) {
  using namespace mrpt::obs;  // TIMUDataIndex enumerators
  // MRPT deserializes the presence flags as raw bytes into bools: a corrupt file can hold any
  // byte there, and loading such a bool is undefined. Read the bytes themselves.
  std::uint8_t present[COUNT_IMU_DATA_FIELDS];
  static_assert(sizeof(obs.dataIsPresent) == sizeof(present));
  std::memcpy(present, obs.dataIsPresent.data(), sizeof(present));
  for (std::size_t i = 0; i < sizeof(present); ++i)
    if (present[i] > 1)
      throw std::invalid_argument("CObservationIMU '" + obs.sensorLabel +
                                  "': corrupt data (a field's presence flag is byte " +
                                  std::to_string(present[i]) + ", not 0 or 1)");
  for (auto idx : {IMU_WX, IMU_WY, IMU_WZ, IMU_X_ACC, IMU_Y_ACC, IMU_Z_ACC}) {
    if (present[idx] == 0)
      throw std::invalid_argument("CObservationIMU '" + obs.sensorLabel +
                                  "' lacks angular velocity or acceleration fields");
  }
  ImuSample s;
  s.t = toUnix(obs.timestamp);
  // MRPT 2.5.8 stores the angular rates as yaw (z), pitch (y), roll (x) rates: indices 3, 4, 5.
  const auto& m = obs.rawMeasurements;
  s.gyro = Vec3(m[IMU_WX], m[IMU_WY], m[IMU_WZ]);
  s.accel = accel_scale * Vec3(m[IMU_X_ACC], m[IMU_Y_ACC], m[IMU_Z_ACC]);
  return s;
}

CObservationIMU::Ptr imuToObservation(const ImuSample& s, const std::string& label) {
  using namespace mrpt::obs;
  auto obs = CObservationIMU::Create();
  obs->timestamp = fromUnix(s.t);
  obs->sensorLabel = label;
  obs->set(IMU_WX, s.gyro.x());
  obs->set(IMU_WY, s.gyro.y());
  obs->set(IMU_WZ, s.gyro.z());
  obs->set(IMU_X_ACC, s.accel.x());
  obs->set(IMU_Y_ACC, s.accel.y());
  obs->set(IMU_Z_ACC, s.accel.z());
  return obs;
}

LidarFrame frameFromObservation(const CObservationPointCloud& obs) {
  if (!obs.pointcloud)
    throw std::invalid_argument(
        "CObservationPointCloud '" + obs.sensorLabel +
        "' has no point cloud (externally stored clouds are not supported)");
  const auto* map = dynamic_cast<const CPointsMapDoppler*>(obs.pointcloud.get());
  if (map == nullptr)
    throw std::invalid_argument("CObservationPointCloud '" + obs.sensorLabel + "' holds a " +
                                obs.pointcloud->GetRuntimeClass()->className +
                                ", which has no per-point Doppler: expected a "
                                "freeinit::mrpt_plugins::CPointsMapDoppler");
  LidarFrame f;
  f.stamp = toUnix(obs.timestamp);
  const std::size_t n = map->size();
  f.points.resize(n);
  const auto& xs = map->getPointsBufferRef_x();
  const auto& ys = map->getPointsBufferRef_y();
  const auto& zs = map->getPointsBufferRef_z();
  for (std::size_t i = 0; i < n; ++i) {
    DopplerPoint& p = f.points[i];
    p.p_l = Eigen::Vector3f(xs[i], ys[i], zs[i]);
    p.doppler = map->doppler(i);
    p.time_offset = map->timeOffset(i);
    p.intensity = map->intensity(i);
    p.line = map->line(i);
  }
  input::sortByTime(f);
  return f;
}

CObservationPointCloud::Ptr frameToObservation(const LidarFrame& f, const Extrinsics& extrinsics,
                                               const std::string& label) {
  return frameToObservation(f.stamp, f.points, extrinsics, label);
}

CObservationPointCloud::Ptr frameToObservation(double stamp,
                                               const std::vector<DopplerPoint>& points,
                                               const Extrinsics& extrinsics,
                                               const std::string& label) {
  auto map = CPointsMapDoppler::Create();
  map->reserve(points.size());
  for (const auto& p : points)
    map->insertPointDoppler(p.p_l.x(), p.p_l.y(), p.p_l.z(), p.doppler, p.time_offset, p.intensity,
                            p.line);
  auto obs = CObservationPointCloud::Create();
  obs->timestamp = fromUnix(stamp);
  obs->sensorLabel = label;
  obs->sensorPose = poseFromExtrinsics(extrinsics);
  obs->pointcloud = map;
  return obs;
}

Extrinsics extrinsicsFromPose(const mrpt::poses::CPose3D& pose_bl) {
  Extrinsics e;
  const auto R = pose_bl.getRotationMatrix();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) e.R_bl(i, j) = R(i, j);
  e.p_bl = Vec3(pose_bl.x(), pose_bl.y(), pose_bl.z());
  return e;
}

mrpt::poses::CPose3D poseFromExtrinsics(const Extrinsics& e) {
  mrpt::math::CMatrixDouble33 R;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) R(i, j) = e.R_bl(i, j);
  return mrpt::poses::CPose3D::FromRotationAndTranslation(
      R, mrpt::math::TVector3D(e.p_bl.x(), e.p_bl.y(), e.p_bl.z()));
}

}  // namespace freeinit::mrpt_plugins
