// Hand-over from Free-Init to MRPT's icp-slam (CMetricMapBuilderICP, MRPT 2.5.8).
//
// Frames. icp-slam's map frame is planar: a robot pose is (x, y, yaw), an observation is placed
// at CPose3D(x, y, 0, yaw, 0, 0) + its sensorPose. We take Free-Init's world w (gravity-aligned,
// origin and yaw of the body at the window start) as the map frame and the body (IMU) as the
// robot: the SE(2) pose is (p_w.x, p_w.y, yaw of R_wb). The body's roll and pitch, which SE(2)
// cannot hold, go into the scans instead: each LiDAR frame is levelled with R_level = Rz(-yaw) R_wb
// before its horizontal slice is taken, R_wb of the initial state (ground-vehicle roll/pitch
// changes little after it) or, with odometry, of the frame's own time. The static map is already
// in w; its slice is taken by the same height band.
//
// Why 2-D scans: icp-slam's ICP is planar, and MRPT 2.5.8's CPointsMap inserts a
// CObservationPointCloud at its sensorPose only, ignoring the robot pose (fixed upstream in
// 2.11.3): point clouds would all land at the map origin. Stock CObservation2DRangeScan are
// inserted correctly and are what icp-slam is made for.
#pragma once

#include <freeinit/app_support/ground_truth.h>
#include <freeinit/doppler_inertial_odometry.h>
#include <freeinit/initial_state.h>
#include <mrpt/maps/CSimpleMap.h>
#include <mrpt/math/TPose2D.h>
#include <mrpt/math/TTwist2D.h>
#include <mrpt/obs/CObservation.h>
#include <mrpt/obs/CObservation2DRangeScan.h>
#include <mrpt/poses/CPosePDFGaussian.h>

#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace freeinit::config {
template <class S>
class Section;
}  // namespace freeinit::config

namespace freeinit::app_support {

/// The horizontal slice a LiDAR frame is reduced to. INI section [freeinit_scan].
struct ScanSliceParams {
  double z_min = -0.3;      ///< [m] slice bottom above the body origin, levelled frame
  double z_max = 1.5;       ///< [m] slice top
  int bins = 361;           ///< bearing bins over 180 deg
  double max_range = 80.0;  ///< [m]
  double min_range = 1.0;   ///< [m]
  /// Odometry mode: deskew every frame with the Doppler-inertial odometry before slicing it.
  bool deskew_with_odometry = true;
};
/// The [freeinit_scan] section of an icp-slam INI file (whose other sections, MRPT's, are not
/// read here). Missing keys keep their defaults; unknown and duplicated keys and bad values
/// throw config::ConfigError naming the file, the line and the key.
ScanSliceParams loadScanSliceParams(const std::string& file);
const config::Section<ScanSliceParams>& scanSliceSection();

/// The three ways icp-slam starts.
enum class IcpSeedMode {
  Plain,     ///< stock: empty map, origin, standing still, every frame from the first one
  Seeded,    ///< Free-Init's static map, pose and velocity at the state time, frames after it
  Odometry,  ///< Seeded, plus Doppler-inertial odometry before every scan (motion prior)
};
const char* toString(IcpSeedMode m);
/// "plain", "seeded" or "odometry"; throws std::invalid_argument otherwise.
IcpSeedMode seedModeFromString(const std::string& s);

/// SE(2) pose of a body pose (x, y, yaw of R_wb).
mrpt::math::TPose2D planarPose(const Quat& q_wb, const Vec3& p_w);
/// Rz(-yaw) R_wb: the roll/pitch part of R_wb.
Mat3 levellingRotation(const Quat& q_wb);

/// The body pose, velocity and rate at time t, interpolated between odometry samples (slerp,
/// linear). Throws std::out_of_range outside them.
struct BodyPose {
  Quat q_wb = Quat::Identity();
  Vec3 p_w = Vec3::Zero();
  Vec3 v_b = Vec3::Zero();
  Vec3 omega_b = Vec3::Zero();
  double u = 0;  ///< interpolation weight of the later sample
};
BodyPose bodyPoseAt(const std::vector<OdometrySample>& odometry, double t);

/// One LiDAR frame as a stock 2-D scan in the levelled body frame (R_level), stamped at the mean
/// time of its points. Without `deskew` the frame is not deskewed (the mean time halves the smear
/// of a moving platform: +-1 m at 20 m/s and 10 Hz). With `deskew` covering the frame, every point
/// is moved to the body frame at the mean time through the odometry, and the frame is levelled
/// with its own attitude at that time.
mrpt::obs::CObservation2DRangeScan::Ptr scanFromFrame(
    const LidarFrame& frame, const Extrinsics& extrinsics, const Mat3& R_level,
    const ScanSliceParams& params, const std::string& label,
    const std::vector<OdometrySample>* deskew = nullptr);

/// The seed: Free-Init's static map as a one-keyframe CSimpleMap (stock classes: a
/// CObservationPointCloud of a CSimplePointsMap at the identity, points in w within the slice's
/// height band around the body), and the SE(2) pose prior: mean from the state, covariance the
/// (x, y, yaw) marginal of the state's covariance (yaw = rotation about w's z: the right
/// perturbation dtheta is rotated into w, R_wb dtheta).
struct IcpSeed {
  mrpt::maps::CSimpleMap map;
  mrpt::obs::CObservation::Ptr map_observation;  ///< the map's one observation
  std::size_t map_points = 0;                    ///< static-map points in the slice
  mrpt::poses::CPosePDFGaussian pose;
  mrpt::math::TTwist2D velocity_local;  ///< [m/s, rad/s] in the robot's SE(2) frame
  double timestamp = 0;                 ///< [s] UNIX, the state time
};
IcpSeed makeIcpSeed(const InitResult& result, const ScanSliceParams& params);

/// Odometry at time t (interpolated between the samples; throws std::out_of_range outside them)
/// as a stock CObservationOdometry: pose (x, y, yaw) in the frame `frame_origin` (odometry =
/// frame_origin^-1 (+) pose; the identity keeps w) and the local velocities (hasVelocities =
/// true), which icp-slam uses to extrapolate to each scan's time.
mrpt::obs::CObservation::Ptr odometryAt(const std::vector<OdometrySample>& odometry, double t,
                                        const mrpt::math::TPose2D& frame_origin);

/// A timestamped SE(2) path and its errors against the ground truth.
struct PlanarPathSample {
  double t = 0;  ///< [s] UNIX
  mrpt::math::TPose2D pose;
};
struct PathErrors {
  std::size_t samples = 0;
  double ate_rmse = 0;   ///< [m] position RMSE after the best SE(2) alignment (Horn, 2-D)
  double end_point = 0;  ///< [m] position error at the last sample after the same alignment
  double length = 0;     ///< [m] true path length over the compared span
  mrpt::math::TPose2D alignment;  ///< truth frame <- estimate frame
};
/// Compares the samples with t_from <= t <= t_to against the truth (body position, linearly
/// interpolated). Throws std::runtime_error if fewer than 2 samples are covered by the truth.
PathErrors comparePathWithTruth(const std::vector<PlanarPathSample>& path,
                                const std::vector<TruthSample>& truth, double t_from,
                                double t_to = std::numeric_limits<double>::infinity());

}  // namespace freeinit::app_support
